// lsmbs.sensitivity: the job of `lsmbs sensitivity` (run_sensitivity, runs/sensitivity.hpp) with
// Python's arguments, and its SensitivityResult.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "lsmbs/runs/sensitivity.hpp"
#include "python/support.hpp"

namespace lsmbs_python {
namespace {

SensitivityOptions::Method method_named(const std::string& method, const std::string& what) {
  SensitivityOptions::Method m;
  if (!SensitivityOptions::parse(method, m)) {
    std::string all;
    for (const auto& n : SensitivityOptions::names()) all += (all.empty() ? "" : ", ") + n;
    throw py::value_error(what + " '" + method + "': expected one of " + all);
  }
  return m;
}

// The keywords as the command line's options, checked before anything runs (the fields named as
// the keywords).
struct SensitivityKeywords {
  std::string method;
  std::vector<std::string> compare;
  double delta;
  bool relative;
  std::string matrix;
  int threads;
  double rtol, atol, adjoint_memory;
  SensitivityRunOptions options() const {
    SensitivityRunOptions o;
    SensitivityOptions& so = o.options;
    so.method = method_named(method, "method");
    for (const auto& c : compare) {
      if (c == method || std::count(compare.begin(), compare.end(), c) > 1)
        throw py::value_error("compare: method '" + c + "' is given twice");
      o.compare.push_back(method_named(c, "compare: method"));
    }
    if (!SensitivityOptions::parse_matrix(matrix, so.matrix))
      throw py::value_error("matrix '" + matrix + "': expected last, converged or refined");
    so.delta = delta;
    so.relative = relative;
    so.threads = threads;
    so.adjoint_memory_mb = adjoint_memory;
    if (const auto msg = idas_tolerance_error(rtol, atol); !msg.empty())
      throw py::value_error(msg.substr(0, 4) + " " + exact(msg[0] == 'r' ? rtol : atol) +
                            msg.substr(4));
    so.idas.rtol = rtol;
    so.idas.atol = atol > 0 ? atol : rtol;
    if (auto msg = so.validate(); !msg.empty()) throw py::value_error(msg);
    return o;
  }
};

SensitivityRun sensitivity(const CasePtr& cs, const SensitivityKeywords& k,
                           const py::object& design, const std::string& out_dir, bool overwrite,
                           const std::optional<GradientCheckOptions>& check,
                           const py::object& progress) {
  SensitivityRunOptions o = k.options();
  o.check = check;
  o.out_dir = out_dir;
  o.command = "lsmbs.sensitivity (Python)";
  const CaseTurn turn(*cs);
  const Vec p = prepared(*cs, design);
  if (!cs->design) throw Error(cs->file, "/design", "sensitivities need design variables");
  return claimed(cs->model.get(), out_dir, overwrite, false, [&](OutputClaim&) {
    PythonRun run(progress);
    o.options.progress = run.progress();
    const lsmbs::SensitivityRun job =
        run([&] { return located(*cs, [&] { return run_sensitivity(*cs, p, o); }); });
    SensitivityRun out{job.result, {}, nullptr, job.summary};
    if (job.checked) out.gradient_check = gradient_check_json(*job.checked, *check);
    for (const auto& v : cs->design->variables) out.variables.push_back(v.name);
    return out;
  });
}

void bind_result(py::module_& m) {
  py::class_<SensitivityRun>(m, "SensitivityResult")
      .def_property_readonly(
          "status", [](const SensitivityRun& r) { return run_status_name(r.result.status()); })
      .def("report", [](const SensitivityRun& r) { return r.result.report(); })
      .def_property_readonly("message", [](const SensitivityRun& r) { return r.result.message; })
      .def_property_readonly("warnings", [](const SensitivityRun& r) { return r.result.warnings; })
      .def_property_readonly("variables", [](const SensitivityRun& r) { return r.variables; })
      .def_property_readonly("values",
                             [](const SensitivityRun& r) {
                               py::dict d;
                               for (const auto& x : r.result.responses)
                                 d[py::str(x.name)] = x.times.empty() && x.values.size() == 1
                                                          ? py::object(py::float_(x.values[0]))
                                                          : py::object(array(x.values));
                               return d;
                             })
      .def_property_readonly(
          "gradients",
          [](const SensitivityRun& r) {
            py::dict d;  // scalar responses: a vector over the variables; per-step: steps × vars
            for (const auto& x : r.result.responses)
              d[py::str(x.name)] = x.times.empty() && x.gradient.rows() == 1
                                       ? py::object(array(Vec(x.gradient.row(0).transpose())))
                                       : py::object(array(x.gradient));
            return d;
          })
      .def_property_readonly("times",
                             [](const SensitivityRun& r) {
                               py::dict d;
                               for (const auto& x : r.result.responses)
                                 if (!x.times.empty()) d[py::str(x.name)] = array(x.times);
                               return d;
                             })
      .def_property_readonly(
          "counts", [](const SensitivityRun& r) { return json_to_python(r.result.counts); })
      .def_property_readonly(
          "gradient_check",
          [](const SensitivityRun& r) { return json_to_python(r.gradient_check); },
          "check=True: central differences along a seeded random direction against the "
          "gradient (as `lsmbs sensitivity --check`); else None")
      .def_property_readonly(
          "summary", [](const SensitivityRun& r) { return json_to_python(r.summary); },
          "what summary.json holds (also without out_dir); 'methods' compares the methods of "
          "compare=[...]");
}

}  // namespace

// lsmbs.sensitivity and its SensitivityResult.
void bind_sensitivity(py::module_& m) {
  bind_result(m);
  m.def(
      "sensitivity",
      [](const CasePtr& cs, const std::string& method, const py::object& design, double delta,
         bool relative, const std::string& matrix, int threads, double rtol, double atol,
         bool check, double check_delta, unsigned check_seed, double check_warn, double check_fail,
         const py::object& progress, double adjoint_memory, const std::vector<std::string>& compare,
         const std::filesystem::path& out_dir, bool overwrite) {
        const SensitivityKeywords k{method,  compare, delta, relative,      matrix,
                                    threads, rtol,    atol,  adjoint_memory};
        k.options();  // the keywords are checked before the case is touched
        std::optional<GradientCheckOptions> co;
        if (check) co = check_options_from(check_delta, check_seed, check_warn, check_fail);
        return sensitivity(cs, k, design, out_dir, overwrite, co, progress);
      },
      py::arg("case").none(false), py::arg("method") = "direct-analytic",
      py::arg("design") = py::none(), py::arg("delta") = 1e-6, py::arg("relative") = true,
      py::arg("matrix") = "converged", py::arg("threads") = 2, py::arg("rtol") = 1e-9,
      py::arg("atol") = 0.0, py::arg("check") = false,
      py::arg("check_delta") = GradientCheckOptions{}.delta, py::arg("check_seed") = 20261122u,
      py::arg("check_warn") = 1e-3, py::arg("check_fail") = 5e-2, py::arg("progress") = py::none(),
      py::arg("adjoint_memory") = 0.0, py::arg("compare") = std::vector<std::string>{},
      py::arg("out_dir") = "", py::arg("overwrite") = false,
      "Responses and their design gradients (§4.3) by one method, as `lsmbs sensitivity` "
      "(method 'adjoint': the discrete adjoint, scalar responses; adjoint_memory: the bound on its "
      "stored trajectory in MB, as --adjoint-memory; compare: further methods run and compared "
      "with the first, as --method a,b,…; out_dir: the command line's files, gradients.csv, "
      "methods.csv and summary.json)");
}

}  // namespace lsmbs_python
