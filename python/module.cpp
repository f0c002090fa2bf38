// The Python module `lsmbs` (compiled part, `lsmbs._lsmbs`): cases loaded from JSON and changed
// from Python, simulations, sensitivities, the design problem, optimization, geometry and the
// verification report. Results come back as NumPy arrays that own their memory (copies). Long
// runs release the GIL, report progress to an optional Python callable, and stop at the next
// step on Ctrl-C (KeyboardInterrupt is raised once the run has stopped). Errors become
// lsmbs.Error (with `file` and `json_path`, as the command line names them) and
// lsmbs.NumericalFailure.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>

#include "lsmbs/core/allocator.hpp"
#include "lsmbs/core/error.hpp"
#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/core/json_file.hpp"
#include "lsmbs/core/text.hpp"
#include "lsmbs/core/version.hpp"
#include "lsmbs/fem/element_types.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/optimization_spec.hpp"
#include "lsmbs/io/optimize_run.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/io/output_folder.hpp"
#include "lsmbs/io/sha256.hpp"
#include "lsmbs/io/simulation_run.hpp"
#include "lsmbs/io/static_run.hpp"
#include "lsmbs/io/verify_run.hpp"
#include "lsmbs/mbs/model_builder.hpp"
#include "lsmbs/optimization/optimizer.hpp"
#include "lsmbs/records/json.hpp"
#include "lsmbs/sensitivity/gradient_check.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"

namespace py = pybind11;
using namespace lsmbs;

namespace {

using CasePtr = std::shared_ptr<Case>;

PyObject* g_check_failed = nullptr;  // lsmbs.GradientCheckFailed (a NumericalFailure)

// ------------------------------------------------------------------ NumPy copies (owning)
py::array_t<double> array(const std::vector<double>& v) {
  py::array_t<double> a(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}
py::array_t<double> array(const Vec& v) {
  py::array_t<double> a(static_cast<py::ssize_t>(v.size()));
  std::copy(v.data(), v.data() + v.size(), a.mutable_data());
  return a;
}
py::array_t<double> array(const Mat& m) {
  py::array_t<double> a({static_cast<py::ssize_t>(m.rows()), static_cast<py::ssize_t>(m.cols())});
  auto r = a.mutable_unchecked<2>();
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) r(i, j) = m(i, j);
  return a;
}
py::object json_to_python(const nlohmann::json& j) {
  return py::module_::import("json").attr("loads")(j.dump());
}

// A design point from Python: None (the case's current design), a sequence of numbers, or a dict
// of variable name -> value over the initial design.
std::string exact(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

Vec design_point(const Case& cs, const py::object& design) {
  if (!cs.design) {
    if (!design.is_none()) throw Error(cs.file, "/design", "the case has no design variables");
    return Vec();
  }
  const Design& d = *cs.design;
  Vec p = d.initial();
  if (design.is_none()) return p;
  if (py::isinstance<py::dict>(design)) {
    for (const auto& [k, v] : design.cast<py::dict>()) {
      if (!py::isinstance<py::str>(k))
        throw py::type_error("design: expected variable names (str) as keys, got " +
                             std::string(py::str(py::type::of(k))));
      const std::string name = py::cast<std::string>(k);
      const int i = d.variable_index(name);
      if (i < 0) throw py::key_error("unknown design variable '" + name + "'");
      if (!py::isinstance<py::float_>(v) && !py::isinstance<py::int_>(v) &&
          !py::isinstance(v, py::module_::import("numpy").attr("number")))
        throw py::type_error("design['" + name + "']: expected a number, got " +
                             std::string(py::str(py::type::of(v))));
      p[i] = py::cast<double>(v);
    }
  } else {
    if (py::isinstance<py::str>(design) || py::isinstance<py::bytes>(design))
      throw py::type_error("design: expected None, a sequence of numbers or {name: value}");
    const py::array_t<double, py::array::c_style | py::array::forcecast> arr = [&] {
      try {
        return py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(design);
      } catch (const py::error_already_set&) {
        return py::array_t<double, py::array::c_style | py::array::forcecast>();
      }
    }();
    if (!arr || arr.ndim() != 1)
      throw py::type_error("design: expected None, a sequence of numbers or {name: value}, got " +
                           std::string(py::str(py::type::of(design))));
    const std::vector<double> v(arr.data(), arr.data() + arr.size());
    if (static_cast<int>(v.size()) != d.size())
      throw py::value_error("design: expected " + std::to_string(d.size()) + " values, got " +
                            std::to_string(v.size()));
    for (int i = 0; i < d.size(); ++i) p[i] = v[static_cast<size_t>(i)];
  }
  for (int i = 0; i < d.size(); ++i) {
    const auto& var = d.variables[static_cast<size_t>(i)];
    p[i] = d.snap_to_bounds(i, p[i]);  // a value within round-off of a bound is that bound
    if (!(p[i] >= var.lower && p[i] <= var.upper))
      throw py::value_error("design variable '" + var.name + "' = " + exact(p[i]) +
                            " is outside its bounds [" + exact(var.lower) + ", " +
                            exact(var.upper) + "]");
  }
  return p;
}

// The design point of a run, with the case as Python left it checked as the command line's loader
// checks a case file (prepare_case): simulation options and model parameters set from Python meet
// the messages that the same values in the case file meet (an invalid option, for instance,
// lsmbs.Error at /simulation/<field>), before anything runs or is written.
// Two Python threads sharing one case take turns (Study::evaluation_mutex): a run reads the model
// parameters the case holds, and the module releases the GIL while it runs. The turn is waited
// for without the GIL (the run that holds it calls back into Python for its progress) and held
// from writing the design into the parameters to the end of the run.
class CaseTurn {
 public:
  explicit CaseTurn(const Case& cs) : lock_(cs.evaluation_mutex(), std::defer_lock) {
    py::gil_scoped_release nogil;
    lock_.lock();
  }

 private:
  std::unique_lock<std::recursive_mutex> lock_;
};

Vec prepared(Case& cs, const py::object& design) {
  const Vec p = design_point(cs, design);
  prepare_case(cs, cs.design ? &p : nullptr);
  return p;
}

// ------------------------------------------------------------------ long runs
// Releases the GIL for the run; the library's progress reports (every step) call back into
// Python at most every 50 ms: the user's callable (if any) and Python's signal check. A pending
// KeyboardInterrupt (or an exception of the callable) asks the run to stop at its next step
// (core/interrupt.hpp) and is raised when the run has returned.
class PythonRun {
 public:
  explicit PythonRun(py::object callback) : callback_(std::move(callback)) {
    interrupt_signal().store(0);
  }
  ProgressCallback progress() {
    return [this](const Progress& p) { report(p); };
  }
  void report(const Progress& p) {
    const auto now = std::chrono::steady_clock::now();
    if (called_ && now - last_ < std::chrono::milliseconds(50)) return;
    called_ = true;
    last_ = now;
    py::gil_scoped_acquire gil;
    if (error_) return;
    if (PyErr_CheckSignals() != 0) return stop();
    if (callback_.is_none()) return;
    try {
      callback_(py::dict(py::arg("label") = p.label, py::arg("t") = p.t, py::arg("t_end") = p.t_end,
                         py::arg("step") = p.step,
                         py::arg("newton_iterations") = p.newton_iterations));
    } catch (py::error_already_set& e) {
      e.restore();
      stop();
    }
  }
  /// Runs f without the GIL; raises what Python asked for during the run.
  template <class F>
  auto operator()(F&& f) {
    struct Reset {
      ~Reset() { interrupt_signal().store(0); }
    } reset;
    auto result = [&] {
      py::gil_scoped_release nogil;
      return f();
    }();
    if (error_) {
      error_->restore();
      throw py::error_already_set();
    }
    return result;
  }

 private:
  void stop() {  // the Python error is set: keep it, and stop the run at its next step
    error_.emplace();
    interrupt_signal().store(SIGINT);
  }
  py::object callback_;
  std::optional<py::error_already_set> error_;
  bool called_ = false;
  std::chrono::steady_clock::time_point last_{};
};

// An output folder given from Python is checked and claimed as the command line's -o: a folder
// that holds an earlier run is refused unless overwrite=True (resume: optimize continues it), and
// only the files an earlier run's summary.json lists are ever replaced (io/output_folder.hpp). f
// runs with the folder claimed (for `model`; null: f claims it itself through the OutputClaim it
// gets, once its case has loaded); an earlier run that overwrite=True replaces comes back when f
// stops on bad input (Error), as on the command line.
struct OutputClaim {
  std::string out;
  bool overwrite, resume;
  ReplacedRun replaced;
  void claim(const Model& model) {
    if (out.empty()) return;
    const OutputFolderNames names{"out_dir", "overwrite=True"};
    replaced = claim_output_folder(out, overwrite, resume, planned_outputs(model), names);
    std::error_code ec;
    std::filesystem::create_directories(out, ec);
    if (ec) throw Error("out_dir " + out + ": cannot create it (" + ec.message() + ")");
  }
};
template <class F>
auto claimed(const Model* model, const std::string& out_dir, bool overwrite, bool resume, F&& f) {
  OutputClaim c{out_dir, overwrite, resume, {}};
  if (!out_dir.empty()) check_output_folder(out_dir, {"out_dir", "overwrite=True"});
  try {
    if (model) c.claim(*model);
    return f(c);
  } catch (const Error&) {
    c.replaced.restore();
    throw;
  }
}

GradientCheckOptions check_options_from(double delta, unsigned seed, double warn, double fail) {
  GradientCheckOptions c;
  c.delta = delta;
  c.seed = seed;
  c.warn = warn;
  c.fail = fail;
  if (auto msg = c.validate(); !msg.empty())  // named by the keywords: check_fail, check_warn
    throw py::value_error(rename_fields(msg, {{"delta", "check_delta"},
                                              {"seed", "check_seed"},
                                              {"warn", "check_warn"},
                                              {"fail", "check_fail"}}));
  return c;
}

// Library errors by name (SetupError) located in the case file, as the command line reports them.
template <class F>
auto located(const Case& cs, F&& f) {
  try {
    return f();
  } catch (const SetupError& e) {
    throw locate(cs.file, e);
  }
}

// ------------------------------------------------------------------ views of a case
struct Parameters {
  CasePtr cs;
  int index(const std::string& name) const {
    const int i = cs->model->parameter_index(name);
    if (i < 0) throw py::key_error("unknown model parameter '" + name + "'");
    return i;
  }
};

struct SensitivityRun {
  SensitivityResult result;
  std::vector<std::string> variables;
  nlohmann::json gradient_check;  // null unless check=True
};

struct Problem {
  CasePtr cs;
  std::unique_ptr<DesignProblem> problem;
  /// The run in progress, to which the problem's simulations report (set by evaluate).
  std::shared_ptr<PythonRun*> current = std::make_shared<PythonRun*>(nullptr);
};

py::dict evaluation_dict(const Evaluation& e) {
  return py::dict(py::arg("p") = array(e.p), py::arg("objective") = e.objective,
                  py::arg("constraints") = array(e.constraints), py::arg("upper") = array(e.upper),
                  py::arg("scale") = array(e.scale),
                  py::arg("objective_gradient") = array(e.objective_gradient),
                  py::arg("constraint_gradient") = array(e.constraint_gradient),
                  py::arg("max_violation") = e.max_violation, py::arg("ok") = e.ok,
                  py::arg("message") = e.message);
}

}  // namespace

PYBIND11_MODULE(_lsmbs, m) {
  m.doc() = "lsmbs: level-set structural optimization of flexible multibody system components";
  m.attr("__version__") = kVersion;
  keep_freed_memory();
  m.attr("git_commit") = git_commit();

  // ---------------------------------------------------------------- errors
  static py::exception<Error> error_type(m, "Error", PyExc_ValueError);
  static py::exception<NumericalFailure> failure_type(m, "NumericalFailure", PyExc_RuntimeError);
  g_check_failed =
      PyErr_NewException("lsmbs._lsmbs.GradientCheckFailed", failure_type.ptr(), nullptr);
  m.attr("GradientCheckFailed") = py::handle(g_check_failed);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      py::object exc = py::reinterpret_borrow<py::object>(error_type.ptr())(e.what());
      exc.attr("file") = e.file();
      exc.attr("json_path") = e.json_path();
      std::string reason = e.what();  // without the "file: path: " prefix
      for (const std::string& part : {e.file(), e.json_path()})
        if (!part.empty() && reason.rfind(part + ": ", 0) == 0) reason.erase(0, part.size() + 2);
      exc.attr("reason") = reason;
      PyErr_SetObject(error_type.ptr(), exc.ptr());
    } catch (const NumericalFailure& e) {
      PyErr_SetString(failure_type.ptr(), e.what());
    }
  });

  // ---------------------------------------------------------------- options
  py::class_<GeneralizedAlphaOptions>(m, "SimulationOptions",
                                      "Generalized-α options of a case (its 'simulation' section)")
      .def_readwrite("h", &GeneralizedAlphaOptions::h, "time step [s]")
      .def_readwrite("t_end", &GeneralizedAlphaOptions::t_end, "final time [s]")
      .def_readwrite("rho_inf", &GeneralizedAlphaOptions::rho_inf, "spectral radius at infinity")
      .def_readwrite("tol_r", &GeneralizedAlphaOptions::tol_r)
      .def_readwrite("tol_phi", &GeneralizedAlphaOptions::tol_phi)
      .def_readwrite("tol_q", &GeneralizedAlphaOptions::tol_q)
      .def_readwrite("max_iter", &GeneralizedAlphaOptions::max_iter)
      .def_readwrite("min_iter", &GeneralizedAlphaOptions::min_iter)
      .def_readwrite("max_halvings", &GeneralizedAlphaOptions::max_halvings)
      .def_readwrite("consistent_start", &GeneralizedAlphaOptions::consistent_start)
      .def_readwrite("project_initial", &GeneralizedAlphaOptions::project_initial)
      .def_readwrite("k", &GeneralizedAlphaOptions::k,
                     "constraint scaling of eq. (7); 0: automatic")
      .def_readwrite("zeta", &GeneralizedAlphaOptions::zeta, "penalty of eq. (7); 0: automatic")
      .def_property(
          "newton",
          [](const GeneralizedAlphaOptions& o) {
            return std::string(GeneralizedAlphaOptions::newton_name(o.newton));
          },
          [](GeneralizedAlphaOptions& o, const std::string& n) {
            using N = GeneralizedAlphaOptions::Newton;
            if (n == "full")
              o.newton = N::kFull;
            else if (n == "modified")
              o.newton = N::kModified;
            else if (n == "modified_across_steps")
              o.newton = N::kModifiedAcrossSteps;
            else
              throw py::value_error("newton '" + n +
                                    "': expected full, modified or modified_across_steps");
          })
      .def_property(
          "ordering",
          [](const GeneralizedAlphaOptions& o) {
            return std::string(SparseLU::ordering_name(o.ordering));
          },
          [](GeneralizedAlphaOptions& o, const std::string& n) {
            if (n == "amd")
              o.ordering = SparseLU::Ordering::kAmd;
            else if (n == "nested_dissection")
              o.ordering = SparseLU::Ordering::kNestedDissection;
            else
              throw py::value_error("ordering '" + n + "': expected amd or nested_dissection");
          })
      .def_readwrite("force_floor", &GeneralizedAlphaOptions::force_floor)
      .def("validate", &GeneralizedAlphaOptions::validate,
           "'' when valid, else 'field: what is expected'")
      .def("to_dict", [](const GeneralizedAlphaOptions& o) { return json_to_python(o); })
      .def("__repr__", [](const GeneralizedAlphaOptions& o) {
        return "SimulationOptions(" + nlohmann::json(o).dump() + ")";
      });

  // ---------------------------------------------------------------- parameters
  py::class_<Parameters>(m, "Parameters", "The model's named scalar parameters ('body.E', …)")
      .def("__getitem__",
           [](const Parameters& p, const std::string& name) {
             return p.cs->model->params().scalars[static_cast<size_t>(p.index(name))];
           })
      .def("__setitem__",
           [](Parameters& p, const std::string& name, double value) {
             const int i = p.index(name);
             if (p.cs->design)
               for (const auto& b : p.cs->design->bindings)
                 if (b.parameter == i)
                   throw py::value_error(
                       "model parameter '" + name + "' is set by design variable '" +
                       p.cs->design->variables[static_cast<size_t>(b.variable)].name +
                       "': change the design instead (design=…)");
             // at the parameter's place in the case file, in the loader's words (lsmbs.Error)
             if (auto msg = ModelBuilder::check_parameter_value(name, value); !msg.empty())
               throw Error(p.cs->file, parameter_json_path(*p.cs, i),
                           msg + " (model parameter '" + name + "' = " + exact(value) +
                               ", set from Python)");
             const CaseTurn turn(*p.cs);  // not under a run of another thread
             p.cs->model->params().scalars[static_cast<size_t>(i)] = value;
           })
      .def("__contains__",
           [](const Parameters& p, const std::string& name) {
             return p.cs->model->parameter_index(name) >= 0;
           })
      .def("__len__", [](const Parameters& p) { return p.cs->model->parameter_names().size(); })
      .def("keys", [](const Parameters& p) { return p.cs->model->parameter_names(); })
      .def("__iter__",
           [](const Parameters& p) { return py::iter(py::cast(p.cs->model->parameter_names())); })
      .def("to_dict", [](const Parameters& p) {
        py::dict d;
        const auto& names = p.cs->model->parameter_names();
        for (size_t i = 0; i < names.size(); ++i)
          d[py::str(names[i])] = p.cs->model->params().scalars[i];
        return d;
      });

  // ---------------------------------------------------------------- case
  py::class_<Case, CasePtr>(m, "Case", "A case loaded from JSON (docs/case-format.md)")
      .def_readonly("name", &Case::name)
      .def_readonly("file", &Case::file)
      .def_readonly("sha256", &Case::sha256)
      .def_property(
          "simulation", [](Case& c) -> GeneralizedAlphaOptions& { return c.simulation; },
          [](Case& c, const GeneralizedAlphaOptions& o) {
            const CaseTurn turn(c);  // not under a run of another thread
            c.simulation = o;
          },
          py::return_value_policy::reference_internal)
      .def_property_readonly("parameters", [](const CasePtr& c) { return Parameters{c}; })
      .def_property_readonly("variables",
                             [](const Case& c) {
                               std::vector<std::string> v;
                               if (c.design)
                                 for (const auto& x : c.design->variables) v.push_back(x.name);
                               return v;
                             })
      .def_property_readonly(
          "initial_design",
          [](const Case& c) { return c.design ? array(c.design->initial()) : array(Vec()); })
      .def_property_readonly(
          "lower", [](const Case& c) { return c.design ? array(c.design->lower()) : array(Vec()); })
      .def_property_readonly(
          "upper", [](const Case& c) { return c.design ? array(c.design->upper()) : array(Vec()); })
      .def_property_readonly("responses",
                             [](const Case& c) {
                               std::vector<std::string> v;
                               for (const auto& r : c.responses) v.push_back(r.name);
                               return v;
                             })
      .def_property_readonly("measures", &Case::measure_columns)
      .def_property_readonly("dofs", [](const Case& c) { return c.model->nq(); })
      .def_property_readonly("constraints", [](const Case& c) { return c.model->nc(); })
      .def("__repr__", [](const Case& c) {
        return "<lsmbs.Case '" + c.name + "' from " + c.file + ": " +
               std::to_string(c.model->nq()) + " DOFs, " +
               std::to_string(c.design ? c.design->size() : 0) + " design variables>";
      });

  m.def(
      "load_case",
      [](const py::object& path) {
        return std::make_shared<Case>(
            load_case(py::str(py::module_::import("os").attr("fspath")(path))));
      },
      py::arg("path"), "Loads and validates a case file (raises lsmbs.Error naming the JSON path)");

  m.def(
      "_load_case_text",
      [](const std::string& text, const std::string& label, const std::string& base_dir) {
        nlohmann::json j;
        try {
          j = parse_json_document(text, label);
        } catch (const nlohmann::json::exception& e) {
          throw Error(label, "", std::string("invalid JSON: ") + e.what());
        }
        auto cs = std::make_shared<Case>(load_case_json(j, label, base_dir));
        cs->sha256 = sha256_hex(text);  // as load_case hashes the file's bytes
        return cs;
      },
      py::arg("text"), py::arg("label"), py::arg("base_dir"),
      "A case from the text of a case document (lsmbs.ModelBuilder.build); the hash is the "
      "text's, as if it were a file");

  // ---------------------------------------------------------------- simulate
  py::class_<SimulationResult>(m, "SimulationResult")
      .def_property_readonly("status",
                             [](const SimulationResult& r) { return run_status_name(r.status()); })
      .def("report", &SimulationResult::report)
      .def_property_readonly("times", [](const SimulationResult& r) { return array(r.times); })
      .def_property_readonly("columns", [](const SimulationResult& r) { return r.columns; })
      .def_property_readonly("history",
                             [](const SimulationResult& r) {
                               Mat h(static_cast<Eigen::Index>(r.history.size()),
                                     static_cast<Eigen::Index>(r.columns.size()));
                               for (size_t i = 0; i < r.history.size(); ++i)
                                 for (size_t j = 0; j < r.columns.size(); ++j)
                                   h(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
                                       r.history[i][j];
                               return array(h);
                             })
      .def("column",
           [](const SimulationResult& r, const std::string& name) { return array(r.column(name)); })
      .def_property_readonly(
          "responses",
          [](const SimulationResult& r) {
            py::dict d;  // NaN when the run did not reach t_end; per-step responses as arrays
            for (const auto& [name, v] : r.responses) {
              const auto ps = r.per_step.find(name);
              d[py::str(name)] = ps != r.per_step.end() ? py::object(array(ps->second))
                                                        : py::object(py::float_(v));
            }
            return d;
          },
          "{response: value}: a float, or an array over the window's steps for a per-step "
          "response; NaN when the run did not reach t_end")
      .def_property_readonly("summary",
                             [](const SimulationResult& r) { return json_to_python(r.summary); });

  m.def(
      "simulate",
      [](const CasePtr& cs, const py::object& design, const std::string& out_dir, bool overwrite,
         const py::object& progress) {
        const CaseTurn turn(*cs);
        const Vec p = prepared(*cs, design);  // the design is in the model's parameters now
        return claimed(cs->model.get(), out_dir, overwrite, false, [&](OutputClaim&) {
          RunOptions ro;
          ro.out_dir = out_dir;
          ro.design_point = p;
          PythonRun run(progress);
          ro.progress = run.progress();
          return run([&] { return located(*cs, [&] { return run_simulation(*cs, ro); }); });
        });
      },
      py::arg("case").none(false), py::arg("design") = py::none(), py::arg("out_dir") = "",
      py::arg("overwrite") = false, py::arg("progress") = py::none(),
      "Generalized-α simulation (Algorithm 1); design: None, a sequence, or {name: value}");

  // ---------------------------------------------------------------- static equilibrium
  py::class_<StaticRunResult>(m, "StaticResult")
      .def_property_readonly("status",
                             [](const StaticRunResult& r) { return run_status_name(r.status()); })
      .def("report", &StaticRunResult::report)
      .def_property_readonly("iterations",
                             [](const StaticRunResult& r) { return r.solver.iterations; })
      .def_property_readonly("columns", [](const StaticRunResult& r) { return r.columns; })
      .def_property_readonly("measures",
                             [](const StaticRunResult& r) {
                               py::dict d;
                               for (size_t i = 0; i < r.columns.size(); ++i)
                                 d[py::str(r.columns[i])] = r.measures[i];
                               return d;
                             })
      .def_property_readonly("responses", [](const StaticRunResult& r) { return r.responses; })
      .def_property_readonly("q", [](const StaticRunResult& r) { return array(r.state.q); })
      .def_property_readonly("summary",
                             [](const StaticRunResult& r) { return json_to_python(r.summary); });

  m.def(
      "static",
      [](const CasePtr& cs, const py::object& design, double t, int max_iter,
         const std::string& out_dir, bool overwrite) {
        const CaseTurn turn(*cs);
        const Vec p = prepared(*cs, design);  // the design is in the model's parameters now
        return claimed(cs->model.get(), out_dir, overwrite, false, [&](OutputClaim&) {
          StaticRunOptions o;
          o.out_dir = out_dir;
          o.t = t;
          o.max_iter = max_iter;
          o.design_point = p;
          o.command_line = "lsmbs.static (Python)";
          PythonRun run{py::none()};
          return run([&] { return located(*cs, [&] { return run_static(*cs, o); }); });
        });
      },
      py::arg("case").none(false), py::arg("design") = py::none(), py::arg("t") = 0.0,
      py::arg("max_iter") = 50, py::arg("out_dir") = "", py::arg("overwrite") = false,
      "Static equilibrium at time t (drivers and loads at t; no inertia), as `lsmbs static`");

  // ---------------------------------------------------------------- sensitivity
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
            py::dict
                d;  // scalar responses: a vector over the variables; per-step: steps × variables
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
          "gradient (as `lsmbs sensitivity --check`); else None");

  m.def(
      "sensitivity",
      [](const CasePtr& cs, const std::string& method, const py::object& design, double delta,
         bool relative, const std::string& matrix, int threads, double rtol, double atol,
         bool check, double check_delta, unsigned check_seed, double check_warn, double check_fail,
         const py::object& progress, double adjoint_memory) {
        SensitivityOptions o;
        if (!SensitivityOptions::parse(method, o.method)) {
          std::string all;
          for (const auto& n : SensitivityOptions::names()) all += (all.empty() ? "" : ", ") + n;
          throw py::value_error("method '" + method + "': expected one of " + all);
        }
        if (!SensitivityOptions::parse_matrix(matrix, o.matrix))
          throw py::value_error("matrix '" + matrix + "': expected last, converged or refined");
        o.delta = delta;
        o.relative = relative;
        o.threads = threads;
        o.adjoint_memory_mb = adjoint_memory;
        // the command line's check of --rtol and --atol
        if (const auto msg = idas_tolerance_error(rtol, atol); !msg.empty())
          throw py::value_error(msg.substr(0, 4) + " " + exact(msg[0] == 'r' ? rtol : atol) +
                                msg.substr(4));
        o.idas.rtol = rtol;
        o.idas.atol = atol > 0 ? atol : rtol;
        if (auto msg = o.validate(); !msg.empty())  // before any run; fields named as keywords
          throw py::value_error(msg);
        const GradientCheckOptions co =
            check_options_from(check_delta, check_seed, check_warn, check_fail);
        const CaseTurn turn(*cs);
        const Vec p = prepared(*cs, design);
        PythonRun run(progress);
        o.progress = run.progress();
        SensitivityRun out;
        std::optional<GradientCheckResult> checked;
        out.result = run([&] {
          return located(*cs, [&] {
            auto r = compute_sensitivities(*cs, p, o);
            if (check && r.ok) checked = check_gradients(*cs, p, r.responses, co);
            return r;
          });
        });
        if (checked) out.gradient_check = gradient_check_json(*checked, co);
        for (const auto& v : cs->design->variables) out.variables.push_back(v.name);
        return out;
      },
      py::arg("case").none(false), py::arg("method") = "direct-analytic",
      py::arg("design") = py::none(), py::arg("delta") = 1e-6, py::arg("relative") = true,
      py::arg("matrix") = "converged", py::arg("threads") = 2, py::arg("rtol") = 1e-9,
      py::arg("atol") = 0.0, py::arg("check") = false,
      py::arg("check_delta") = GradientCheckOptions{}.delta, py::arg("check_seed") = 20261122u,
      py::arg("check_warn") = 1e-3, py::arg("check_fail") = 5e-2, py::arg("progress") = py::none(),
      py::arg("adjoint_memory") = 0.0,
      "Responses and their design gradients (§4.3) by one method, as `lsmbs sensitivity` "
      "(method 'adjoint': the discrete adjoint, scalar responses; adjoint_memory: the bound on its "
      "stored trajectory in MB, as --adjoint-memory)");

  // ---------------------------------------------------------------- design problem, optimize
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
               pr.problem = std::make_unique<DesignProblem>(*cs, spec);
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

  m.def(
      "optimize",
      [](const CasePtr& cs, const std::string& out_dir, bool resume, bool overwrite,
         const std::string& optimizer, bool check, double check_delta, unsigned check_seed,
         double check_warn, double check_fail, const py::object& progress) {
        const CaseTurn turn(*cs);
        prepared(*cs, py::none());  // the run starts from the initial design
        const GradientCheckOptions co =
            check_options_from(check_delta, check_seed, check_warn, check_fail);
        // the problem, as `lsmbs optimize` reads it, before the output folder is touched
        OptimizationSpec spec = located(*cs, [&] { return parse_optimization(*cs); });
        set_optimizer(spec, *cs, optimizer, "optimizer='" + optimizer + "'");
        PythonRun run(progress);
        return claimed(cs->model.get(), out_dir, overwrite, resume, [&](OutputClaim&) {
          return located(*cs, [&] {
            spec.sensitivity.progress = run.progress();
            // the job of `lsmbs optimize` (run_optimize): the check at the initial design of a
            // new run, the optimization, its checkpoint, pictures and summary.json
            OptimizeRunOptions o;
            o.out_dir = out_dir;
            o.command = "lsmbs.optimize (Python)";
            o.resume = resume;
            if (check) o.check = co;
            const OptimizeRun job = run([&] { return run_optimize(*cs, spec, o); });
            const nlohmann::json check_record =
                job.checked ? gradient_check_json(*job.checked, co) : nlohmann::json(nullptr);
            if (job.stage == OptimizeRun::Stage::kCheckFailed) {
              py::object exc = py::reinterpret_borrow<py::object>(g_check_failed)(
                  "gradient check at the initial design failed: " + job.check_message + " (above " +
                  exact(co.fail) + "; check=False skips the check)");
              exc.attr("gradient_check") = json_to_python(check_record);
              PyErr_SetObject(g_check_failed, exc.ptr());
              throw py::error_already_set();
            }
            if (job.stage == OptimizeRun::Stage::kInterruptedInCheck)
              throw Error(job.summary["failure"].get<std::string>());
            const OptimizeResult& r = job.result;
            for (const auto& w : job.warnings)  // as `lsmbs optimize` prints them on stderr
              PyErr_WarnEx(PyExc_RuntimeWarning, ("lsmbs.optimize: " + w).c_str(), 1);
            py::list history;
            for (const auto& e : r.history) history.append(evaluation_dict(e));
            return py::dict(
                // the status summary.json records: complete, interrupted or partial
                py::arg("status") = job.summary["status"].get<std::string>(),
                py::arg("report") = r.report(), py::arg("p") = array(r.p),
                py::arg("final") = evaluation_dict(r.final), py::arg("history") = history,
                py::arg("converged") = r.converged, py::arg("nlopt_status") = r.nlopt_status,
                py::arg("stop_reason") = r.stop_reason,
                py::arg("kkt") = r.kkt ? json_to_python(r.kkt->to_json()) : py::object(py::none()),
                py::arg("warnings") = job.warnings, py::arg("evaluations") = r.evaluations,
                py::arg("gradient_check") = json_to_python(check_record),
                py::arg("summary") = json_to_python(job.summary));
          });
        });
      },
      py::arg("case").none(false), py::arg("out_dir") = "", py::arg("resume") = false,
      py::arg("overwrite") = false, py::arg("optimizer") = "", py::arg("check") = true,
      py::arg("check_delta") = GradientCheckOptions{}.delta, py::arg("check_seed") = 20261122u,
      py::arg("check_warn") = 1e-3, py::arg("check_fail") = 5e-2, py::arg("progress") = py::none(),
      "The fully coupled optimization of the case's design (as `lsmbs optimize`): a gradient "
      "check at the initial design of a new run first (check=False skips it; a warning above "
      "check_warn, GradientCheckFailed above check_fail)");

  // ---------------------------------------------------------------- geometry
  m.def(
      "geometry",
      [](const CasePtr& cs, const py::object& design) {
        if (!cs->design) throw Error(cs->file, "/design", "the case has no design section");
        const CaseTurn turn(*cs);
        const Vec p = prepared(*cs, design);  // as `lsmbs geometry` loads the case
        ModelParams params = cs->model->params();
        std::vector<SpMat> dmu;
        cs->design->apply(p, params, &dmu);
        py::dict bodies;
        for (size_t b = 0; b < cs->design->bodies.size(); ++b) {
          const BodyDesign& bd = cs->design->bodies[b];
          const FlexibleBody& body = *bd.body;
          const Mesh2D& mesh = body.mesh;
          Mat nodes(mesh.num_nodes(), 2);
          Vec phi(mesh.num_nodes());
          const auto values = bd.map->level_set().values(p);
          for (int i = 0; i < mesh.num_nodes(); ++i) {
            nodes.row(i) = mesh.nodes[static_cast<size_t>(i)].transpose();
            phi[i] =
                bd.map->level_set().evaluate(mesh.nodes[static_cast<size_t>(i)], values, nullptr);
          }
          // cells: one array of node indices per cell (counter-clockwise); quads: the same as an
          // (elements × 4) array when every cell is a quadrilateral
          py::list cells, types;
          bool all_quads = true;
          for (const Cell& c : mesh.cells) {
            cells.append(py::array_t<int>(c.size(), c.begin()));
            types.append(element_type(c.type).name);
            all_quads = all_quads && c.size() == 4;
          }
          py::object quads = py::none();
          if (all_quads) {
            py::array_t<int> a({static_cast<py::ssize_t>(mesh.num_elements()), py::ssize_t{4}});
            auto q = a.mutable_unchecked<2>();
            for (int e = 0; e < mesh.num_elements(); ++e)
              for (int k = 0; k < 4; ++k) q(e, k) = mesh.cells[static_cast<size_t>(e)][k];
            quads = a;
          }
          Vec grad;
          const double mass = Design::mass_gradient(bd, dmu[b], params, grad);
          bodies[py::str(body.name)] =
              py::dict(py::arg("nodes") = array(nodes), py::arg("cells") = cells,
                       py::arg("cell_types") = types, py::arg("quads") = quads,
                       py::arg("mu") = array(params.fields[static_cast<size_t>(body.field)]),
                       py::arg("phi") = array(phi), py::arg("mass") = mass,
                       py::arg("mass_gradient") = array(grad));
        }
        return bodies;
      },
      py::arg("case").none(false), py::arg("design") = py::none(),
      "Per designed body: mesh nodes and cells (body frame; 'quads' as an array when all are "
      "quadrilaterals), μ_e, the nodal level set φ (material "
      "where φ > 0), the mass and its gradient");

  // ---------------------------------------------------------------- verify
  m.def(
      "verify",
      [](const std::string& path, const std::string& out_dir, bool idas, bool mesh_study,
         bool overwrite, double idas_rtol, double tol_mesh) {
        return claimed(nullptr, out_dir, overwrite, false, [&](OutputClaim& claim) {
          VerifyOptions o;
          o.on_loaded = [&](const Case& cs) { claim.claim(*cs.model); };
          o.out_dir = out_dir;
          o.idas = idas;
          o.mesh_study = mesh_study;
          o.idas_rtol = idas_rtol;
          o.tol_mesh = tol_mesh;
          o.command_line = "lsmbs.verify (Python)";
          PythonRun run{py::none()};
          const VerifyResult r = run([&] { return run_verify(path, o); });
          return json_to_python(r.summary);
        });
      },
      py::arg("path"), py::arg("out_dir"), py::arg("idas") = true, py::arg("mesh_study") = true,
      py::arg("overwrite") = false, py::arg("idas_rtol") = VerifyOptions{}.idas_rtol,
      py::arg("tol_mesh") = VerifyOptions{}.tol_mesh,
      "The verification report of a case file (as `lsmbs verify`); returns its summary");
}
