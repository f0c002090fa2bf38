// lsmbs.DesignProblem (evaluate(p) with gradients, cached) and lsmbs.optimize: the job of
// `lsmbs optimize` (run_optimize, or run_multistart with starts=N; runs/) with Python's
// arguments.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "lsmbs/runs/multistart.hpp"
#include "python/support.hpp"

namespace lsmbs_python {
namespace {

void bind_problem(py::module_& m) {
  py::class_<Problem>(m, "DesignProblem",
                      "The case's optimization problem (its 'optimization' section); evaluate(p) "
                      "runs one simulation with sensitivities and caches the result by p")
      .def(py::init([](const CasePtr& cs) {
             Problem pr{cs, nullptr};
             located(*cs, [&] {
               OptimizationSpec spec = parse_optimization(*cs);
               spec.sensitivity.progress = [slot = pr.current](const Progress& p) {
                 if (*slot) (*slot)->report(p);
               };
               pr.problem = std::make_unique<DesignProblem>(conditions_of(*cs), spec);
               return 0;
             });
             return pr;
           }),
           py::arg("case").none(false))
      .def_property_readonly("num_variables",
                             [](const Problem& p) { return p.problem->num_variables(); })
      .def_property_readonly("num_constraints",
                             [](const Problem& p) { return p.problem->num_constraints(); })
      .def_property_readonly("simulations",
                             [](const Problem& p) { return p.problem->simulations(); })
      .def_property_readonly("cache_hits", [](const Problem& p) { return p.problem->cache_hits(); })
      .def(
          "evaluate",
          [](Problem& pr, const py::object& design, const py::object& progress) {
            const CaseTurn turn(*pr.cs);
            const Vec p = prepared(*pr.cs, design);
            PythonRun run(progress);
            *pr.current = &run;
            struct Unset {
              PythonRun** slot;
              ~Unset() { *slot = nullptr; }
            } unset{pr.current.get()};
            return evaluation_dict(
                run([&] { return located(*pr.cs, [&] { return pr.problem->evaluate(p); }); }));
          },
          py::arg("design"), py::arg("progress") = py::none(),
          "{'objective', 'constraints', 'upper', 'objective_gradient', 'constraint_gradient', …}");
}

// GradientCheckFailed with the check's record, as `lsmbs optimize` refuses the run.
[[noreturn]] void raise_check_failed(const OptimizeRun& job, const GradientCheckOptions& co) {
  py::object exc = py::reinterpret_borrow<py::object>(g_check_failed)(
      "gradient check at the initial design failed: " + job.check_message + " (above " +
      exact(co.fail) + "; check=False skips the check)");
  exc.attr("gradient_check") =
      json_to_python(job.checked ? gradient_check_json(*job.checked, co) : nlohmann::json());
  PyErr_SetObject(g_check_failed, exc.ptr());
  throw py::error_already_set();
}

py::dict optimize_dict(const OptimizeRun& job, const std::optional<GradientCheckOptions>& co) {
  const OptimizeResult& r = job.result;
  for (const auto& w : job.warnings)  // as `lsmbs optimize` prints them on stderr
    PyErr_WarnEx(PyExc_RuntimeWarning, ("lsmbs.optimize: " + w).c_str(), 1);
  py::list history;
  for (const auto& e : r.history) history.append(evaluation_dict(e));
  const nlohmann::json check =
      job.checked && co ? gradient_check_json(*job.checked, *co) : nlohmann::json(nullptr);
  return py::dict(
      // the status summary.json records: complete, interrupted or partial
      py::arg("status") = job.summary["status"].get<std::string>(), py::arg("report") = r.report(),
      py::arg("p") = array(r.p), py::arg("final") = evaluation_dict(r.final),
      py::arg("history") = history, py::arg("converged") = r.converged,
      py::arg("nlopt_status") = r.nlopt_status, py::arg("stop_reason") = r.stop_reason,
      py::arg("kkt") = r.kkt ? json_to_python(r.kkt->to_json()) : py::object(py::none()),
      py::arg("warnings") = job.warnings, py::arg("evaluations") = r.evaluations,
      py::arg("gradient_check") = json_to_python(check),
      py::arg("summary") = json_to_python(job.summary));
}

// One optimization (run_optimize): the check at the initial design of a new run, the run, its
// files; a dict of the result, GradientCheckFailed for a refused check.
py::dict optimize_one(const CasePtr& cs, const OptimizationSpec& spec, const std::string& out_dir,
                      bool resume, const std::optional<GradientCheckOptions>& co, PythonRun& run) {
  OptimizeRunOptions o;
  o.out_dir = out_dir;
  o.command = "lsmbs.optimize (Python)";
  o.resume = resume;
  o.check = co;
  const OptimizeRun job = run([&] { return run_optimize(*cs, spec, o); });
  if (job.stage == OptimizeRun::Stage::kCheckFailed) raise_check_failed(job, *co);
  if (job.stage == OptimizeRun::Stage::kInterruptedInCheck)
    throw Error(job.summary["failure"].get<std::string>());
  return optimize_dict(job, co);
}

// starts=N (run_multistart): the ranking as summary.json holds it, with each start's row.
py::dict optimize_starts(const CasePtr& cs, const OptimizationSpec& spec, MultistartOptions o,
                         PythonRun& run) {
  o.command = "lsmbs.optimize (Python)";
  const MultistartRun job = run([&] { return run_multistart(*cs, spec, o); });
  if (job.interrupted_in_screening)
    throw Error("interrupted while screening candidate " + std::to_string(job.candidates) +
                " of the multi-start (no start had begun; nothing was written)");
  py::list starts;
  for (const auto& r : job.rows)
    starts.append(py::dict(py::arg("start") = r.start, py::arg("exit_code") = r.exit_code,
                           py::arg("status") = r.status, py::arg("objective") = r.objective,
                           py::arg("max_violation") = r.violation, py::arg("feasible") = r.feasible,
                           py::arg("converged") = r.converged,
                           py::arg("stop_reason") = r.stop_reason,
                           py::arg("initial") = array(r.initial),
                           py::arg("p") = array(r.final_design), py::arg("message") = r.message));
  return py::dict(py::arg("status") = job.summary["status"].get<std::string>(),
                  py::arg("best_start") = job.best, py::arg("order") = job.order,
                  py::arg("starts") = starts, py::arg("summary") = json_to_python(job.summary));
}

}  // namespace

// lsmbs.DesignProblem and lsmbs.optimize.
void bind_optimize(py::module_& m) {
  bind_problem(m);
  m.def(
      "optimize",
      [](const CasePtr& cs, const std::filesystem::path& out_dir, bool resume, bool overwrite,
         const std::string& optimizer, bool check, double check_delta, unsigned check_seed,
         double check_warn, double check_fail, const py::object& progress, int starts,
         unsigned long seed, int jobs) {
        const CaseTurn turn(*cs);
        prepared(*cs, py::none());  // the run starts from the initial design
        std::optional<GradientCheckOptions> co;
        if (check) co = check_options_from(check_delta, check_seed, check_warn, check_fail);
        MultistartOptions ms;
        ms.starts = starts, ms.seed = seed, ms.jobs = jobs, ms.resume = resume;
        ms.overwrite = overwrite, ms.out_dir = out_dir, ms.check = co;
        if (starts > 0)
          if (auto msg = ms.validate(); !msg.empty()) throw py::value_error(msg);
        // the problem, as `lsmbs optimize` reads it, before the output folder is touched
        OptimizationSpec spec = located(*cs, [&] { return parse_optimization(*cs); });
        set_optimizer(spec, *cs, optimizer, "optimizer='" + optimizer + "'");
        PythonRun run(progress);
        return claimed(cs->model.get(), out_dir, overwrite, resume, [&](OutputClaim&) {
          return located(*cs, [&] {
            spec.sensitivity.progress = run.progress();
            return starts > 0 ? optimize_starts(cs, spec, ms, run)
                              : optimize_one(cs, spec, out_dir, resume, co, run);
          });
        });
      },
      py::arg("case").none(false), py::arg("out_dir") = "", py::arg("resume") = false,
      py::arg("overwrite") = false, py::arg("optimizer") = "", py::arg("check") = true,
      py::arg("check_delta") = GradientCheckOptions{}.delta, py::arg("check_seed") = 20261122u,
      py::arg("check_warn") = 1e-3, py::arg("check_fail") = 5e-2, py::arg("progress") = py::none(),
      py::arg("starts") = 0, py::arg("seed") = 1, py::arg("jobs") = 2,
      "The fully coupled optimization of the case's design (as `lsmbs optimize`): a gradient "
      "check at the initial design of a new run first (check=False skips it; a warning above "
      "check_warn, GradientCheckFailed above check_fail). starts=N: a multi-start from N feasible "
      "random designs (seed), `jobs` at a time, in out_dir/start_k (as --starts); returns the "
      "ranking");
}

}  // namespace lsmbs_python
