#!/usr/bin/env python3
"""Calibrates the reconstructed connecting rod against the paper's initial design.

Targets (Tromme et al., Table 1, initial design p = 0.001): rod mass 295.664 g and maximum
elongation 13.508 um over the simulated cycle. Knobs of rod.geo: the big-end boss radius Rbo
(mostly mass) and a common scale s of the shank half-widths hb = 12 s, hs = 8 s (mostly
stiffness). Newton iterations with a forward-difference Jacobian; every evaluation meshes the
rod with gmsh and runs `lsmbs simulate` on slider_crank_1hole.json. The result is written as
the defaults of rod.geo and rod.msh / rod_coarse.msh are regenerated.

Usage: python3 calibrate.py [--lsmbs ../../build/src/lsmbs]
"""
import argparse
import json
import os
import re
import subprocess
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
TARGET = (0.295664, 13.508e-6)
HB0, HS0 = 12.0, 8.0


def evaluate(lsmbs, rbo, s, work):
    msh = os.path.join(work, "rod.msh")
    subprocess.run(["gmsh", "-setnumber", "Rbo", repr(rbo), "-setnumber", "hb", repr(HB0 * s), "-setnumber", "hs",
                    repr(HS0 * s), "-2", os.path.join(HERE, "rod.geo"), "-format", "msh41", "-o", msh],
                   check=True, stdout=subprocess.DEVNULL)
    case = json.load(open(os.path.join(HERE, "slider_crank_1hole.json")))
    case["bodies"][2]["mesh"]["file"] = msh
    case["forces"][0]["table"]["file"] = os.path.join(HERE, "pressure.csv")
    case["output"]["vtu_stride"] = 0
    path = os.path.join(work, "case.json")
    json.dump(case, open(path, "w"))
    out = os.path.join(work, "out")
    subprocess.run([lsmbs, "simulate", path, "-o", out, "--quiet"], check=True)
    r = json.load(open(os.path.join(out, "summary.json")))["responses"]
    m, e = r["rod_mass"], r["max_elongation"]
    print(f"  Rbo = {rbo:.6f} mm, s = {s:.6f}: mass {m * 1e3:.4f} g, max elongation {e * 1e6:.4f} um", flush=True)
    return m, e


def main():
    ap = argparse.ArgumentParser(description="calibrate rod.geo (see the module docstring)")
    ap.add_argument("--lsmbs", default=os.path.join(HERE, "..", "..", "build", "src", "lsmbs"))
    ap.add_argument("--rbo", type=float, default=30.0)
    ap.add_argument("--s", type=float, default=1.0)
    args = ap.parse_args()
    x = [args.rbo, args.s]
    with tempfile.TemporaryDirectory() as work:
        for it in range(8):
            m, e = evaluate(args.lsmbs, x[0], x[1], work)
            res = [m / TARGET[0] - 1, e / TARGET[1] - 1]
            print(f"iteration {it}: relative errors mass {res[0]:+.2e}, elongation {res[1]:+.2e}")
            if abs(res[0]) < 2e-4 and abs(res[1]) < 2e-3:
                break
            J = [[0, 0], [0, 0]]
            for j, d in enumerate([0.05, 0.01]):
                xp = list(x)
                xp[j] += d
                mp, ep = evaluate(args.lsmbs, xp[0], xp[1], work)
                J[0][j] = (mp / TARGET[0] - 1 - res[0]) / d
                J[1][j] = (ep / TARGET[1] - 1 - res[1]) / d
            det = J[0][0] * J[1][1] - J[0][1] * J[1][0]
            dx0 = -(J[1][1] * res[0] - J[0][1] * res[1]) / det
            dx1 = -(-J[1][0] * res[0] + J[0][0] * res[1]) / det
            x = [x[0] + dx0, x[1] + dx1]
    geo = os.path.join(HERE, "rod.geo")
    text = open(geo).read()
    for name, value in [("Rbo", x[0]), ("hb", HB0 * x[1]), ("hs", HS0 * x[1])]:
        text = re.sub(rf"If \(!Exists\({name}\)\)\s*{name} = [0-9.]+;", f"If (!Exists({name})) {name} = {value:.4f};",
                      text)
    open(geo, "w").write(text)
    for lc, name in [(None, "rod.msh"), (3, "rod_coarse.msh")]:
        cmd = ["gmsh"] + (["-setnumber", "lc", str(lc)] if lc else []) + ["-2", geo, "-format", "msh41", "-o",
                                                                          os.path.join(HERE, name)]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    print(f"calibrated: Rbo = {x[0]:.4f} mm, hb = {HB0 * x[1]:.4f} mm, hs = {HS0 * x[1]:.4f} mm -> rod.geo, "
          "rod.msh, rod_coarse.msh")


if __name__ == "__main__":
    main()
