#!/usr/bin/env python3
"""Step cost of a spatial mechanism against a planar one with the same number of coordinates.

Cases (emitted as case files; docs/performance.md, "Spatial mechanisms", times them with
farm-bench):
  - `spatial:N`: a chain of N rods (0.2 m, 1 kg) hung by spherical joints from the ground,
    released horizontal with a sideways push, under gravity: 12 N coordinates (natural
    coordinates), 9 N constraint equations;
  - `planar:M`: a chain of M rods hung by revolute joints, released horizontal: 3 M coordinates,
    2 M equations. M = 4 N gives the spatial chain's number of coordinates.
Both run 1 s at h = 1 ms, with the first and last rods' masses as design variables and the tip's
final height and average position as responses.

  bench/spatial_cost.py --emit spatial:10 FILE
  bench/spatial_cost.py --emit planar:40 FILE
"""
import argparse
import json
import sys

L, M = 0.2, 1.0
I_ROD = M * L * L / 12


def spatial(n):
    bodies, joints = [], []
    for i in range(n):
        bodies.append({"name": f"rod{i}", "type": "rigid", "mass": M,
                       "inertia": [1e-3 * I_ROD, I_ROD, I_ROD],  # e1 along the rod
                       "position": [L * (i + 0.5), 0, 0],
                       "velocity": [0, 0.5 * (i + 0.5) * L, 0]})
        joints.append({"name": f"ball{i}", "type": "spherical", "a": "ground" if i == 0 else f"rod{i - 1}",
                       "b": f"rod{i}", "at": [L * i, 0, 0]})
    tip = {"name": "tip", "type": "position", "body": f"rod{n - 1}", "at": [L * n, 0, 0]}
    return {"name": f"spatial_chain_{n}", "dimension": 3, "gravity": [0, 0, -9.81],
            "bodies": bodies, "joints": joints, "measures": [tip], "tip_z": "tip.z"}


def planar(m):
    bodies, joints = [], []
    for i in range(m):
        bodies.append({"name": f"rod{i}", "type": "rigid", "mass": M, "inertia": I_ROD,
                       "position": [L * (i + 0.5), 0], "angular_velocity": 0.0})
        a = {"ground": [0, 0]} if i == 0 else {"body": f"rod{i - 1}", "at": [L / 2, 0]}
        joints.append({"name": f"pin{i}", "type": "revolute", "a": {"body": f"rod{i}", "at": [-L / 2, 0]},
                       "b": a})
    tip = {"name": "tip", "type": "position", "point": {"body": f"rod{m - 1}", "at": [L / 2, 0]}}
    return {"name": f"planar_chain_{m}", "gravity": [0, -9.81], "bodies": bodies,
            "joints": joints, "measures": [tip], "tip_z": "tip.y"}


def case(kind, n):
    c = spatial(n) if kind == "spatial" else planar(n)
    tip_z = c.pop("tip_z")
    measures = c.pop("measures")
    last = f"rod{n - 1}"
    c.update({
        "simulation": {"t_end": 1.0, "h": 1e-3},
        "output": {"csv_stride": 1000, "measures": measures,
                   "responses": [{"name": "final_tip", "measure": tip_z, "aggregate": "final"},
                                 {"name": "mean_tip", "measure": tip_z, "aggregate": "average"}]},
        "design": {"variables": [{"name": "m0", "initial": M, "lower": 0.5, "upper": 2},
                                 {"name": "m1", "initial": M, "lower": 0.5, "upper": 2}],
                   "parameters": [{"parameter": "rod0.mass", "variable": "m0"},
                                  {"parameter": f"{last}.mass", "variable": "m1"}]}})
    return c


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--emit", nargs=2, metavar=("KIND:N", "FILE"), required=True)
    a = ap.parse_args()
    kind, n = a.emit[0].split(":")
    if kind not in ("spatial", "planar"):
        sys.exit("KIND: spatial or planar")
    with open(a.emit[1], "w") as f:
        json.dump(case(kind, int(n)), f, indent=1)


if __name__ == "__main__":
    main()
