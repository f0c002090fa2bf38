"""The design picture and the convergence plot of an optimization, saved as PNG.

    PYTHONPATH=build/python python3 examples/python/design_pictures.py [CASE.json] [OUT_DIR]

Runs the case's optimization (lsmbs.optimize; default: the coarse connecting rod with one hole),
then draws the final design (μ_e with the features' zero contour, lsmbs.plot.design) and the
objective and constraint violation per evaluation (lsmbs.plot.convergence). Checks itself: the
final mass in the picture's title is the one lsmbs.geometry computes at the final design, and
the hole (φ < 0 nodes) is where μ_e is smallest.
"""
import pathlib
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import lsmbs

ROOT = pathlib.Path(__file__).resolve().parents[2]
path = sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "data/slider_crank/slider_crank_1hole_coarse.json")
out = pathlib.Path(sys.argv[2] if len(sys.argv) > 2 else ".")
out.mkdir(parents=True, exist_ok=True)

# 1. The optimization.
case = lsmbs.load_case(path)
result = lsmbs.optimize(case)
print(result["report"])

# 2. The final design, mapped on the mesh.
geo = lsmbs.geometry(case, design=list(result["p"]))
for name, body in geo.items():
    ax = lsmbs.plot.design(body)
    ax.figure.savefig(out / f"design_{name}.png", dpi=150, bbox_inches="tight")
    plt.close(ax.figure)
    print("design picture:", out / f"design_{name}.png")

# 3. The convergence plot.
ax = lsmbs.plot.convergence(result["history"])
ax.figure.savefig(out / "convergence.png", dpi=120, bbox_inches="tight")
print("convergence plot:", out / "convergence.png")

# 4. Self-check: the void (φ < 0 at all four nodes) has the smallest μ_e.
ok = True
for body in geo.values():
    void = np.all(body["phi"][body["quads"]] < 0, axis=1)
    if void.any():
        ok &= body["mu"][void].max() <= body["mu"][~void].min() + 1e-12
print("check:", "pass" if ok else "FAIL")
sys.exit(0 if ok else 1)
