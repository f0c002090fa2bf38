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
from ._lsmbs import static  # noqa: F401  (lsmbs.static(case): static equilibrium)
from ._lsmbs import (  # noqa: F401
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
