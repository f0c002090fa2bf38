#!/usr/bin/env python3
"""Adjoint corpus: the discrete adjoint against direct-analytic on generated mechanisms.

    adjoint_corpus.py --lsmbs BIN --seeds A-B [--with-new-loads] [--threshold 1e-9] [--jobs 1] [-q]

For each seed, gen_mechanisms.py generates a case (the gradient corpus's pendulum chains,
four-bars, slider-cranks, two-loop linkages and flexible plates with a level-set hole). Every
scalar aggregate is added on the case's first responses' measures (average_eq45, rms, max, min,
ks, some in a window), so that each backward source (aggregation weights) is exercised. Then
``lsmbs sensitivity --method direct-analytic,adjoint`` runs both methods on the same discrete
solution: the forward recurrence of Algorithm 2 and its transpose compute the same derivatives in
another order, so they must agree to round-off: to the threshold (1e-9), or, where the problem
amplifies round-off beyond it, to 3 x the spread of direct-analytic against itself with another
exact back-solve (``--matrix refined``: the same derivative, other round-off); such responses are
listed. direct-analytic itself is checked against central
finite differences on the same seeds by run_corpus.py (ctest gradient_corpus).

Metric, per response: max_j |g_adj,j − g_dir,j| w_j / max_j |g_dir,j| w_j, w_j the variable's range
(run_corpus.py's metric); responses whose gradient is ~0 relative to their value (a change of every
variable over its range moves it by less than 1e-9 of it) are skipped. Exit 1 if a case fails.
"""
import argparse
import concurrent.futures
import json
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gen_mechanisms  # noqa: E402
from run_corpus import metric, parse_seeds, SKIP_REL, write_case  # noqa: E402

EXTRA = ("average_eq45", "rms", "max", "min", "ks")
FLOOR_FACTOR = 3.0   # a response beyond the threshold passes within 3 x the direct method's spread


def add_aggregates(case):
    """Every scalar aggregate on the measures of the first two responses (ks with the weight of an
    existing ks response or 20 per unit of the measure's range; windows on the second half)."""
    resp = case["output"]["responses"]
    t_end = case["simulation"]["t_end"]
    names = {r["name"] for r in resp}
    for base in resp[:2]:
        for k, agg in enumerate(EXTRA):
            name = "x_%s_%s" % (agg, base["name"])
            if name in names:
                continue
            r = {"name": name, "measure": base["measure"], "aggregate": agg}
            if agg == "ks":
                r["ks"] = 20.0
            if k % 2 == 1:
                r["window"] = {"t0": round(0.5 * t_end, 9), "t1": t_end}
            resp.append(r)
            names.add(name)


def run_seed(seed, a):
    case = gen_mechanisms.generate(seed, with_new_loads=a.with_new_loads)
    add_aggregates(case)
    d = os.path.join(a.out, "seed_%04d" % seed)
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    path = os.path.join(d, "case.json")
    write_case(case, path)
    out = os.path.join(d, "out")
    cmd = [a.lsmbs, "sensitivity", path, "--method", "direct-analytic,adjoint", "-o", out, "-q"]
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    rec = {"seed": seed, "family": case["_generator"]["family"], "responses": {}, "failures": []}
    if p.returncode != 0:
        msg = (p.stderr.strip() or p.stdout.strip()).splitlines()
        # a mechanism the primal cannot integrate is run_corpus.py's concern, not the adjoint's
        rec["status"] = "not run (rc %d: %s)" % (p.returncode, msg[-1] if msg else "")
        if p.returncode == 2 or "adjoint" in " ".join(msg):
            rec["failures"].append(rec["status"])
        return rec
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    m = s["methods"]
    if m["adjoint"].get("status") != "complete":
        rec["failures"].append("adjoint: " + str(m["adjoint"].get("status")))
        return rec
    variables = [v["name"] for v in case["design"]["variables"]]
    w = {v["name"]: v["upper"] - v["lower"] for v in case["design"]["variables"]}
    # the round-off floor: direct-analytic with another exact back-solve (iterative refinement
    # instead of a fresh factorization) differs from itself by round-off amplified by the problem
    out2 = os.path.join(d, "out_refined")
    p2 = subprocess.run([a.lsmbs, "sensitivity", path, "--method", "direct-analytic", "--matrix",
                         "refined", "-o", out2, "-q"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                        text=True)
    refined = None
    if p2.returncode == 0:
        with open(os.path.join(out2, "summary.json")) as f:
            refined = json.load(f)["gradients"]
    for r, gd in m["direct-analytic"]["gradients"].items():
        ga = m["adjoint"]["gradients"][r]
        value = s["responses"][r]
        if max(abs(gd[v]) * w[v] for v in variables) < SKIP_REL * abs(value):
            rec["responses"][r] = {"skipped": "gradient ~0"}
            continue
        e = metric(ga, gd, variables, w)
        floor = metric(refined[r], gd, variables, w) if refined else 0.0
        rec["responses"][r] = {"error": e, "floor": floor}
        # pass: within the threshold, or within FLOOR_FACTOR x the direct method's own spread
        if not (e <= a.threshold or e <= FLOOR_FACTOR * floor):
            rec["failures"].append("%s: %.2e (floor %.2e)" % (r, e, floor))
        elif e > a.threshold:
            rec.setdefault("above_threshold", []).append("%s: %.2e (floor %.2e)" % (r, e, floor))
    rec["status"] = "failed" if rec["failures"] else "ok"
    return rec


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--lsmbs", required=True)
    ap.add_argument("--seeds", required=True, help="A-B, or a comma list of seeds and ranges")
    ap.add_argument("--with-new-loads", action="store_true")
    ap.add_argument("--threshold", type=float, default=1e-9)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--out", help="output folder (default: a temporary folder, removed)")
    ap.add_argument("-q", "--quiet", action="store_true")
    a = ap.parse_args(argv)
    a.lsmbs = os.path.abspath(a.lsmbs)
    temp = a.out is None
    a.out = a.out or tempfile.mkdtemp(prefix="lsmbs_adjoint_corpus_")
    os.makedirs(a.out, exist_ok=True)
    seeds = parse_seeds(a.seeds)
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as ex:
        recs = list(ex.map(lambda s: run_seed(s, a), seeds))
    errors = [x["error"] for r in recs for x in r["responses"].values() if "error" in x]
    failed = [r for r in recs if r["failures"]]
    for r in recs:
        if not a.quiet or r["failures"]:
            worst = max([x["error"] for x in r["responses"].values() if "error" in x] or [float("nan")])
            print("seed %4d %-13s %-10s worst %.2e %s" % (r["seed"], r["family"], r.get("status"), worst,
                                                        "; ".join((r["failures"] + r.get("above_threshold", []))[:3])))
    not_run = sum(1 for r in recs if r.get("status", "").startswith("not run"))
    print("adjoint vs direct-analytic: %d seeds (%d not run by the primal), %d responses compared, "
          "worst %.2e, median %.2e; threshold %.0e; %d failed" % (
              len(recs), not_run, len(errors), max(errors or [float("nan")]),
              sorted(errors)[len(errors) // 2] if errors else float("nan"), a.threshold, len(failed)))
    with open(os.path.join(a.out, "results.json"), "w") as f:
        json.dump(recs, f, indent=1)
    if temp:
        shutil.rmtree(a.out, ignore_errors=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
