"""A free-form hole: a closed cubic B-spline whose control points are the design variables.

    PYTHONPATH=build/python python3 examples/python/freeform_hole.py [OUT_DIR]

A cantilever plate (300 × 50 × 2 mm aluminium, clamped at its left edge, a 40 N tip load brought
in over 22 ms) with one hole bounded by a closed uniform cubic B-spline of 12 control points: 24
design variables, each point free to move ±12 mm in x and ±5 mm in y about an ellipse (the curve,
inside its control points' hull, then keeps 10 mm, two elements, from the plate's edges). The plate's
mass is minimized under a bound on the average tip deflection, with MMA and the discrete adjoint
(the cost of a gradient does not grow with the number of control points).

Checks itself (exit 1 otherwise):
  1. the void area at the start against the curve's exact area (Green's theorem on its Bézier
     segments, lsmbs.export.bspline_area), to the mapping's resolution (0.5 %);
  2. the adjoint gradient of both responses against central differences, coordinate by
     coordinate, for the 4 coordinates of two neighbouring control points (1e-4 of the largest);
  3. the optimum is feasible (within the stop rule's 0.25 %), lighter than the start, judged sound (no unresolved member, no load
     path through the void) and its curve a simple closed curve;
  4. exported to STEP through OpenCASCADE (the exact curve, as Bézier segments), the part's
     volume matches the fixed-mesh mass / ρ to the mapping's resolution (1 %).
"""
import json
import math
import pathlib
import sys
import tempfile

import numpy as np

import lsmbs
from lsmbs import export, rectangle

out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="freeform_"))
RHO, T = 2700.0, 0.002
failures = []


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what)
    if not ok:
        failures.append(what)


# ------------------------------------------------------------------ the model
m = lsmbs.ModelBuilder("freeform_plate")
m.flexible_body("plate", rectangle((0, -0.025), (0.3, 0.05), (60, 10)),
                E=70e9, nu=0.33, rho=RHO, thickness=T)
m.clamp("root", "plate", "left")
tip = lsmbs.nearest("plate", (0.3, 0.0))
m.point_force("load", tip, fy=lsmbs.trapezoid(0.0, -40.0, acceleration=4e5, speed=2500.0))
points, start = [], []
for k in range(12):
    t = 2 * math.pi * k / 12
    x0, y0 = 0.15 + 0.06 * math.cos(t), 0.010 * math.sin(t)
    x = m.variable(f"x{k + 1}", initial=x0, lower=x0 - 0.012, upper=x0 + 0.012)
    y = m.variable(f"y{k + 1}", initial=y0, lower=y0 - 0.005, upper=y0 + 0.005)
    points.append([x, y])
    start.append([x0, y0])
m.features("plate", [lsmbs.bspline("free", control_points=points)])
m.measure("tip", "position", point=tip)
m.measure("mass", "mass", body="plate")
m.response("plate_mass", "mass", "final")
m.response("tip_deflection", "tip.y", "average")
m.simulation(t_end=0.03, h=0.001)

# ------------------------------------------------------------------ 1. the mapped area
case = m.build()
g = lsmbs.geometry(case)["plate"]
void = (RHO * T * 0.3 * 0.05 - g["mass"]) / (RHO * T * (1 - 1e-3))
exact = export.bspline_area(start)
check(abs(void / exact - 1) < 5e-3,
      f"void area {void:.6e} m² against the curve's {exact:.6e} m² ({100 * (void / exact - 1):+.3f} %)")

# ------------------------------------------------------------------ 2. adjoint vs differences
s = lsmbs.sensitivity(case, method="adjoint")
p0 = np.array([c for pt in start for c in pt])
h = 1e-6
for name in ("plate_mass", "tip_deflection"):
    for k in (2, 3, 4, 5):  # x2, y2, x3, y3
        vals = []
        for sign in (+1, -1):
            p = p0.copy()
            p[k] += sign * h
            vals.append(lsmbs.simulate(case, design=p).responses[name])
        fd = (vals[0] - vals[1]) / (2 * h)
        ad = s.gradients[name][k]
        scale = np.max(np.abs(s.gradients[name]))
        check(abs(ad - fd) <= 1e-4 * scale,
              f"d {name} / d {case.variables[k]}: adjoint {ad:.8e}, central {fd:.8e}")

# ------------------------------------------------------------------ 3. the optimization
bound = 1.05 * s.values["tip_deflection"]  # deflection is negative: 5 % more sag allowed
m.optimization("plate_mass", constraints=[{"response": "tip_deflection", "lower": bound}],
               sensitivity={"method": "adjoint"}, stop={"max_evaluations": 80, "relative_objective_change": 1e-5})
case = m.build()
r = lsmbs.optimize(case, out_dir=str(out / "optimize"), overwrite=True)
final = r["final"]
check(final["objective"] < s.values["plate_mass"],
      f"mass {s.values['plate_mass'] * 1e3:.3f} g -> {final['objective'] * 1e3:.3f} g "
      f"after {r['evaluations']} evaluations ({r['stop_reason']})")
check(final["max_violation"] <= 2.5e-3,  # (g − bound)/|bound|: the stop rule's tolerance
      f"deflection constraint: relative violation {final['max_violation']:.2e}")
judgement = json.loads((out / "optimize" / "summary.json").read_text())["judgement"]
check(judgement["sound"], f"the design is judged sound ({judgement['verdict']})")
shape_file = out / "optimize" / "final_design" / "plate_shape.json"
shape = json.loads(shape_file.read_text())
P = shape["features"][0]["control_points"]
poly = export.feature_points(shape["features"][0], 240)


def crosses(a, b, c, d):
    o = lambda p, q, r: np.sign((q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]))
    return o(a, b, c) != o(a, b, d) and o(c, d, a) != o(c, d, b)


simple = not any(crosses(poly[i], poly[i + 1], poly[j], poly[(j + 1) % len(poly)])
                 for i in range(len(poly) - 1) for j in range(i + 2, len(poly))
                 if not (i == 0 and j == len(poly) - 1))
check(simple, "the optimized curve is a simple closed curve")

# ------------------------------------------------------------------ 4. out to CAD
files = export.export(shape, out / "cad", ("dxf", "svg", "step"))
import gmsh  # noqa: E402  (python3-gmsh)

gmsh.initialize(readConfigFiles=False)
gmsh.option.setNumber("General.Terminal", 0)
vol = sum(gmsh.model.occ.getMass(d, t) for d, t in gmsh.model.occ.importShapes(files["step"])
          if d == 3) * 1e-9  # mm³ -> m³
gmsh.finalize()
mass_cad = RHO * vol
check(abs(mass_cad / final["objective"] - 1) < 1e-2,
      f"STEP solid {mass_cad * 1e3:.3f} g against the fixed mesh's {final['objective'] * 1e3:.3f} g")
print(f"results in {out}")
sys.exit(1 if failures else 0)
