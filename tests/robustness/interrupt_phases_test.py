#!/usr/bin/env python3
"""Every long phase answers an interrupt: exit 130, the results flagged interrupted, never a run
that goes on, a complete summary, a numerical failure or a failed check.

    interrupt_phases_test.py --lsmbs BIN --root SOURCE_DIR [-v]

The signal is sent at the phase by the testing hook LSMBS_TEST_SIGNAL=POINT[:TERM|:HUP] (the process
signals itself the first time it reaches the point; docs/verification.md), so the test does not
depend on timing: without polling in that phase the run would finish (exit 0) or fail (exit 1).
The case is the clamped plate with one design hole of tests/integration/data/cantilever_ramp.json
(shortened to 20 steps). Phases:

  optimize     the initial gradient check (SIGINT and SIGTERM); --resume afterwards ends on the
               uninterrupted run's design
  sensitivity  --check's simulations (status interrupted, gradient_check verdict "interrupted");
               the adjoint's backward pass; the adjoint's recomputation from checkpoints
               (--adjoint-memory, SIGTERM)
  verify       each stage, with IDAS (stage 1 is the IDAS reference) and without (--no-idas)
  simulate     the writing of a finished run's outputs (the files written are listed)
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lsmbs", required=True)
    ap.add_argument("--root", required=True)
    ap.add_argument("-v", action="store_true")
    a = ap.parse_args()
    work = tempfile.mkdtemp()
    with open(os.path.join(a.root, "tests/integration/data/cantilever_ramp.json")) as f:
        case = json.load(f)
    case["simulation"]["t_end"] = 0.01
    case["forces"][0]["fy"]["ramp_time"] = 0.005
    case["optimization"]["stop"]["max_evaluations"] = 3
    path = os.path.join(work, "case.json")
    with open(path, "w") as f:
        json.dump(case, f)
    findings = []

    def run(label, point, args, expect_rc=130):
        out = os.path.join(work, label)
        env = dict(os.environ)
        if point:
            env["LSMBS_TEST_SIGNAL"] = point
        p = subprocess.run([a.lsmbs] + args + ["-o", out], env=env, capture_output=True,
                           text=True, timeout=600)
        if a.v:
            print(f"{label}: exit {p.returncode}: {p.stderr.strip()[-200:]!r}")
        S = None
        try:
            with open(os.path.join(out, "summary.json")) as f:
                S = json.load(f)
        except (OSError, ValueError):
            pass
        if p.returncode != expect_rc:
            findings.append(f"{label}: exit {p.returncode}, expected {expect_rc}: "
                            f"{p.stderr.strip()[-300:]!r}")
        elif expect_rc == 130:
            if S is None or S.get("status") != "interrupted":
                findings.append(f"{label}: summary status "
                                f"{None if S is None else S.get('status')!r}, expected interrupted")
            elif any(not os.path.exists(os.path.join(out, x)) for x in S.get("files", [])):
                findings.append(f"{label}: summary lists files that do not exist")
            else:  # and every file there is listed (an unlisted one blocks the next --overwrite)
                listed = set(S.get("files", []))
                for d, _, names in os.walk(out):
                    for n in names:
                        rel = os.path.relpath(os.path.join(d, n), out)
                        if rel not in listed and rel != "summary.json":
                            findings.append(f"{label}: {rel} is there but not listed")
            if "interrupted" not in p.stderr:
                findings.append(f"{label}: the message does not say interrupted: {p.stderr!r}")
        return S, out

    # optimize: the initial gradient check, then --resume from there
    ref, _ = run("opt_ref", None, ["optimize", path], expect_rc=0)
    S, out = run("opt_check_int", "gradient-check", ["optimize", path])
    if S and S.get("interrupted_phase") != "gradient check at the initial design":
        findings.append(f"opt_check_int: interrupted_phase {S.get('interrupted_phase')!r}")
    p = subprocess.run([a.lsmbs, "optimize", path, "-o", out, "--resume"], capture_output=True,
                       text=True, timeout=600)
    if p.returncode != 0:
        findings.append(f"resume after the initial check: exit {p.returncode}: {p.stderr!r}")
    else:
        with open(os.path.join(out, "summary.json")) as f:
            R = json.load(f)
        if not ref or R["status"] != "complete" or R["final"]["design"] != ref["final"]["design"]:
            findings.append(f"resumed: status {R.get('status')}, design {R['final']['design']} "
                            f"!= {ref and ref['final']['design']}")
    run("opt_check_term", "gradient-check:TERM", ["optimize", path])
    run("opt_check_hup", "gradient-check:HUP", ["optimize", path])  # the terminal closed

    # sensitivity: --check, the adjoint's backward pass and its recomputation
    S, _ = run("sens_check", "gradient-check", ["sensitivity", path, "--check"])
    if S and (S.get("gradient_check") or {}).get("verdict") != "interrupted":
        findings.append(f"sens_check: gradient_check {S.get('gradient_check')!r}")
    S, out = run("adjoint_back", "adjoint-backward", ["sensitivity", path, "--method", "adjoint"])
    if os.path.exists(os.path.join(out, "gradients.csv")):
        findings.append("adjoint_back: gradients.csv written for an interrupted run")
    run("adjoint_recompute", "adjoint-recompute:TERM",
        ["sensitivity", path, "--method", "adjoint", "--adjoint-memory", "0.15"])

    # verify: every stage, with and without IDAS
    for stage in (1, 2, 3, 4):
        run(f"verify_idas_{stage}", f"verify:{stage}", ["verify", path, "--no-mesh-study"])
    for stage in (1, 2):
        run(f"verify_noidas_{stage}", f"verify:{stage}", ["verify", path, "--no-idas",
                                                          "--no-mesh-study"])

    # simulate: the writing of a finished run's outputs
    run("write_hup", "write-outputs:HUP", ["simulate", path])
    S, out = run("write", "write-outputs", ["simulate", path])
    if S and "history.csv" not in S.get("files", []):
        findings.append(f"write: summary lists {S.get('files')}, expected history.csv among them")

    print(f"interrupt phases: {len(findings)} findings")
    for f in findings:
        print("  FAIL " + f)
    return 1 if findings else 0


if __name__ == "__main__":
    sys.exit(main())
