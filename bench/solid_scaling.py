#!/usr/bin/env python3
"""How KLU's cost grows on 3D solid meshes (docs/performance.md, "Solid bodies: KLU on 3D
meshes"): a plate-like block 0.4 x 0.2 x 0.1 m of 4k x 2k x k enhanced bricks, clamped at one
end and released under its weight, run for a few steps by `lsmbs bench --methods none`; per mesh
the DOFs, the nonzeros of the matrix and of KLU's factors (AMD ordering), the time of one KLU
refactorization and solve, of a whole step, and the peak memory; then the fitted exponents of
step time and factor fill against DOFs (least squares in log-log).

  python3 bench/solid_scaling.py --lsmbs build/src/lsmbs --k 3,4,6,8 [--ordering nested_dissection]

A mesh whose run exceeds --timeout (or fails) ends the sweep; the table so far is printed.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile


def case(k, ordering, steps=3, h=1e-4):
    return {"name": "solid_block_k%d" % k, "dimension": 3, "gravity": [0, 0, -9.81],
            "bodies": [{"name": "block", "type": "solid",
                        "mesh": {"type": "box", "origin": [0, 0, 0], "size": [0.4, 0.2, 0.1],
                                 "elements": [4 * k, 2 * k, k]},
                        "material": {"E": 7e10, "nu": 0.3, "rho": 2700}}],
            "joints": [{"name": "clamp", "type": "solid_connection", "solid": "block",
                        "node_set": "xmin", "body": "ground"}],
            "simulation": {"t_end": steps * h, "h": h, "ordering": ordering},
            "output": {"measures": [{"name": "tip", "type": "node_set_position", "body": "block",
                                     "node_set": "xmax"}],
                       "responses": [{"name": "tip_z", "measure": "tip.z", "aggregate": "final"}]}}


def fit(xs, ys):
    lx, ly = [math.log(x) for x in xs], [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    return sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sum((a - mx) ** 2 for a in lx)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--lsmbs", required=True)
    ap.add_argument("--k", default="4,6,8,11,16")
    ap.add_argument("--timeout", type=float, default=900)
    ap.add_argument("--ordering", default="amd", choices=["amd", "nested_dissection"],
                    help="KLU's fill-reducing ordering (\"simulation\": {\"ordering\"})")
    a = ap.parse_args()
    rows = []
    work = tempfile.mkdtemp(prefix="solid_scaling_")
    for k in [int(x) for x in a.k.split(",")]:
        cf = os.path.join(work, "k%d.json" % k)
        with open(cf, "w") as f:
            json.dump(case(k, a.ordering), f)
        out = os.path.join(work, "k%d" % k)
        try:
            p = subprocess.run([a.lsmbs, "bench", cf, "-o", out, "-q", "--methods", "none",
                                "--matrices", "none", "--repetitions", "2", "--threads", "1"],
                               capture_output=True, text=True, timeout=a.timeout)
        except subprocess.TimeoutExpired:
            print("k = %d: over %g s, stopped" % (k, a.timeout), file=sys.stderr)
            break
        if p.returncode != 0:
            print("k = %d: exit %d: %s" % (k, p.returncode, p.stderr.strip()), file=sys.stderr)
            break
        b = json.load(open(os.path.join(out, "bench.json")))
        fl = b["floor_seconds"]
        rows.append({"k": k, "elements": 8 * k ** 3, "dofs": b["model"]["dofs"],
                     "nonzeros": b["model"]["nonzeros"], "lu_nonzeros": b["model"]["lu_nonzeros"],
                     "klu_refactor_and_solve": fl["klu_refactor_and_solve"],
                     "step": b["primal"]["seconds_per_step"], "peak_mb": b["peak_rss_kb"] / 1024})
        r = rows[-1]
        print("k %2d  bricks %7d  DOFs %7d  nnz %9d  LU nnz %11d (x%.1f)  KLU %.3g s  step %.3g s  "
              "peak %.0f MB" % (k, r["elements"], r["dofs"], r["nonzeros"], r["lu_nonzeros"],
                                r["lu_nonzeros"] / r["nonzeros"], r["klu_refactor_and_solve"],
                                r["step"], r["peak_mb"]), flush=True)
    if len(rows) >= 2:
        d = [r["dofs"] for r in rows]
        print("fitted exponents against DOFs: step time %.2f, KLU refactor+solve %.2f, LU nonzeros "
              "%.2f, peak memory %.2f" % (fit(d, [r["step"] for r in rows]),
                                          fit(d, [r["klu_refactor_and_solve"] for r in rows]),
                                          fit(d, [r["lu_nonzeros"] for r in rows]),
                                          fit(d, [r["peak_mb"] for r in rows])))
    print(json.dumps(rows))


if __name__ == "__main__":
    main()
