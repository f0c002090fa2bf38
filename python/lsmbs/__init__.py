"""lsmbs: level-set structural optimization of flexible multibody system components.

    import lsmbs
    case = lsmbs.ModelBuilder(...) ... .build()   # a model built in Python (lsmbs.builder), or
    case = lsmbs.load_case("data/slider_crank_rigid/slider_crank_spring.json")
    case.simulation.h = 5e-4                      # any option of the case
    r = lsmbs.sensitivity(case, method="direct-analytic")
    r.values, r.gradients                         # dicts of floats / NumPy arrays by response

Long runs release the GIL, take an optional ``progress`` callable (called with a dict: label, t,
t_end, step, newton_iterations) and stop cleanly on Ctrl-C (KeyboardInterrupt once stopped).
Errors: ``lsmbs.Error`` (a ValueError with ``file`` and ``json_path``) for invalid input,
``lsmbs.NumericalFailure`` when a run fails. Plots: ``lsmbs.plot`` (matplotlib).
"""
import sys as _sys


def _interpreter_error(missing):
    """An ImportError that names the interpreter this build is for: the compiled module needs
    NumPy and the Python version it was built with, and the `python3` first on PATH is not
    always that one (a pyenv or conda interpreter before Debian's)."""
    try:
        from ._build_info import PYTHON, VERSION
    except ImportError:  # a source tree without a build
        PYTHON, VERSION = "the Python lsmbs was built with", "?"
    here = f"{_sys.version_info.major}.{_sys.version_info.minor}"
    return ImportError(
        f"lsmbs was built for {PYTHON} (Python {VERSION}, with NumPy); this interpreter is "
        f"{_sys.executable} (Python {here}) and {missing}. Run {PYTHON}, or build lsmbs for this "
        f"interpreter (cmake -DPython_EXECUTABLE={_sys.executable}; it needs NumPy and pybind11).")


try:
    import numpy as _numpy  # noqa: F401  (the compiled module's arrays are NumPy arrays)
except ImportError:
    raise _interpreter_error("it has no NumPy") from None
try:
    from . import _lsmbs  # noqa: F401
except ImportError as _e:
    raise _interpreter_error(f"the compiled module does not load here ({_e})") from None

from ._lsmbs import static  # noqa: F401,E402  (lsmbs.static(case): static equilibrium)
from ._lsmbs import (  # noqa: F401,E402
    Case,
    DesignProblem,
    Error,
    GradientCheckFailed,
    NumericalFailure,
    Parameters,
    SensitivityResult,
    SimulationOptions,
    SimulationResult,
    StaticResult,
    __version__,
    geometry,
    git_commit,
    load_case,
    optimize,
    sensitivity,
    simulate,
    verify,
)



def sweep(case, axes=None, lhs=None, samples=0, seed=1, gradients=False, method="direct-analytic",
          jobs=2, out_dir="", resume=False, overwrite=False, progress=None):
    """The responses (and, with gradients=True, their gradients with respect to the design
    variables) at the points of a grid or a Latin hypercube, as `lsmbs sweep` (docs/python.md);
    a pandas DataFrame, one row per point: `point`, `status`, a column per axis, per response
    (and per gradient, "d(response)/d(variable)"), `wall_seconds`, `message`.

    axes: {name: (lower, upper, points)} for a grid (the last axis fastest), or
    lhs: {name: (lower, upper)} with samples=N for a Latin hypercube (seed). A name is a design
    variable, a model parameter ('spring.stiffness') or a JSON pointer ('/simulation/h')."""
    import pandas
    if (axes is None) == (lhs is None):
        raise TypeError("sweep: give axes={name: (lower, upper, points)} or lhs={name: (lower, upper)}")
    if lhs is not None and samples < 1:
        raise ValueError("sweep: lhs= needs samples=N (the number of points)")
    spec = []
    for name, v in (axes or lhs).items():
        v = tuple(v)
        if axes is not None:
            if len(v) != 3:
                raise TypeError(f"sweep: axes[{name!r}]: expected (lower, upper, points)")
            spec.append((str(name), float(v[0]), float(v[1]), int(v[2])))
        else:
            if len(v) != 2:
                raise TypeError(f"sweep: lhs[{name!r}]: expected (lower, upper)")
            spec.append((str(name), float(v[0]), float(v[1]), 0))
    import os
    out_dir = os.fspath(out_dir)
    r = _lsmbs._sweep(case, spec, samples if lhs is not None else 0, seed, gradients, method, jobs,
                      out_dir, resume, overwrite, progress)
    if out_dir:  # every finished point, this run's and an earlier one's (resume), as written
        frame = pandas.read_csv(os.path.join(out_dir, "sweep.csv"),
                                keep_default_na=False, na_values=["nan"])
        frame["message"] = frame["message"].astype(str)
        frame.attrs["summary"] = r["summary"]
        return frame
    n = len(r["status"])
    data = {"point": list(range(n)), "status": r["status"]}
    for j, (name, *_unused) in enumerate(spec):
        data[name] = [r["points"][k][j] for k in range(n)]
    values = [c for c in r["columns"] if c not in data and c not in ("wall_seconds", "message")]
    for i, c in enumerate(values):
        data[c] = [row[i] if i < len(row) else float("nan") for row in r["rows"]]
    data["wall_seconds"] = r["wall"]
    data["message"] = r["message"]
    frame = pandas.DataFrame(data, columns=r["columns"])
    frame.attrs["summary"] = r["summary"]
    return frame


METHODS = ("semi-analytical", "semi-analytical-central", "direct-analytic", "adjoint",
           "adjoint-semi-analytical", "fd-forward", "fd-central", "idas", "idas-adjoint")
from .builder import (  # noqa: E402,F401
    ModelBuilder,
    SpatialModelBuilder,
    Variable,
    at,
    at_global,
    bspline,
    circle,
    constant,
    cylinder,
    ellipse,
    gmsh,
    ground,
    nearest,
    node,
    pocket,
    ramp,
    rectangle,
    sphere,
    super_ellipse,
    super_ellipsoid,
    table,
    through_hole,
    trapezoid,
)
from . import plot  # noqa: E402,F401  (matplotlib is imported when a plot is drawn)
