#!/usr/bin/env python3
"""idas-adjoint against idas (forward sensitivities): the time-integral responses' values and
gradients on windows that start and end on output times, before, across and after the driver
law's kinks, on generated mechanism seed 111 (a driven four-bar with a pendulum: ramp from rest
at t = 0.045 s, constant speed from t = 0.2418 s).

The two runs integrate the same DAE with different step sequences, so they agree to IDAS's
accuracy (rtol 1e-9: a few 1e-8 measured); the adjoint's values once came from a stale
IDAGetQuad (Q at the previous output time) and were 2 % off on int_0_0.04.
Usage: idas_adjoint_values_test.py LSMBS ROOT
"""
import json
import os
import subprocess
import sys
import tempfile

lsmbs, root = sys.argv[1], sys.argv[2]
sys.path.insert(0, os.path.join(root, "verification", "corpus"))
import gen_mechanisms  # noqa: E402

WINDOWS = [(0, 0.04), (0.04, 0.05), (0.05, 0.24), (0.24, 0.25), (0.25, 0.3725), (0, 0.3725)]
VALUE_TOL = 1e-6    # relative; measured ≤ 1.4e-7
GRADIENT_TOL = 1e-5  # relative to the largest entry of the response's gradient; measured ≤ 3.1e-6

with tempfile.TemporaryDirectory() as t:
    case = gen_mechanisms.generate(111)
    case["output"]["responses"] = [
        {"name": "int_%g_%g" % w, "measure": "m_pendulum_angle", "aggregate": "integral",
         "window": {"t0": w[0], "t1": w[1]}} for w in WINDOWS] + [
        {"name": "avg_ke", "measure": "m_ke", "aggregate": "average", "window": {"t0": 0.04, "t1": 0.3725}}]
    path = os.path.join(t, "case.json")
    json.dump(case, open(path, "w"))
    out = {}
    for m in ("idas", "idas-adjoint"):
        d = os.path.join(t, m)
        subprocess.run([lsmbs, "sensitivity", path, "--method", m, "-o", d, "-q"], check=True)
        out[m] = json.load(open(os.path.join(d, "summary.json")))["quadratures"]
    bad = 0
    for name, f in out["idas"].items():
        a = out["idas-adjoint"][name]
        ev = abs(a["value"] - f["value"]) / abs(f["value"])
        scale = max(abs(v) for v in f["gradient"].values())
        eg = max(abs(a["gradient"][v] - f["gradient"][v]) for v in f["gradient"]) / scale
        ok = ev <= VALUE_TOL and eg <= GRADIENT_TOL
        bad += not ok
        print("%-16s value %.3e  gradient %.3e  %s" % (name, ev, eg, "ok" if ok else "FAIL"))
    sys.exit(1 if bad else 0)
