#!/usr/bin/env python3
"""Randomized fault injection: SIGKILL and SIGINT at seeded random moments of `lsmbs simulate` and
`lsmbs optimize`, then `optimize --resume` (issue 19).

    fault_injection.py --lsmbs BIN [--seed S] [--sim-trials N] [--opt-trials N] [-v]

Cases (small settings of shipped cases): the coarse connecting rod of the slider-crank
(data/slider_crank/slider_crank_1hole_coarse.json, 80 steps, VTU every 10 steps) for simulate; the
robot arm with a 30x3 plate (data/robot_arm/robot_arm_holes.json, h = 10 ms, 10 evaluations) for
optimize. Each is first run once without interruption: the reference.

Each trial starts the command in a fresh folder, or with --overwrite over a folder holding an
earlier run of another case, waits a seeded random delay in [0, 1.2 x the reference's duration],
sends SIGKILL or SIGINT, and checks the folder. Whenever the signal lands — before the run
started, during the load, a step, an evaluation, the final writing, or after the end — these must
hold (so the test does not depend on the machine's speed):

  * a summary.json whose status is "complete" belongs to this run and the run is complete and
    consistent: the files it lists exist and are not empty, the PVD's VTU files exist, and the
    results equal the reference's (history.csv identical; for optimize the history without the
    wall-time column, the final and initial designs and objectives, the checkpoint's evaluations
    as many as history rows);
  * otherwise summary.json is absent or says "partial" / "interrupted" (never an earlier run's);
  * exit codes: SIGINT ends with 130 and a partial / interrupted summary (0 if the run had
    finished; death by the signal only before the handlers are installed, with no summary of this
    run); SIGKILL with -9 (or 0).

After an interrupted optimize, `optimize --resume` (itself interrupted once more in a third of the
trials, then resumed again) must end complete with exactly the reference's design, objective,
initial summary and history. Resuming without a checkpoint is refused (exit 2, message naming the
checkpoint). Damaged checkpoints (truncated, wrong sizes, deeply nested) are refused with exit 2.
Exit status 1 when an invariant fails.
"""
import argparse
import json
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time


def fail(msg):
    raise AssertionError(msg)


def load(path):
    with open(path) as f:
        return json.load(f)


def history_rows(path, drop_wall=True):
    lines = [l.split(",") for l in open(path).read().splitlines() if l]
    if drop_wall and lines and "wall_seconds" in lines[0]:
        i = lines[0].index("wall_seconds")
        lines = [l[:i] + l[i + 1:] for l in lines]
    return lines


def make_cases(root, work):
    sim = load(os.path.join(root, "data/slider_crank/slider_crank_1hole_coarse.json"))
    for b in sim["bodies"]:
        if "mesh" in b and b["mesh"].get("type") == "gmsh":
            b["mesh"]["file"] = os.path.join(root, "data/slider_crank", b["mesh"]["file"])
    for f in sim.get("forces", []):
        if "table" in f and "file" in f["table"]:
            f["table"]["file"] = os.path.join(root, "data/slider_crank", f["table"]["file"])
    sim["simulation"]["t_end"] = 80 * sim["simulation"]["h"]
    sim["output"]["vtu_stride"] = 10
    opt = load(os.path.join(root, "data/robot_arm/robot_arm_holes.json"))
    opt["bodies"][2]["mesh"]["elements"] = [30, 3]
    opt["simulation"]["h"] = 0.01
    opt["output"]["vtu_stride"] = 0
    opt["optimization"]["stop"]["max_evaluations"] = 10
    other = load(os.path.join(root, "data/slider_crank_rigid/slider_crank_spring.json"))
    paths = {}
    for name, c in (("sim", sim), ("opt", opt), ("other", other)):
        paths[name] = os.path.join(work, f"{name}.json")
        with open(paths[name], "w") as f:
            json.dump(c, f, indent=1)
    return paths


def run(exe, args, timeout=600):
    t0 = time.monotonic()
    p = subprocess.run([exe] + args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, timeout=timeout)
    return p.returncode, p.stderr.decode(errors="replace"), time.monotonic() - t0


def run_and_signal(exe, args, delay, sig):
    p = subprocess.Popen([exe] + args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        p.wait(timeout=delay)
    except subprocess.TimeoutExpired:
        p.send_signal(sig)
    _, err = p.communicate(timeout=600)
    return p.returncode, err.decode(errors="replace")


def check_files(out, S):
    files = S.get("files") or []
    for v in files.values() if isinstance(files, dict) else files:  # a list since issue 23
        if isinstance(v, str):
            p = os.path.join(out, v)
            if not os.path.exists(p) or (os.path.isfile(p) and os.path.getsize(p) == 0):
                fail(f"{out}: complete summary lists {v}, missing or empty")
    for f in os.listdir(out):
        if f.endswith(".pvd"):
            for v in re.findall(r'file="([^"]+)"', open(os.path.join(out, f)).read()):
                p = os.path.join(out, v)
                if not os.path.isfile(p) or os.path.getsize(p) == 0:
                    fail(f"{out}: {f} lists {v}, missing or empty")


def check_folder(out, kind, ref, case_name, rc, sig, err):
    """The invariant on a folder after a signal; returns the summary status (or None)."""
    sp = os.path.join(out, "summary.json")
    S = load(sp) if os.path.isfile(sp) else None
    status = S.get("status") if S else None
    if S is not None and S.get("case_name") != case_name:
        fail(f"{out}: summary.json of another run ({S.get('case_name')}) after {sig.name}")
    if status == "complete":
        check_files(out, S)
        if kind == "sim":
            if open(os.path.join(out, "history.csv")).read() != open(os.path.join(ref, "history.csv")).read():
                fail(f"{out}: complete, but history.csv differs from the uninterrupted run's")
            R = load(os.path.join(ref, "summary.json"))
            if S["responses"] != R["responses"]:
                fail(f"{out}: complete, but responses differ: {S['responses']} vs {R['responses']}")
        else:
            check_optimize_equal(out, ref)
    elif status is not None and status not in ("partial", "interrupted"):
        fail(f"{out}: summary status {status!r} after {sig.name}")
    reported = [x for v in ((S or {}).get("responses") or {}).values()
                for x in (v if isinstance(v, list) else [v]) if x is not None]  # per-step: arrays
    if status == "partial" and kind == "sim" and reported:
        fail(f"{out}: a partial simulation reports responses {S['responses']}")
    # exit codes
    if "internal error" in err:
        fail(f"{out}: internal error after {sig.name}: {err}")
    if rc == 0:
        if status != "complete":
            fail(f"{out}: exit 0 with summary status {status!r}")
    elif sig == signal.SIGINT:
        if rc == 130:
            if status not in ("partial", "interrupted"):
                fail(f"{out}: exit 130 with summary status {status!r}")
        elif rc == -signal.SIGINT:  # the signal came before the handlers were installed (load)
            if status is not None:
                fail(f"{out}: ended by SIGINT during the load, yet summary {status!r}")
        else:
            fail(f"{out}: SIGINT gave exit {rc}: {err}")
    elif rc != -signal.SIGKILL:
        fail(f"{out}: SIGKILL gave exit {rc}: {err}")
    return status


def check_optimize_equal(out, ref):
    S, R = load(os.path.join(out, "summary.json")), load(os.path.join(ref, "summary.json"))
    if S["status"] != "complete":
        fail(f"{out}: status {S['status']}")
    for key in ("final", "initial"):
        if S[key] != R[key]:
            fail(f"{out}: {key} differs from the uninterrupted run: {S[key]} vs {R[key]}")
    a, b = history_rows(os.path.join(out, "history.csv")), history_rows(os.path.join(ref, "history.csv"))
    if a != b:
        fail(f"{out}: history.csv differs from the uninterrupted run's ({len(a) - 1} vs {len(b) - 1} rows)")
    n = len(a) - 1
    if S["counts"]["evaluations"] != n:
        fail(f"{out}: {S['counts']['evaluations']} evaluations in the summary, {n} history rows")
    cp = load(os.path.join(out, "checkpoint.json"))
    if len(cp["evaluations"]) != n:
        fail(f"{out}: {len(cp['evaluations'])} evaluations in the checkpoint, {n} history rows")
    check_files(out, S)


def damaged_checkpoints(exe, case, ref, work, verbose):
    """A damaged checkpoint is refused with exit 2 and a message naming it."""
    cp = load(os.path.join(ref, "checkpoint.json"))
    text = json.dumps(cp)
    bad_sizes = json.loads(text)
    bad_sizes["evaluations"][0]["p"] = bad_sizes["evaluations"][0]["p"][:1]
    bad_rows = json.loads(text)
    bad_rows["evaluations"][0]["rows"] = -3
    bad_hex = json.loads(text)
    bad_hex["evaluations"][0]["objective"] = "zz"
    no_evals = json.loads(text)
    del no_evals["evaluations"]
    variants = {"truncated": text[: len(text) // 2], "sizes": json.dumps(bad_sizes), "rows": json.dumps(bad_rows),
                "hex": json.dumps(bad_hex), "no_evaluations": json.dumps(no_evals),
                "deep": "[" * 100000 + "]" * 100000, "not_object": "[1, 2]"}
    bad = []
    for name, content in variants.items():
        out = os.path.join(work, f"damaged_{name}")
        shutil.copytree(ref, out)
        with open(os.path.join(out, "checkpoint.json"), "w") as f:
            f.write(content)
        rc, err, _ = run(exe, ["optimize", case, "-o", out, "--resume", "-q"])
        if rc != 2 or "checkpoint.json" not in err:
            bad.append(f"{name} (exit {rc}: {err.strip()[:200]})")
        if verbose:
            print(f"  damaged checkpoint ({name}): exit {rc}: {err.strip()[:150]}")
    if bad:
        fail(f"damaged checkpoints not refused with exit 2: {'; '.join(bad)}")
    return len(variants)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--lsmbs", required=True)
    ap.add_argument("--root", default=os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--sim-trials", type=int, default=8)
    ap.add_argument("--opt-trials", type=int, default=6)
    ap.add_argument("--keep", action="store_true", help="keep the work folder")
    ap.add_argument("-v", "--verbose", action="store_true")
    a = ap.parse_args()
    exe = os.path.abspath(a.lsmbs)
    rng = random.Random(a.seed)
    work = tempfile.mkdtemp(prefix="lsmbs_faults_")
    tally = {}
    try:
        cases = make_cases(os.path.abspath(a.root), work)
        ref = {"sim": os.path.join(work, "ref_sim"), "opt": os.path.join(work, "ref_opt")}
        rc, err, t_sim = run(exe, ["simulate", cases["sim"], "-o", ref["sim"], "-q"])
        if rc:
            fail(f"reference simulate: exit {rc}: {err}")
        rc, err, t_opt = run(exe, ["optimize", cases["opt"], "-o", ref["opt"], "-q", "--no-check"])
        if rc:
            fail(f"reference optimize: exit {rc}: {err}")
        if a.verbose:
            print(f"references: simulate {t_sim:.2f} s, optimize {t_opt:.2f} s")
        names = {"sim": load(os.path.join(ref["sim"], "summary.json"))["case_name"],
                 "opt": load(os.path.join(ref["opt"], "summary.json"))["case_name"]}
        trials = [("sim", i) for i in range(a.sim_trials)] + [("opt", i) for i in range(a.opt_trials)]
        for kind, i in trials:
            sig = rng.choice([signal.SIGKILL, signal.SIGINT])
            delay = rng.uniform(0, 1.2 * (t_sim if kind == "sim" else t_opt))
            over_earlier = rng.random() < 0.5
            out = os.path.join(work, f"{kind}_{i}")
            extra = []
            if over_earlier:  # an earlier complete run of another case in the same folder
                rc, err, _ = run(exe, ["simulate", cases["other"], "-o", out, "-q"])
                if rc:
                    fail(f"earlier run: exit {rc}: {err}")
                extra = ["--overwrite"]
            cmd = (["simulate", cases["sim"]] if kind == "sim" else ["optimize", cases["opt"], "--no-check"])
            rc, err = run_and_signal(exe, cmd + ["-o", out, "-q"] + extra, delay, sig)
            status = check_folder(out, kind, ref[kind], names[kind], rc, sig, err)
            key = f"{kind} {sig.name} -> {status or 'no summary'} (exit {rc})"
            tally[key] = tally.get(key, 0) + 1
            if a.verbose:
                print(f"{kind} trial {i}: {sig.name} after {delay:.2f} s{' over an earlier run' if over_earlier else ''}: "
                      f"exit {rc}, summary {status}")
            if kind != "opt":
                continue
            # resume until complete (interrupted once more in a third of the trials)
            if not os.path.isfile(os.path.join(out, "checkpoint.json")):
                rc, err, _ = run(exe, ["optimize", cases["opt"], "-o", out, "--resume", "-q"])
                if rc != 2 or "no checkpoint" not in err:
                    fail(f"{out}: resume without a checkpoint: exit {rc}: {err}")
                tally["opt resume refused: no checkpoint"] = tally.get("opt resume refused: no checkpoint", 0) + 1
                continue
            if rng.random() < 1 / 3:
                sig2 = rng.choice([signal.SIGKILL, signal.SIGINT])
                rc, err = run_and_signal(exe, ["optimize", cases["opt"], "-o", out, "--resume", "-q"],
                                         rng.uniform(0, t_opt), sig2)
                check_folder(out, "opt", ref["opt"], names["opt"], rc, sig2, err)
                tally["opt resume interrupted again"] = tally.get("opt resume interrupted again", 0) + 1
            rc, err, _ = run(exe, ["optimize", cases["opt"], "-o", out, "--resume", "-q"])
            if rc:
                fail(f"{out}: resume: exit {rc}: {err}")
            check_optimize_equal(out, ref["opt"])
            tally["opt resumed == uninterrupted"] = tally.get("opt resumed == uninterrupted", 0) + 1
        n_damaged = damaged_checkpoints(exe, cases["opt"], ref["opt"], work, a.verbose)
    except AssertionError as e:
        print(f"fault_injection: FAIL: {e}")
        print(f"fault_injection: work folder kept: {work}")
        return 1
    print("fault_injection: seed %d: " % a.seed + "; ".join(f"{k}: {v}" for k, v in sorted(tally.items())) +
          f"; damaged checkpoints refused: {n_damaged}")
    if not a.keep:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
