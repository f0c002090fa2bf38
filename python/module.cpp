// The Python module `lsmbs` (compiled part, `lsmbs._lsmbs`): cases loaded from JSON and changed
// from Python, simulations, sensitivities, the design problem, optimization, geometry and the
// verification report. Results come back as NumPy arrays that own their memory (copies). Long
// runs release the GIL, report progress to an optional Python callable, and stop at the next
// step on Ctrl-C (KeyboardInterrupt is raised once the run has stopped). Errors become
// lsmbs.Error (with `file` and `json_path`, as the command line names them) and
// lsmbs.NumericalFailure.
//
// The workflows are the library's (src/lsmbs/runs/), the same functions the command line calls;
// the files here only turn Python arguments into their options and their results into Python:
//   bind_case.cpp         errors, SimulationOptions, Parameters, Case, load_case, model_kinds
//   bind_runs.cpp         simulate, static, geometry, verify, sweep
//   bind_sensitivity.cpp  sensitivity
//   bind_optimize.cpp     DesignProblem, optimize (multi-start included)
#include <pybind11/pybind11.h>

#include "lsmbs/core/allocator.hpp"
#include "lsmbs/core/version.hpp"
#include "python/support.hpp"

namespace lsmbs_python {

PyObject* g_check_failed = nullptr;

void bind_errors(py::module_& m);
void bind_options(py::module_& m);
void bind_parameters(py::module_& m);
void bind_case(py::module_& m);
void bind_model_kinds(py::module_& m);
void bind_simulate(py::module_& m);
void bind_static(py::module_& m);
void bind_geometry(py::module_& m);
void bind_verify(py::module_& m);
void bind_sweep(py::module_& m);
void bind_sensitivity(py::module_& m);
void bind_optimize(py::module_& m);

}  // namespace lsmbs_python

PYBIND11_MODULE(_lsmbs, m) {
  using namespace lsmbs_python;
  m.doc() = "lsmbs: level-set structural optimization of flexible multibody system components";
  m.attr("__version__") = lsmbs::kVersion;
  lsmbs::keep_freed_memory();
  m.attr("git_commit") = lsmbs::git_commit();
  bind_errors(m);
  bind_options(m);
  bind_parameters(m);
  bind_case(m);
  bind_model_kinds(m);
  bind_simulate(m);
  bind_static(m);
  bind_geometry(m);
  bind_verify(m);
  bind_sweep(m);
  bind_sensitivity(m);
  bind_optimize(m);
}
