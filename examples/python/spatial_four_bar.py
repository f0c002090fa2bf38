"""A spatial four-bar balanced by a torsion spring: the spring's stiffness and free angle that
minimize the motor's RMS torque, found by SciPy with lsmbs's exact gradients.

    PYTHONPATH=build/python python3 examples/python/spatial_four_bar.py

An RSSR-type linkage: the crank turns about the ground's z axis, driven at constant speed; the
rocker turns about a tilted ground axis (not parallel to the crank's, so the linkage is spatial);
the coupler has a spherical joint at the crank pin and a universal joint at the rocker, which
holds its spin. A torsion spring on the rocker's joint angle stores and returns energy over the
cycle; its stiffness k and free angle θ0 are the design variables, the objective the RMS of the
motor's torque over the second revolution (gravity and inertia load it). Built in Python with
lsmbs.SpatialModelBuilder (docs/case-format.md, "Spatial cases").

Checks itself: the gradient at the start against central differences of the objective; the
optimum's RMS torque is at least 10 % below the one without a spring; at the optimum the gradient is zero to within 1e-3 of its size at
the start (an interior minimum: both variables end inside their bounds).
"""
import math
import sys

import numpy as np
from scipy.optimize import minimize

import lsmbs

# 1. The linkage (m, kg, s).
a = 0.05                                   # crank radius
G = np.array([0.12, 0.10, 0.04])           # the rocker's ground pivot
n = np.array([0.0, 1.0, 1.0]) / math.sqrt(2)  # the rocker's axis
c = 0.09                                   # rocker length
P0 = np.array([a, 0.0, 0.0])               # crank pin at t = 0
u = np.cross(n, [1.0, 0.0, 0.0])
u /= np.linalg.norm(u)                     # the rocker's direction at t = 0, ⟂ its axis
R0 = G + c * u                             # rocker tip at t = 0
d = (R0 - P0) / np.linalg.norm(R0 - P0)    # the coupler's direction


def frame(e3, hint):
    """A rotation matrix whose third column is e3 and first is hint made ⟂ e3."""
    e1 = hint - np.dot(hint, e3) * e3
    e1 /= np.linalg.norm(e1)
    return np.column_stack([e1, np.cross(e3, e1), e3])


def rod(m, length):  # a slender rod along its third axis: principal moments
    return (m * length**2 / 12, m * length**2 / 12, 1e-3 * m * length**2 / 12)


m = lsmbs.SpatialModelBuilder("spatial_four_bar", gravity=(0, 0, -9.81))
m.rigid_body("crank", position=P0 / 2, orientation=frame(np.array([1.0, 0, 0]), np.array([0, 0, 1.0])),
             mass=0.3, inertia=rod(0.3, a))
L = float(np.linalg.norm(R0 - P0))
m.rigid_body("coupler", position=(P0 + R0) / 2, orientation=frame(d, n), mass=0.6,
             inertia=rod(0.6, L))
m.rigid_body("rocker", position=(G + R0) / 2, orientation=frame(u, n), mass=0.5,
             inertia=rod(0.5, c))
m.revolute("bearing", "ground", "crank", (0, 0, 0), (0, 0, 1))
m.spherical("pin", "crank", "coupler", P0)
m.universal("wrist", "rocker", "coupler", R0, n, np.cross(d, n) / np.linalg.norm(np.cross(d, n)))
m.revolute("rocker_pivot", "ground", "rocker", G, n)
omega = 4 * math.pi  # 2 rev/s
m.rotation_driver("motor", "bearing", lsmbs.ramp(omega, 0.25))
m.rotational_spring_damper("spring", "rocker_pivot", 1.0, free_angle=0.0)
m.measure("torque", "constraint_force", joint="motor")
m.measure("rocker_angle", "joint_angle", joint="rocker_pivot")
m.response("rms_torque", "torque.0", "rms", window=(0.75, 1.25))
m.response("swing", "rocker_angle", "max")
m.variable("k", 1.0, 0.0, 20.0)
m.variable("theta0", 0.0, -1.5, 1.5)
m.bind_parameter("spring.stiffness", "k")
m.bind_parameter("spring.free_angle", "theta0")
m.optimization("rms_torque")
m.simulation(t_end=1.25, h=2e-3)
case = m.build()
problem = lsmbs.DesignProblem(case)

# 2. The gradient at the start against central differences.
p0 = np.array(case.initial_design)
e0 = problem.evaluate(p0)
g0 = np.asarray(e0["objective_gradient"])
fd = np.zeros_like(p0)
for i, step in enumerate((1e-3, 1e-5)):
    dp = np.zeros_like(p0)
    dp[i] = step
    fd[i] = (problem.evaluate(p0 + dp)["objective"] - problem.evaluate(p0 - dp)["objective"]) / (2 * step)
print(f"start: k = {p0[0]:g} N m/rad, θ0 = {p0[1]:g} rad, RMS torque {e0['objective']:.6f} N m")
print(f"  gradient {g0}, central differences {fd}")
assert np.allclose(g0, fd, rtol=1e-4, atol=1e-8 * np.abs(g0).max()), (g0, fd)

# 3. SciPy's L-BFGS-B on (k, θ0) with the exact gradient.
lo, up = np.array(case.lower), np.array(case.upper)
res = minimize(lambda p: problem.evaluate(p)["objective"], p0, method="L-BFGS-B",
               jac=lambda p: np.asarray(problem.evaluate(p)["objective_gradient"]),
               bounds=list(zip(lo, up)), options={"gtol": 1e-9, "ftol": 1e-12, "maxiter": 50})
best = problem.evaluate(res.x)
g = np.asarray(best["objective_gradient"])
none = problem.evaluate(np.array([0.0, 0.0]))["objective"]  # no spring
print(f"optimum: k = {res.x[0]:.4f} N m/rad, θ0 = {res.x[1]:.4f} rad, RMS torque "
      f"{best['objective']:.6f} N m ({100 * (best['objective'] / none - 1):+.1f} % against no "
      f"spring, {none:.6f} N m), {problem.simulations} simulations; gradient {g}")
inside = np.all(res.x > lo + 1e-6) and np.all(res.x < up - 1e-6)
assert best["objective"] < 0.9 * none, "the spring should lower the RMS torque"
assert inside, f"expected an interior optimum, got {res.x}"
assert np.abs(g).max() < 1e-3 * np.abs(g0).max(), (g, g0)
print("spatial_four_bar: checks passed")
sys.exit(0)
