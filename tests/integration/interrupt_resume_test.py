#!/usr/bin/env python3
"""Ctrl-C in the middle of an evaluation, then --resume, ends on the uninterrupted run's design.

The reference is the same optimization run without interruption (NLopt and the simulations are
deterministic). The interrupted run gets SIGINT once its checkpoint holds two evaluations, so the
signal lands inside a later evaluation (or between two): whenever it lands, the run must stop at
the next time step (exit 130, status "interrupted", no evaluation half-recorded), and the resumed
run must reproduce the uninterrupted history and final design exactly. No wall-clock limits: the
test waits on the checkpoint file, not on time.

  interrupt_resume_test.py LSMBS CASE
"""
import json
import os
import signal
import subprocess
import sys
import tempfile
import time


def main():
    exe, case = sys.argv[1], sys.argv[2]
    work = tempfile.mkdtemp()
    full, part = os.path.join(work, "full"), os.path.join(work, "part")
    ref = subprocess.run([exe, "optimize", case, "-o", full, "-q", "--no-check"], capture_output=True, text=True)
    assert ref.returncode == 0, ref.stderr
    ref_summary = json.load(open(os.path.join(full, "summary.json")))
    ref_history = open(os.path.join(full, "history.csv")).read().splitlines()

    p = subprocess.Popen([exe, "optimize", case, "-o", part, "-q", "--no-check"], stderr=subprocess.PIPE, text=True)
    ck = os.path.join(part, "checkpoint.json")
    n_at_signal = 0
    while p.poll() is None:
        try:
            n_at_signal = len(json.load(open(ck))["evaluations"])
        except (OSError, ValueError, KeyError):
            n_at_signal = 0
        if n_at_signal >= 2:
            p.send_signal(signal.SIGINT)
            break
        time.sleep(0.05)
    _, err = p.communicate()
    assert n_at_signal >= 2, "the run ended before its checkpoint held two evaluations: use a longer case"
    assert p.returncode == 130, f"exit {p.returncode} after SIGINT: {err}"
    s = json.load(open(os.path.join(part, "summary.json")))
    assert s["status"] == "interrupted", s["status"]
    n_ck = len(json.load(open(ck))["evaluations"])
    rows = open(os.path.join(part, "history.csv")).read().splitlines()
    assert len(rows) - 1 == n_ck, f"history has {len(rows) - 1} evaluations, the checkpoint {n_ck}"
    assert n_ck < len(ref_history) - 1, "the interrupted run finished all its evaluations"
    # the evaluations kept are the uninterrupted run's (wall time aside: the last column set differs)
    strip = lambda r: [c for i, c in enumerate(r.split(",")) if i != 4]  # column 4: wall_seconds
    assert [strip(r) for r in rows] == [strip(r) for r in ref_history[: len(rows)]], "history differs before the interrupt"

    res = subprocess.run([exe, "optimize", case, "-o", part, "-q", "--no-check", "--resume"], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    got = json.load(open(os.path.join(part, "summary.json")))
    assert got["final"]["design"] == ref_summary["final"]["design"], (got["final"], ref_summary["final"])
    assert got["final"]["objective"] == ref_summary["final"]["objective"]
    rows = open(os.path.join(part, "history.csv")).read().splitlines()
    assert [strip(r) for r in rows] == [strip(r) for r in ref_history], "resumed history differs"
    print(f"interrupt_resume: SIGINT with {n_at_signal} evaluations in the checkpoint, {n_ck} kept; resumed run "
          f"ends on the uninterrupted design {got['final']['design']} after {len(rows) - 1} evaluations")


if __name__ == "__main__":
    main()
