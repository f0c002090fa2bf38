#!/usr/bin/env python3
"""How the sparse LU's cost grows on 3D solid meshes (docs/performance.md, "Linear solvers on 3D
meshes"): a plate-like block 0.4 x 0.2 x 0.1 m of 4k x 2k x k enhanced bricks with a spherical
void whose radius is a design variable, clamped at one end and released under its weight, run
for a few steps by `lsmbs bench`, one process per method so that each has its own peak memory:
the primal run (`--methods none`), the direct and the adjoint sensitivities (each with its
primal). Per mesh: the DOFs, the nonzeros of the matrix and of the factors, one factorization
and solve, the time per step of each method, and the peak memory; then the fitted exponents
against DOFs (least squares in log-log).

  python3 bench/solid_scaling.py --lsmbs build/src/lsmbs --k 3,4,6,8 --solver klu
  python3 bench/solid_scaling.py --lsmbs build/src/lsmbs --k 4,6,8,11,14 --solver umfpack \\
      --ordering nested_dissection --methods none,direct-analytic,adjoint

With --amg build/bench/lsmbs_amg_block (built with -DLSMBS_BUILD_BENCH=ON where hypre is
installed) each mesh's solve is also timed on the iteration matrix's elastic block (clamped nodes
and multipliers removed) by UMFPACK and by hypre's BoomerAMG-preconditioned CG (bench/amg_block.cpp):

  python3 bench/solid_scaling.py --lsmbs build/src/lsmbs --k 4,6,8,11,14,18 --methods none \
      --solver umfpack --ordering nested_dissection --amg build/bench/lsmbs_amg_block

A mesh whose run exceeds --timeout (or fails) ends the sweep; the table so far is printed.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

STEPS, H = 3, 1e-4


def case(k, ordering, solver):
    return {"name": "solid_block_k%d" % k, "dimension": 3, "gravity": [0, 0, -9.81],
            "bodies": [{"name": "block", "type": "solid",
                        "mesh": {"type": "box", "origin": [0, 0, 0], "size": [0.4, 0.2, 0.1],
                                 "elements": [4 * k, 2 * k, k]},
                        "material": {"E": 7e10, "nu": 0.3, "rho": 2700}}],
            "joints": [{"name": "clamp", "type": "solid_connection", "solid": "block",
                        "node_set": "xmin", "body": "ground"}],
            "design": {"variables": [{"name": "r", "initial": 0.03, "lower": 0.01,
                                      "upper": 0.045}],
                       "geometry": [{"body": "block", "features": [
                           {"name": "void", "type": "sphere", "cx": 0.2, "cy": 0.1, "cz": 0.05,
                            "r": "r"}]}]},
            "simulation": {"t_end": STEPS * H, "h": H, "ordering": ordering,
                           "linear_solver": solver},
            "output": {"measures": [{"name": "tip", "type": "node_set_position", "body": "block",
                                     "node_set": "xmax"}],
                       "responses": [{"name": "tip_z", "measure": "tip.z",
                                      "aggregate": "average"}]}}


def fit(xs, ys):
    lx, ly = [math.log(x) for x in xs], [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    return sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sum((a - mx) ** 2 for a in lx)


def bench(a, cf, out, method):
    p = subprocess.run([a.lsmbs, "bench", cf, "-o", out, "-q", "--methods", method,
                        "--matrices", "none", "--repetitions", "1", "--threads", "1"],
                       capture_output=True, text=True, timeout=a.timeout)
    if p.returncode != 0:
        raise RuntimeError("exit %d: %s" % (p.returncode, p.stderr.strip()))
    return json.load(open(os.path.join(out, "bench.json")))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--lsmbs", required=True)
    ap.add_argument("--k", default="4,6,8,11,14")
    ap.add_argument("--timeout", type=float, default=1800)
    ap.add_argument("--ordering", default="amd", choices=["amd", "nested_dissection"],
                    help="fill-reducing ordering (\"simulation\": {\"ordering\"})")
    ap.add_argument("--solver", default="auto", choices=["auto", "klu", "umfpack", "amg"],
                    help="sparse LU (\"simulation\": {\"linear_solver\"})")
    ap.add_argument("--amg", help="lsmbs_amg_block: also time the elastic block's solve by "
                    "UMFPACK and by AMG-preconditioned CG")
    ap.add_argument("--methods", default="none",
                    help="comma-separated: none (the primal run), direct-analytic, adjoint")
    a = ap.parse_args()
    methods = a.methods.split(",")
    rows = []
    work = tempfile.mkdtemp(prefix="solid_scaling_")
    for k in [int(x) for x in a.k.split(",")]:
        cf = os.path.join(work, "k%d.json" % k)
        with open(cf, "w") as f:
            json.dump(case(k, a.ordering, a.solver), f)
        r = {"k": k, "elements": 8 * k ** 3}
        try:
            for m in methods:
                b = bench(a, cf, os.path.join(work, "k%d_%s" % (k, m)), m)
                r["peak_mb_" + m] = b["peak_rss_kb"] / 1024
                if m == "none":
                    fl = b["floor_seconds"]
                    r.update(dofs=b["model"]["dofs"], nonzeros=b["model"]["nonzeros"],
                             lu_nonzeros=b["model"]["lu_nonzeros"],
                             solver=b["model"]["linear_solver"],
                             factor_and_solve=fl["factor_and_solve"],
                             step_none=b["primal"]["seconds_per_step"],
                             newton_per_step=b["primal"]["newton_per_step"],
                             factorizations_per_step=b["primal"]["factorizations_per_step"],
                             gmres_per_step=b["primal"].get("linear_iterations_per_step", 0),
                             gmres_max=b["primal"].get("max_linear_iterations", 0))
                else:
                    s = b["sensitivities"][m]
                    r["step_" + m] = s["wall_seconds"] / s["steps"]
            if a.amg:
                for solver in ("umfpack", "amg"):
                    p = subprocess.run([a.amg, cf, "--solver", solver], capture_output=True,
                                       text=True, timeout=a.timeout)
                    if p.returncode != 0:
                        raise RuntimeError("%s: exit %d: %s" % (a.amg, p.returncode, p.stderr))
                    r["block_" + solver] = json.loads(p.stdout.strip().splitlines()[-1])
        except subprocess.TimeoutExpired:
            print("k = %d: over %g s, stopped" % (k, a.timeout), file=sys.stderr)
            break
        except RuntimeError as e:
            print("k = %d: %s" % (k, e), file=sys.stderr)
            break
        rows.append(r)
        line = "k %2d  bricks %7d  DOFs %7d  nnz %9d  LU nnz %11d (x%.1f, %s)  LU %.3g s" % (
            k, r["elements"], r.get("dofs", 0), r.get("nonzeros", 0), r.get("lu_nonzeros", 0),
            r.get("lu_nonzeros", 0) / max(1, r.get("nonzeros", 1)), r.get("solver", "?"),
            r.get("factor_and_solve", 0))
        if r.get("gmres_max"):
            line += "  GMRES %.0f iterations a step (at most %d a solve)" % (
                r["gmres_per_step"], r["gmres_max"])
        for m in methods:
            line += "  %s: step %.3g s, peak %.0f MB" % (
                "primal" if m == "none" else m, r["step_" + m], r["peak_mb_" + m])
        if a.amg:
            u, g = r["block_umfpack"], r["block_amg"]
            line += ("\n      elastic block %d unknowns: UMFPACK factor %.3g s + solve %.3g s, peak %.0f "
                     "MB; AMG-CG setup %.3g s + solve %.3g s (%d iterations, %.1e from the LU), peak "
                     "%.0f MB" % (u["unknowns"], u["lu"]["factor_seconds"], u["lu"]["solve_seconds"],
                                  u["peak_rss_kb"] / 1024, g["amg"]["setup_seconds"],
                                  g["amg"]["solve_seconds"], g["amg"]["iterations"],
                                  g["amg"]["difference_from_lu"], g["peak_rss_kb"] / 1024))
        print(line, flush=True)
    if len(rows) >= 2 and "dofs" in rows[0]:
        d = [r["dofs"] for r in rows]
        parts = ["%s step %.2f, peak memory %.2f" % (
            "primal" if m == "none" else m, fit(d, [r["step_" + m] for r in rows]),
            fit(d, [r["peak_mb_" + m] for r in rows])) for m in methods]
        lu_fit = ("; LU nonzeros %.2f" % fit(d, [r["lu_nonzeros"] for r in rows])
                  if all(r["lu_nonzeros"] > 0 for r in rows) else "")  # none with AMG
        print("fitted exponents against DOFs: " + "; ".join(parts) +
              "; factorization + solve %.2f%s" % (
                  fit(d, [r["factor_and_solve"] for r in rows]), lu_fit))
        if a.amg:
            lu = [r["block_umfpack"]["lu"] for r in rows]
            amg = [r["block_amg"]["amg"] for r in rows]
            n = [r["block_umfpack"]["unknowns"] for r in rows]
            print("elastic block, exponents against its unknowns: UMFPACK factor + solve %.2f, "
                  "AMG-CG setup + solve %.2f" % (
                      fit(n, [x["factor_seconds"] + x["solve_seconds"] for x in lu]),
                      fit(n, [x["setup_seconds"] + x["solve_seconds"] for x in amg])))
    print(json.dumps(rows))


if __name__ == "__main__":
    main()
