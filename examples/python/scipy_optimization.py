"""The design loop driven from Python: SciPy's trust-constr on lsmbs.DesignProblem, compared with
the built-in MMA (lsmbs.optimize) on the same case.

    PYTHONPATH=build/python python3 examples/python/scipy_optimization.py [CASE.json] [--h H]

Default case: the robot arm with holes (data/robot_arm/robot_arm_holes.json, 15 variables,
minimum mass with an average-tip-deviation constraint; minutes). ctest runs it on the coarse
connecting rod (one variable) with --h 5e-4, twice the case's time step, so that the Python
examples finish within a minute together; --h changes the case of both optimizers alike. DesignProblem.evaluate(p) runs one
simulation with its sensitivities and caches it by p, so SciPy's separate calls for the
objective, the constraints and their Jacobians cost one simulation per design.
SLSQP stops on the connecting rod with "positive directional derivative for linesearch" at an
infeasible point (its per-step elongation constraints, one per time step, are non-smooth where the
worst step changes); trust-constr, an interior-point/SQP trust-region method, handles them.
Checks itself: trust-constr ends feasible, and within 1 % of MMA's objective.
"""
import argparse
import pathlib
import sys

import numpy as np
from scipy.optimize import Bounds, NonlinearConstraint, minimize

import lsmbs

ROOT = pathlib.Path(__file__).resolve().parents[2]
cli = argparse.ArgumentParser(description=__doc__.splitlines()[0])
cli.add_argument("case", nargs="?", default=str(ROOT / "data/robot_arm/robot_arm_holes.json"))
cli.add_argument("--h", type=float, help="time step [s] instead of the case's")
args = cli.parse_args()


def load():
    case = lsmbs.load_case(args.case)
    if args.h:
        case.simulation.h = args.h
    return case


# 1. The problem of the case's optimization section: objective and constraints g_j <= upper_j.
case = load()
problem = lsmbs.DesignProblem(case)
lo, up = case.lower, case.upper
scale = up - lo  # SLSQP on x in [0, 1]: p = lo + scale x


def at(x):
    return problem.evaluate(np.clip(lo + scale * x, lo, up))


# 2. SciPy: objective and constraints ((g - upper) / scale <= 0) with their gradients.
def f(x):
    e = at(x)
    return e["objective"] / abs(first["objective"])


def df(x):
    return at(x)["objective_gradient"] * scale / abs(first["objective"])


def g(x):
    e = at(x)
    return (e["constraints"] - e["upper"]) / e["scale"]


def dg(x):
    e = at(x)
    return e["constraint_gradient"] * scale / e["scale"][:, None]


x0 = (case.initial_design - lo) / scale
first = at(x0)
res = minimize(f, x0, jac=df, method="trust-constr", bounds=Bounds(0, 1),
               constraints=[NonlinearConstraint(g, -np.inf, 0, jac=dg)], options={"maxiter": 40})
best = at(res.x)
print(f"trust-constr: {res.message} after {res.nit} iterations, {problem.simulations} simulations "
      f"({problem.cache_hits} answers from the cache)")
print(f"  objective {first['objective']:.6g} -> {best['objective']:.6g}, max violation {best['max_violation']:.2e}")

# 3. The built-in MMA on the same case, for comparison.
mma = lsmbs.optimize(load())
print(f"MMA:   {mma['nlopt_status']}, {mma['evaluations']} evaluations; objective "
      f"{mma['final']['objective']:.6g}, max violation {mma['final']['max_violation']:.2e}")

# 4. Self-check: trust-constr feasible (within MMA's constraint tolerance) and close to MMA.
ok = best["max_violation"] <= 2.5e-3 and abs(best["objective"] - mma["final"]["objective"]) <= 1e-2 * abs(mma["final"]["objective"])
print("check:", "pass" if ok else "FAIL")
sys.exit(0 if ok else 1)
