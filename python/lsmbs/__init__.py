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

METHODS = ("semi-analytical", "semi-analytical-central", "direct-analytic", "adjoint",
           "adjoint-semi-analytical", "fd-forward", "fd-central", "idas", "idas-adjoint")
from .builder import (  # noqa: E402,F401
    ModelBuilder,
    Variable,
    at,
    at_global,
    circle,
    constant,
    ellipse,
    gmsh,
    ground,
    nearest,
    node,
    ramp,
    rectangle,
    super_ellipse,
    table,
    trapezoid,
)
from . import plot  # noqa: E402,F401  (matplotlib is imported when a plot is drawn)
