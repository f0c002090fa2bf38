"""Parameter sweep: the robot arm's average tip deviation over the plate thickness.

    PYTHONPATH=build/python python3 examples/python/thickness_sweep.py [OUT.png]

A model parameter changed from Python (`case.parameters["plate.thickness"]`), one simulation
per value, and the sweep as a plot. The deviation is dynamic: a thicker plate is stiffer (bending
∝ t³) but also heavier (∝ t), and what remains of its vibration after the arm stops depends on
how its natural period fits the motion, so the deviation is not monotone in t. Checks itself
against what is exact: the plate's mass ρ t Σ A_e is linear in t (to round-off).
"""
import pathlib
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import lsmbs

ROOT = pathlib.Path(__file__).resolve().parents[2]
out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "thickness_sweep.png")
out.parent.mkdir(parents=True, exist_ok=True)

# 1. The case, and the parameter to vary.
case = lsmbs.load_case(str(ROOT / "data/robot_arm/robot_arm.json"))
t0 = case.parameters["plate.thickness"]

# 2. The sweep: one simulation per thickness.
thickness = t0 * np.array([0.8, 1.0, 1.25, 1.5])
deviation, mass = [], []
for t in thickness:
    case.parameters["plate.thickness"] = t
    r = lsmbs.simulate(case)
    deviation.append(r.responses["average_tip_deviation"])
    mass.append(r.responses["plate_mass"])
    print(f"t = {1e3 * t:.3f} mm: average tip deviation {1e3 * deviation[-1]:.4f} mm, mass {1e3 * mass[-1]:.2f} g")

# 3. The plot.
fig, ax = plt.subplots(figsize=(6, 4))
ax.plot(1e3 * thickness, 1e3 * np.array(deviation), "o-")
ax.set_xlabel("plate thickness [mm]")
ax.set_ylabel("average tip deviation [mm]")
ax.grid(True, alpha=0.3)
fig.tight_layout()
fig.savefig(out, dpi=120)
print("plot:", out)

# 4. Self-check: the mass is exactly linear in t.
ok = np.allclose(np.array(mass) / thickness, mass[1] / thickness[1], rtol=1e-12, atol=0)
print("check:", "pass" if ok else "FAIL")
sys.exit(0 if ok else 1)
