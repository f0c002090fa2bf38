#pragma once
// What the binding files of the Python module share (python/module.cpp has the module's
// overview): NumPy copies, design points from Python, a case's turns and start checks, long runs
// without the GIL, output folders claimed as the command line claims them.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

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
#include "lsmbs/runs/optimize.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/io/output_folder.hpp"
#include "lsmbs/io/sha256.hpp"
#include "lsmbs/runs/simulate.hpp"
#include "lsmbs/runs/static.hpp"
#include "lsmbs/runs/verify.hpp"
#include "lsmbs/mbs/model_builder.hpp"
#include "lsmbs/optimization/optimizer.hpp"
#include "lsmbs/records/json.hpp"
#include "lsmbs/sensitivity/gradient_check.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"

namespace py = pybind11;

namespace lsmbs_python {

using namespace lsmbs;  // NOLINT: the module's own namespace speaks the library's names

using CasePtr = std::shared_ptr<Case>;

extern PyObject* g_check_failed;  // lsmbs.GradientCheckFailed (a NumericalFailure)

// ------------------------------------------------------------------ NumPy copies (owning)
inline py::array_t<double> array(const std::vector<double>& v) {
  py::array_t<double> a(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}
inline py::array_t<double> array(const Vec& v) {
  py::array_t<double> a(static_cast<py::ssize_t>(v.size()));
  std::copy(v.data(), v.data() + v.size(), a.mutable_data());
  return a;
}
inline py::array_t<double> array(const Mat& m) {
  py::array_t<double> a({static_cast<py::ssize_t>(m.rows()), static_cast<py::ssize_t>(m.cols())});
  auto r = a.mutable_unchecked<2>();
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) r(i, j) = m(i, j);
  return a;
}
inline py::object json_to_python(const nlohmann::json& j) {
  return py::module_::import("json").attr("loads")(j.dump());
}

// A design point from Python: None (the case's current design), a sequence of numbers, or a dict
// of variable name -> value over the initial design.
inline std::string exact(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

inline Vec design_point(const Case& cs, const py::object& design) {
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

inline Vec prepared(Case& cs, const py::object& design) {
  const Vec p = design_point(cs, design);
  prepare_conditions(cs, cs.design ? &p : nullptr);
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

inline GradientCheckOptions check_options_from(double delta, unsigned seed, double warn, double fail) {
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
    throw locate(cs, e);
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
  nlohmann::json summary;         // summary.json's content
};

struct Problem {
  CasePtr cs;
  std::unique_ptr<DesignProblem> problem;
  /// The run in progress, to which the problem's simulations report (set by evaluate).
  std::shared_ptr<PythonRun*> current = std::make_shared<PythonRun*>(nullptr);
};

inline py::dict evaluation_dict(const Evaluation& e) {
  return py::dict(py::arg("p") = array(e.p), py::arg("objective") = e.objective,
                  py::arg("constraints") = array(e.constraints), py::arg("upper") = array(e.upper),
                  py::arg("scale") = array(e.scale),
                  py::arg("objective_gradient") = array(e.objective_gradient),
                  py::arg("constraint_gradient") = array(e.constraint_gradient),
                  py::arg("max_violation") = e.max_violation, py::arg("ok") = e.ok,
                  py::arg("message") = e.message);
}

}  // namespace lsmbs_python
