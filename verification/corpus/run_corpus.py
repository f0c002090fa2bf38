#!/usr/bin/env python3
"""Gradient corpus: the direct sensitivity methods at default options on random mechanisms.

    run_corpus.py --lsmbs BIN --seeds A-B [--jobs 1] [--out DIR] [--resume] [--matrix M] [--no-idas] [--require-idas] [--keep]
    mpirun -np K python3 run_corpus.py --lsmbs BIN --seeds A-B --out DIR [--resume] ...

For each seed, gen_mechanisms.py (with ``--spatial``: gen_spatial.py) generates a case; the gradients of every response are computed
with ``direct-analytic``, ``semi-analytical`` and ``semi-analytical-central`` at their default
options (``--matrix M`` is passed to them only when given) and compared with

- the primary reference, ``fd-central`` on a copy of the case with a tight Newton tolerance
  (``tol_r`` 1e-12 and ``min_iter`` 2: every step takes one more Newton iteration after it has
  converged, which puts the solution at round-off whatever the absolute residual floor), at the
  relative steps Δp = 1e-2 ... 1e-6; per variable the step with the smallest estimated error is the
  reference and that estimate is the reference error (``fd_reference``). The direct methods
  differentiate the discrete generalized-α solution, and so does this reference;
- the secondary reference, ``idas`` (rtol 1e-9), which differentiates the continuous DAE: its
  gradients differ by the time-discretization error, estimated from the exact discrete gradient
  at h and at h/2 (``direct-analytic --matrix converged`` on the tight copy; second order:
  e(h) ≈ 4/3 |g_h − g_h/2|). Flagged beyond 10x (estimate + 1e-6), failed beyond 100x (on
  models with a plate only flagged: IDAS is a weak reference there, see README.md).

Metric, per response and method: max_j |g_j − g_ref,j| w_j / max_j |g_ref,j| w_j, j over the
design variables, w_j = upper_j − lower_j (the gradient in the optimizer's [0, 1] scaling; without
it the metric mixes units, e.g. kg·m² and m). Responses whose reference gradient is ~0 relative to
the value (a change of every variable over its range moves it by less than 1e-9 of its value)
are skipped. A response whose reference error estimate exceeds the method's threshold is
"reference not accurate", not a failure.

Output (``--out``, default a temporary folder that is removed unless --keep): ``results.json``
(everything), ``errors.csv`` (one row per seed, response, method and reference) and
``summary.json``; the summary is printed. Exit code 1 if any case fails, 0 otherwise.

Each seed's record is written to ``DIR/seeds/seed_NNNN.json`` as soon as the seed finishes;
``--resume`` keeps those and runs the others only (a killed campaign loses the seeds that were
running). Under ``mpirun``/``srun`` (the launcher's rank and size in the environment) every rank
takes the next seed nobody has taken (an exclusive file in ``DIR/claims/<job>/``, on the folder
the ranks share): one seed per rank at a time, the next one as it finishes. Rank 0 waits for every
seed and writes the merged files. The lsmbs runs each rank starts are plain processes (the
launcher's variables are removed from their environment). ``--jobs`` seeds at once per rank.
"""
import argparse
import concurrent.futures
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gen_mechanisms  # noqa: E402
import gen_spatial  # noqa: E402

METHODS = ["direct-analytic", "semi-analytical", "semi-analytical-central"]
# Pass thresholds on the metric against fd-central. The forward semi-analytical method perturbs
# q̇, q̈ and p by Δp (default 1e-6, relative) in rate-nonlinear elements: its error is O(Δp) and
# its coefficient grows with the state sensitivities (measured: linear in Δp; from ~1e-3 on most
# cases to above 100 % on free chains, README.md), so no fixed threshold both passes it and
# catches a wrong matrix. Its threshold is therefore 1e-5 + SA_TRUNCATION_FACTOR x its measured
# truncation |g(Δp) − g(Δp/10)| · 10/9 (a second run at Δp/10 with the same options).
THRESHOLDS = {"direct-analytic": 1e-5, "semi-analytical": 1e-5, "semi-analytical-central": 1e-5}
FD_DELTAS = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6)   # relative fd-central steps (see fd_reference)
SA_TRUNCATION_FACTOR = 2.0        # semi-analytical: threshold + 2 x its measured Δp truncation
TIGHT = {"tol_r": 1e-12, "min_iter": 2}
SKIP_REL = 1e-9                   # skip a response when max_j |g_j| s_j < SKIP_REL |value|
IDAS_FACTOR = 10.0                # IDAS flagged beyond IDAS_FACTOR x (discretization estimate + floor)
IDAS_FAIL_FACTOR = 100.0          # ... and failed beyond IDAS_FAIL_FACTOR x
IDAS_FLOOR = 1e-6


def launcher():
    """(rank, size, job key) of an MPI launch (OpenMPI's mpirun, PMI/PMIx, Slurm's srun), or
    (0, 1, None) when not launched as several processes."""
    env = os.environ
    for r, n in (("OMPI_COMM_WORLD_RANK", "OMPI_COMM_WORLD_SIZE"), ("PMIX_RANK", "PMIX_SIZE"),
                 ("PMI_RANK", "PMI_SIZE"), ("SLURM_PROCID", "SLURM_NTASKS")):
        if r in env and n in env and int(env[n]) > 1:
            # a key of this launch, the same on every rank (OpenMPI: a random 128-bit key per job)
            job = "-".join(env.get(k, "") for k in ("OMPI_MCA_orte_precondition_transports",
                                                      "PMIX_NAMESPACE", "SLURM_JOB_ID", "SLURM_STEP_ID"))
            return int(env[r]), int(env[n]), job.strip("-") or "job"
    return 0, 1, None


# the environment of the lsmbs processes: without the launcher's variables, so that an lsmbs built
# with MPI runs as the plain process it is, not as a rank of this job
CHILD_ENV = {k: v for k, v in os.environ.items()
             if not k.startswith(("OMPI_", "PMIX_", "PMI_", "SLURM_"))}


def run(cmd):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=CHILD_ENV)
    return p.returncode, (p.stderr.strip() or p.stdout.strip())


OVERWRITE = []   # ["--overwrite"] when the binary has it (set in main; folders are fresh anyway)


def sensitivity(bin_, case_file, out_dir, method, extra=()):
    cmd = [bin_, "sensitivity", case_file, "--method", method, "-o", out_dir, "-q"] + OVERWRITE + list(extra)
    t0 = time.monotonic()
    rc, msg = run(cmd)
    res = {"rc": rc, "command": " ".join(cmd[1:]), "seconds": round(time.monotonic() - t0, 3)}
    if rc != 0:
        res["message"] = msg.splitlines()[-1] if msg else ""
    summ = os.path.join(out_dir, "summary.json")
    if rc == 0 and os.path.exists(summ):
        with open(summ) as f:
            s = json.load(f)
        res["responses"] = s["responses"]
        res["gradients"] = s["gradients"]
        res["status"] = s.get("status")
        res["steps"] = s.get("counts", {}).get("steps")
    return res


def write_case(case, path):
    with open(path, "w") as f:
        json.dump(case, f, indent=1)


def fd_reference(fds, variables):
    """fd-central reference per variable from the runs at decreasing relative steps Δp_k (ratio 10).

    Central differences carry a truncation error C·Δp² at large Δp and round-off at small Δp (on
    these models not the textbook ~1/Δp: values at 1e-5 and 1e-6 scatter by the same amount). For
    each Δp_j (neither the largest nor the smallest) the error estimate is the larger of
    - truncation: the difference to the next larger step, |g_j−1 − g_j|; when the two differences
      above Δp_j fall by 30-300x (the Δp² regime confirmed on three steps) it is 3 x that / 99;
    - scatter: the difference to the next smaller step, |g_j − g_j+1| (noisy values can agree by
      chance with their larger neighbour; the smaller one shows the noise level).
    The reference is g at the Δp with the smallest estimate. Returns (ref, err, chosen) or Nones."""
    ref, err, chosen = {}, {}, {}
    for v in variables:
        vals = [(d, g[v]) for d, g in fds]
        best = None
        for j in range(1, len(vals) - 1):
            (dm, gm), (dj, gj), (dp, gp) = vals[j - 1], vals[j], vals[j + 1]
            if not (finite(gm) and finite(gj) and finite(gp)):
                continue
            trunc = abs(gm - gj)
            if j >= 2 and finite(vals[j - 2][1]):
                above = abs(vals[j - 2][1] - gm)
                if 30 * trunc <= above <= 300 * trunc:
                    trunc = 3 * trunc / 99
            e = max(trunc, abs(gj - gp))
            if best is None or e < best[0]:
                best = (e, gj, "%g" % dj)
        if best is None:
            return None, None, None
        err[v], ref[v], chosen[v] = best
    return ref, err, chosen


def finite(x):
    return isinstance(x, (int, float)) and math.isfinite(x)


def metric(g, ref, variables, w):
    """max_j |g_j - ref_j| w_j / max_j |ref_j| w_j (w_j: the variable's range, i.e. the optimizer's scaling)."""
    den = max(abs(ref[v]) * w[v] for v in variables)
    if any(not finite(g[v]) for v in variables):
        return float("inf")
    if den == 0:
        return float("inf") if any(g[v] != 0 for v in variables) else 0.0
    return max(abs(g[v] - ref[v]) * w[v] for v in variables) / den


def run_seed(seed, a):
    d = os.path.join(a.out, "cases", "seed_%04d" % seed)
    shutil.rmtree(d, ignore_errors=True)   # lsmbs refuses an output folder holding an earlier run
    os.makedirs(d)
    rec = {"seed": seed}
    try:
        case = (gen_spatial.generate(seed, solid=a.solid) if a.spatial or a.solid
                else gen_mechanisms.generate(seed, with_new_loads=a.with_new_loads))
    except Exception as e:  # a generator bug: report it as such
        rec.update({"status": "generator_error", "message": "%s: %s" % (type(e).__name__, e)})
        return rec
    if a.linear_solver:
        case["simulation"]["linear_solver"] = a.linear_solver
    rec["family"] = case["_generator"]["family"]
    rec["description"] = case["description"]
    cf = os.path.join(d, "case.json")
    write_case(case, cf)
    tight = json.loads(json.dumps(case))
    tight["simulation"].update(TIGHT)
    tf = os.path.join(d, "case_tight.json")
    write_case(tight, tf)
    variables = [v["name"] for v in case["design"]["variables"]]
    # IDAS is a weak reference on plates (unresolved elastic modes: the h/2 estimate is not
    # asymptotic, and its own gradients move by tens of % between rtol 1e-8 and 1e-9): flag only
    flexible = any(b["type"] == "flexible" for b in case["bodies"])
    w = {v["name"]: v["upper"] - v["lower"] for v in case["design"]["variables"]}
    rec["variables"] = variables
    extra = ["--matrix", a.matrix] if a.matrix else []
    runs = {}
    for m in METHODS:  # --matrix is an option of the direct methods (the others refuse it)
        direct = m in ("semi-analytical", "semi-analytical-central", "direct-analytic")
        runs[m] = sensitivity(a.lsmbs, cf, os.path.join(d, m), m, extra if direct else [])
    # the forward method's Δp truncation: the same at Δp/10 (its error is linear in Δp)
    runs["semi-analytical@1e-7"] = sensitivity(a.lsmbs, cf, os.path.join(d, "sa_small"), "semi-analytical",
                                               extra + ["--delta", "1e-7"])
    for dp in FD_DELTAS:
        runs["fd-central@%g" % dp] = sensitivity(a.lsmbs, tf, os.path.join(d, "fd_%g" % dp), "fd-central",
                                                 ["--delta", "%g" % dp, "--threads", "1"])
    if not a.no_idas:
        runs["idas"] = sensitivity(a.lsmbs, cf, os.path.join(d, "idas"), "idas", ["--threads", "1"])
        half = json.loads(json.dumps(tight))
        half["simulation"]["h"] = case["simulation"]["h"] / 2
        hf = os.path.join(d, "case_half_h.json")
        write_case(half, hf)
        runs["exact@h"] = sensitivity(a.lsmbs, tf, os.path.join(d, "exact_h"), "direct-analytic",
                                      ["--matrix", "converged", "--threads", "1"])
        runs["exact@h/2"] = sensitivity(a.lsmbs, hf, os.path.join(d, "exact_h2"), "direct-analytic",
                                        ["--matrix", "converged", "--threads", "1"])
    rec["runs"] = {k: {x: v[x] for x in ("rc", "message", "command", "steps", "seconds")
                          if x in v} for k, v in runs.items()}
    failures = []
    for k, v in runs.items():
        if v["rc"] != 0:
            rec.setdefault("run_failures", []).append("%s: exit %d: %s" % (k, v["rc"], v.get("message", "")))
    rows = []
    fd_keys = ["fd-central@%g" % dp for dp in FD_DELTAS]
    for m in METHODS:
        if runs[m]["rc"] != 0:
            failures.append("%s exited with %d: %s" % (m, runs[m]["rc"], runs[m].get("message", "")))
    if a.require_idas and "idas" in runs and runs["idas"]["rc"] != 0:
        failures.append("idas exited with %d: %s" % (runs["idas"]["rc"], runs["idas"].get("message", "")))
    for k, v in runs.items():   # invalid input or usage (exit 2) is never a numerical limitation
        if v["rc"] == 2 and k not in METHODS:
            failures.append("%s exited with 2: %s" % (k, v.get("message", "")))
    if any(runs[k]["rc"] != 0 for k in fd_keys):
        rec["failures"] = failures
        rec["status"] = "FAIL" if failures else "reference_failed"
        finish(rec, a, d)
        return rec
    base = runs[fd_keys[0]]
    rec["responses"] = {}
    for rname in sorted(base["gradients"]):
        value = base["responses"][rname]
        if isinstance(value, list):
            continue
        fds = [(dp, runs["fd-central@%g" % dp]["gradients"][rname]) for dp in FD_DELTAS]
        ref, ref_e, chosen = fd_reference(fds, variables)
        r = {"value": value}
        if ref is None:
            r["status"] = "reference not finite"
            rec["responses"][rname] = r
            continue
        sens = max(abs(ref[v]) * w[v] for v in variables)
        r.update({"reference": ref, "fd_pairs": chosen, "sensitivity": sens})
        if not sens > SKIP_REL * abs(value) or sens == 0:
            r["status"] = "skipped (gradient ~0)"
            rec["responses"][rname] = r
            rows.append({"seed": seed, "family": rec["family"], "response": rname, "method": "", "reference": "",
                         "error": "", "threshold": "", "ref_error": "", "status": r["status"]})
            continue
        ref_err = max(ref_e[v] * w[v] for v in variables) / sens
        r["ref_error"] = ref_err
        r["errors"] = {}
        trunc = None
        if runs["semi-analytical"]["rc"] == 0 and runs["semi-analytical@1e-7"]["rc"] == 0:
            g1, g2 = runs["semi-analytical"]["gradients"][rname], runs["semi-analytical@1e-7"]["gradients"][rname]
            trunc = 10.0 / 9.0 * metric(g1, g2, variables, w) * max(abs(g2[v]) * w[v] for v in variables) / sens \
                if all(finite(g2[v]) for v in variables) else float("inf")
            r["semi_analytical_truncation"] = trunc
        for m in METHODS:
            if runs[m]["rc"] != 0:
                continue
            g = runs[m]["gradients"][rname]
            e = metric(g, ref, variables, w)
            thr = THRESHOLDS[m]
            if m == "semi-analytical":
                thr = thr + SA_TRUNCATION_FACTOR * (trunc if trunc is not None else 0.0)
            if ref_err > THRESHOLDS[m]:
                st = "reference not accurate"
            elif not e <= thr:
                st = "FAIL"
                failures.append("%s %s: error %.3g > %.2g (fd reference error %.2g)" % (m, rname, e, thr, ref_err))
            else:
                st = "pass"
            r["errors"][m] = {"error": e, "threshold": thr, "status": st,
                              "error_unscaled": metric(g, ref, variables, {v: 1.0 for v in variables})}
            rows.append({"seed": seed, "family": rec["family"], "response": rname, "method": m,
                         "reference": "fd-central", "error": "%.3e" % e, "threshold": "%.2e" % thr,
                         "ref_error": "%.3e" % ref_err, "status": st})
        # secondary: IDAS, with the discretization error estimate
        if not a.no_idas and runs["idas"]["rc"] == 0 and runs["exact@h"]["rc"] == 0 \
                and runs["exact@h/2"]["rc"] == 0:
            gi = runs["idas"]["gradients"][rname]
            gh, gh2 = runs["exact@h"]["gradients"][rname], runs["exact@h/2"]["gradients"][rname]
            disc = 4.0 / 3.0 * metric(gh2, gh, variables, w)
            vi = runs["idas"]["responses"][rname]
            r["idas"] = {"discretization_estimate": disc,
                         "value_difference": abs(value - vi) / max(abs(value), 1e-300),
                         "exact_vs_idas": metric(gh, gi, variables, w), "errors": {}}
            for m in METHODS:
                if runs[m]["rc"] != 0:
                    continue
                extra_tol = SA_TRUNCATION_FACTOR * trunc if (m == "semi-analytical" and trunc is not None) else 0.0
                tol = IDAS_FACTOR * (disc + IDAS_FLOOR) + extra_tol
                e = metric(runs[m]["gradients"][rname], gi, variables, w)
                st = "pass" if e <= tol else ("FAIL" if not flexible and not
                                              e <= IDAS_FAIL_FACTOR * (disc + IDAS_FLOOR) + extra_tol
                                              else "idas disagrees")
                if st == "FAIL":
                    failures.append("%s %s: differs from IDAS by %.3g, discretization estimate %.2g"
                                    % (m, rname, e, disc))
                r["idas"]["errors"][m] = {"error": e, "tolerance": tol, "status": st}
                rows.append({"seed": seed, "family": rec["family"], "response": rname, "method": m,
                             "reference": "idas", "error": "%.3e" % e, "threshold": "%.1e" % tol,
                             "ref_error": "%.3e" % disc, "status": st})
        rec["responses"][rname] = r
    rec["rows"] = rows
    rec["failures"] = failures
    rec["status"] = "FAIL" if failures else "pass"
    finish(rec, a, d)
    return rec


def seed_file(a, seed):
    return os.path.join(a.out, "seeds", "seed_%04d.json" % seed)


def write_atomic(path, data):
    tmp = "%s.%d.tmp" % (path, os.getpid())
    with open(tmp, "w") as f:
        json.dump(data, f, indent=1)
    os.replace(tmp, path)


def say_seed(r, a):
    if a.quiet:
        return
    worst = max([e["error"] for x in r.get("responses", {}).values()
                 for m, e in x.get("errors", {}).items() if m == "direct-analytic"] or [float("nan")])
    print("seed %4d %-13s %-16s direct-analytic worst %.2e%s" % (
        r["seed"], r.get("family", "?"), r.get("status"), worst,
        ("  " + "; ".join(r["failures"][:2])) if r.get("failures") else ""), flush=True)


def run_seeds(seeds, a, rank, size, job):
    """Every seed's record, each written as it finishes (rank 0: every seed's, once all ranks
    have written theirs; another rank: None once no seed is left to take)."""
    os.makedirs(os.path.join(a.out, "seeds"), exist_ok=True)
    earlier = {}
    for s in seeds:
        if os.path.exists(seed_file(a, s)):
            with open(seed_file(a, s)) as f:
                r = json.load(f)
            if r.get("job") != job or job is None:
                earlier[s] = r
    if earlier and not a.resume:
        print("run_corpus: --out %s holds the results of an earlier run (seeds %s...): --resume to "
              "keep them, or another --out" % (a.out, ", ".join(str(s) for s in sorted(earlier)[:5])),
              file=sys.stderr)
        sys.exit(2)
    todo = [s for s in seeds if s not in earlier]
    claims = os.path.join(a.out, "claims", job) if job else None
    if claims:
        os.makedirs(claims, exist_ok=True)

    def take(s):  # this rank runs seed s, unless another rank took it
        if not claims:
            return True
        try:
            os.close(os.open(os.path.join(claims, "seed_%04d" % s), os.O_CREAT | os.O_EXCL | os.O_WRONLY))
            return True
        except FileExistsError:
            return False

    def work(s):
        if not take(s):
            return None
        r = run_seed(s, a)
        r["job"], r["rank"] = job, rank
        write_atomic(seed_file(a, s), r)
        return r

    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as ex:
        for r in ex.map(work, todo):
            if r is not None:
                say_seed(r, a)
    if rank != 0:
        return None
    recs = {}
    for s in seeds:  # rank 0: the other ranks' seeds, as they finish them
        while not os.path.exists(seed_file(a, s)):
            time.sleep(0.2)
        with open(seed_file(a, s)) as f:
            recs[s] = json.load(f)
        recs[s]["finished_before"] = s in earlier
    return recs


def finish(rec, a, d):
    if not a.keep:
        for x in os.listdir(d):
            p = os.path.join(d, x)
            if os.path.isdir(p):
                shutil.rmtree(p, ignore_errors=True)


def parse_seeds(s):
    out = []
    for part in s.split(","):
        if "-" in part:
            lo, hi = part.split("-")
            out.extend(range(int(lo), int(hi) + 1))
        else:
            out.append(int(part))
    return out


def percentile(xs, q):
    if not xs:
        return float("nan")
    xs = sorted(xs)
    k = (len(xs) - 1) * q
    f = math.floor(k)
    c = min(f + 1, len(xs) - 1)
    return xs[f] + (xs[c] - xs[f]) * (k - f)


def summarize(recs, a):
    s = {"cases": len(recs), "matrix": a.matrix or "default", "thresholds": THRESHOLDS,
         "fd_deltas": FD_DELTAS, "tight": TIGHT, "sa_truncation_factor": SA_TRUNCATION_FACTOR, "methods": {}}
    s["failed_cases"] = [r["seed"] for r in recs if r.get("status") == "FAIL"]
    s["reference_failed"] = [r["seed"] for r in recs if r.get("status") == "reference_failed"]
    s["generator_errors"] = [r["seed"] for r in recs if r.get("status") == "generator_error"]
    s["run_failures"] = {r["seed"]: r["run_failures"] for r in recs if r.get("run_failures")}
    n_resp = n_skip = n_refbad = 0
    ref_errs = []
    for r in recs:
        for rn, x in r.get("responses", {}).items():
            n_resp += 1
            if "errors" not in x:
                n_skip += 1
                continue
            ref_errs.append(x["ref_error"])
            if x["ref_error"] > min(THRESHOLDS.values()):
                n_refbad += 1
    s["responses"] = {"compared": n_resp - n_skip, "skipped_zero_gradient": n_skip,
                      "reference_not_accurate": n_refbad,
                      "fd_reference_error": {"median": percentile(ref_errs, 0.5), "p99": percentile(ref_errs, 0.99),
                                             "max": max(ref_errs) if ref_errs else None}}
    for m in METHODS:
        errs, worst, idas_errs, worst_i = [], None, [], None
        n_fail = n_fail_cases = 0
        n_idas_flag = n_idas_fail = 0
        for r in recs:
            case_failed = False
            for rn, x in r.get("responses", {}).items():
                e = x.get("errors", {}).get(m)
                if e and e["status"] != "reference not accurate":
                    errs.append(e["error"])
                    if worst is None or e["error"] > worst[0]:
                        worst = (e["error"], r["seed"], rn)
                    if e["status"] == "FAIL":
                        n_fail += 1
                        case_failed = True
                ie = x.get("idas", {}).get("errors", {}).get(m)
                if ie:
                    ratio = ie["error"] / (x["idas"]["discretization_estimate"] + IDAS_FLOOR)
                    idas_errs.append(ratio)
                    if worst_i is None or ratio > worst_i[0]:
                        worst_i = (ratio, r["seed"], rn, ie["error"])
                    n_idas_flag += ie["status"] != "pass"
                    n_idas_fail += ie["status"] == "FAIL"
            n_fail_cases += case_failed
        s["methods"][m] = {
            "threshold": THRESHOLDS[m], "responses": len(errs),
            "median": percentile(errs, 0.5), "p99": percentile(errs, 0.99),
            "worst": {"error": worst[0], "seed": worst[1], "response": worst[2]} if worst else None,
            "responses_failed": n_fail, "cases_failed": n_fail_cases,
            "idas": {"ratio_to_discretization_median": percentile(idas_errs, 0.5),
                     "ratio_p99": percentile(idas_errs, 0.99),
                     "worst": {"ratio": worst_i[0], "seed": worst_i[1], "response": worst_i[2],
                               "error": worst_i[3]} if worst_i else None,
                     "flagged": n_idas_flag, "failed": n_idas_fail}}
    return s


def print_summary(s, out=sys.stdout):
    p = lambda *x: print(*x, file=out)  # noqa: E731
    p("gradient corpus: %d cases, matrix %s; fd-central reference (tight Newton; relative Δp %s, per variable the "
      "one with the smallest error estimate)" % (s["cases"], s["matrix"], ", ".join("%g" % x for x in s["fd_deltas"])))
    rs = s["responses"]
    p("responses compared %d, skipped (zero gradient) %d, reference not accurate %d; fd reference error median "
      "%.2g, p99 %.2g, max %s" % (rs["compared"], rs["skipped_zero_gradient"], rs["reference_not_accurate"],
                                  rs["fd_reference_error"]["median"], rs["fd_reference_error"]["p99"],
                                  "%.2g" % rs["fd_reference_error"]["max"] if rs["fd_reference_error"]["max"]
                                  is not None else "-"))
    p("%-24s %9s %10s %10s %10s  %-40s %s" % ("method", "threshold", "median", "p99", "worst", "(seed, response)",
                                               "failed responses / cases"))
    for m, x in s["methods"].items():
        w = x["worst"]
        p("%-24s %9.0e %10.2e %10.2e %10.2e  %-40s %d / %d" % (
            m, x["threshold"], x["median"], x["p99"], w["error"] if w else float("nan"),
            ("(%d, %s)" % (w["seed"], w["response"])) if w else "", x["responses_failed"], x["cases_failed"]))
    for m, x in s["methods"].items():
        i = x["idas"]
        if i["worst"]:
            p("  vs IDAS %-24s error / discretization estimate: median %.2g, p99 %.2g, worst %.3g (seed %d, %s: "
              "error %.2g); flagged %d, failed %d" % (m, i["ratio_to_discretization_median"], i["ratio_p99"],
                                                      i["worst"]["ratio"], i["worst"]["seed"], i["worst"]["response"],
                                                      i["worst"]["error"], i["flagged"], i["failed"]))
    if s["run_failures"]:
        p("runs that exited non-zero:")
        for seed, msgs in sorted(s["run_failures"].items()):
            for m in msgs:
                p("  seed %d: %s" % (seed, m))
    if s["generator_errors"]:
        p("generator errors: %s" % s["generator_errors"])
    if s["reference_failed"]:
        p("reference failed (not counted): %s" % s["reference_failed"])
    p("FAILED cases: %d %s" % (len(s["failed_cases"]), s["failed_cases"] if s["failed_cases"] else ""))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--lsmbs", required=True, help="lsmbs binary")
    ap.add_argument("--seeds", required=True, help="A-B, or a comma list of seeds and ranges")
    ap.add_argument("--jobs", type=int, default=1, help="cases run in parallel (default 1)")
    ap.add_argument("--out", help="output folder (default: a temporary folder, removed unless --keep)")
    ap.add_argument("--matrix", choices=["last", "converged", "refined"],
                    help="passed to the direct methods (default: not passed, i.e. lsmbs's default)")
    ap.add_argument("--no-idas", action="store_true", help="skip the secondary IDAS reference")
    ap.add_argument("--require-idas", action="store_true",
                    help="an IDAS run that fails fails the case (default: reported only)")
    ap.add_argument("--keep", action="store_true", help="keep every lsmbs output folder")
    ap.add_argument("--resume", action="store_true",
                    help="keep the seeds already written in OUT/seeds/ and run the others")
    ap.add_argument("--with-new-loads", action="store_true", help="generate torque / rotational spring loads")
    ap.add_argument("--spatial", action="store_true",
                    help="spatial mechanisms (gen_spatial.py: chains, slider-cranks, pendulums)")
    ap.add_argument("--solid", action="store_true",
                    help="spatial mechanisms with a flexible 3D solid body (gen_spatial.py --solid: "
                         "cantilevers, arms with a drilled plate, pendulums)")
    ap.add_argument("--linear-solver", choices=["auto", "klu", "umfpack", "amg"],
                    help="every case's \"simulation\": {\"linear_solver\"} (default: the "
                         "generator's, i.e. auto)")
    ap.add_argument("-q", "--quiet", action="store_true", help="print only the summary")
    a = ap.parse_args(argv)
    a.lsmbs = os.path.abspath(a.lsmbs)
    if not os.access(a.lsmbs, os.X_OK):
        ap.error("--lsmbs %s: not an executable" % a.lsmbs)
    rc, text = run([a.lsmbs, "sensitivity", "--help"])
    if "--overwrite" in text:
        OVERWRITE.append("--overwrite")
    temp = a.out is None
    if temp:
        a.out = tempfile.mkdtemp(prefix="lsmbs_corpus_")
    os.makedirs(a.out, exist_ok=True)
    seeds = parse_seeds(a.seeds)
    rank, size, job = launcher()
    if size > 1 and temp:
        ap.error("under mpirun every rank writes into one folder: give --out (on a file system "
                 "the ranks share)")
    recs = run_seeds(seeds, a, rank, size, job)
    if recs is None:  # a rank other than 0: its seeds are written; rank 0 merges
        return 0
    recs = [recs[s] for s in seeds]
    s = summarize(recs, a)
    s["seeds_finished_before"] = sum(1 for r in recs if r.get("finished_before"))
    s["ranks"] = size
    with open(os.path.join(a.out, "results.json"), "w") as f:
        json.dump({"summary": s, "cases": recs}, f, indent=1)
    with open(os.path.join(a.out, "errors.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, ["seed", "family", "response", "method", "reference", "error", "threshold",
                               "ref_error", "status"])
        w.writeheader()
        for r in recs:
            for row in r.get("rows", []):
                w.writerow(row)
    with open(os.path.join(a.out, "summary.json"), "w") as f:
        json.dump(s, f, indent=1)
    print_summary(s)
    if temp and not a.keep:
        shutil.rmtree(a.out, ignore_errors=True)
    else:
        print("outputs in", a.out)
    return 1 if s["failed_cases"] else 0


if __name__ == "__main__":
    sys.exit(main())
