#!/usr/bin/env python3
"""Service conditions on MPI ranks: whole-process parallel efficiency of one evaluation (a
`sensitivity` run of every condition) on K ranks against one process on one core, and the cost
model of docs/performance.md ("Service conditions on MPI ranks") checked at K = 1, 2, 3.

    python3 bench/mpi_scaling.py --lsmbs build/src/lsmbs [--mpirun mpirun] [--runs 3] [--out DIR]

Cases (written to DIR from the shipped ones; one sensitivity thread per process, --threads 1):
  payloads   the robot arm (robot_arm_holes.json, 15 variables) carrying 2 kg and 5 kg: two
             conditions of equal length, the efficiency figure at K = 2
  speeds     the three-hole rod at 2000, 3000, 4000 rpm (slider_crank_3holes_coarse_speeds.json):
             conditions of 320, 220 and 170 steps, the model's check at K = 1, 2, 3

Cost model of one evaluation on K ranks (conditions assigned longest first, runs/mpi.cpp):
  T(K) = T_launch(K) + T_fixed + max_r sum_{k on r} t_k + T_comm(K)
  T_launch(K): mpirun starting and ending K processes that initialize MPI (measured: `mpirun -np K
               lsmbs --version`); T_fixed: loading and checking the case and every condition,
               writing the results (measured: every run one step long); t_k: condition k's run
               (measured: the case with condition k only, minus the same for one step), all on one
               core; T_comm(K): every rank
               receives every condition's result (responses and gradients, B bytes each) from its
               rank: C broadcasts, about C (alpha log2 K + beta B) (alpha, beta: latency and inverse
               bandwidth of the network; on one machine below a millisecond in total).
Every time is the median of --runs whole-process runs (wall clock, time.monotonic). Like the
serial run (taskset to one core), each rank has one core (`mpirun --bind-to core`) while K does
not exceed the cores; K = 3 on two cores shares them (--oversubscribe).
"""
import argparse
import json
import math
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent


def median_time(cmd, runs, env=None):
    ts = []
    for _ in range(runs):
        t0 = time.monotonic()
        p = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env)
        ts.append(time.monotonic() - t0)
        if p.returncode != 0:
            sys.exit("bench: %s failed: %s" % (" ".join(map(str, cmd)), p.stderr.strip()[-300:]))
    return statistics.median(ts)


def cases(out):
    arm = json.loads((ROOT / "data/robot_arm/robot_arm_holes.json").read_text())
    arm["name"] = "robot_arm_payloads"
    arm["conditions"] = [{"name": "kg2", "set": {"/forces/effector/mass": 2.0}},
                         {"name": "kg5", "set": {"/forces/effector/mass": 5.0}}]
    arm["output"]["vtu_stride"] = 0
    rod = json.loads((ROOT / "data/slider_crank/slider_crank_3holes_coarse_speeds.json").read_text())
    for c in (arm, rod):
        c.setdefault("optimization", {}).setdefault("sensitivity", {})["threads"] = 1
    files = {}
    for name, c, base in (("payloads", arm, "data/robot_arm"),
                          ("speeds", rod, "data/slider_crank")):
        # relative files (meshes, tables) resolve against the case's folder: write it there
        f = ROOT / base / (".bench_%s_%d.json" % (name, os.getpid()))
        f.write_text(json.dumps(c))
        files[name] = (f, c)
    return files


def variant(case, keep=None, one_step=False):
    """The case with only the conditions `keep` (indices), or with every run one step long."""
    c = json.loads(json.dumps(case))
    if keep is not None:
        c["conditions"] = [c["conditions"][k] for k in keep]
        c.pop("combined", None)
        c["optimization"].pop("constraints", None)
    if one_step:
        h = c["simulation"]["h"]
        c["simulation"]["t_end"] = h
        for cond in c["conditions"]:
            if "/simulation/t_end" in cond["set"]:
                cond["set"]["/simulation/t_end"] = h
        # a window (a driver's phase, a time span) holds no step of a one-step run: the whole run
        for r in c["output"].get("responses", []):
            r.pop("window", None)
    return c


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--lsmbs", required=True)
    ap.add_argument("--mpirun", default="mpirun")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--out", default=None)
    ap.add_argument("--no-conditions", action="store_true",
                    help="skip the conditions' efficiency and model (with --campaign: that only)")
    ap.add_argument("--campaign", action="store_true",
                    help="also the multi-start campaign: optimize --starts 8 on 2 ranks against 2 "
                         "threads of one process (the coarse one-hole rod)")
    a = ap.parse_args()
    lsmbs = os.path.abspath(a.lsmbs)
    out = pathlib.Path(a.out or tempfile.mkdtemp(prefix="lsmbs_mpi_bench_"))
    out.mkdir(parents=True, exist_ok=True)
    mpi = [a.mpirun, "--allow-run-as-root", "--oversubscribe", "--bind-to", "none"]
    cores = os.cpu_count() or 1

    def ranks(k):  # K ranks on K cores, one each, as the serial run has one; more: shared
        bind = ["--bind-to", "core"] if k <= cores else ["--oversubscribe", "--bind-to", "none"]
        return [a.mpirun, "--allow-run-as-root", *bind, "-np", str(k)]

    one_core = ["taskset", "-c", "0"]
    files = cases(out)
    report = {"runs": a.runs, "cases": {}}
    try:
        launch = {k: median_time([*ranks(k), lsmbs, "--version"], a.runs) for k in (1, 2, 3)}
        report["T_launch"] = launch
        for name, (f, case) in ([] if a.no_conditions else files.items()):
            sens = lambda d: ["sensitivity", str(f), "-o", str(out / d), "-q", "--overwrite", "--threads", "1"]
            serial = median_time([*one_core, lsmbs, *sens(name + "_serial")], a.runs)

            def timed(c, tag):  # a variant of the case, on one core
                vf = f.with_name(f.stem + "_%s.json" % tag)
                vf.write_text(json.dumps(c))
                try:
                    return median_time([*one_core, lsmbs, "sensitivity", str(vf), "-o",
                                        str(out / ("%s_%s" % (name, tag))), "-q", "--overwrite",
                                        "--threads", "1"], a.runs)
                finally:
                    vf.unlink()

            fixed = timed(variant(case, one_step=True), "fixed")
            t = [timed(variant(case, keep=[k]), "single%d" % k) - timed(
                variant(variant(case, keep=[k]), one_step=True), "single%d_fixed" % k)
                 for k in range(len(case["conditions"]))]
            S = json.loads((out / (name + "_serial") / "summary.json").read_text())
            doubles = sum(len(v) if isinstance(v, list) else 1 for v in S["responses"].values())
            # gradients by variable name: a number each, or a list (per-step responses)
            doubles += sum(sum(len(x) if isinstance(x, list) else 1 for x in g.values())
                           for g in S["gradients"].values())
            row = {"serial_one_core": serial, "T_fixed": fixed, "t_k": t,
                   "result_bytes_per_evaluation": 8 * doubles, "K": {}}
            steps = []
            for k, cond in enumerate(case["conditions"]):
                te = cond["set"].get("/simulation/t_end", case["simulation"]["t_end"])
                steps.append(math.ceil(te / case["simulation"]["h"]))
            for K in (1, 2, 3):
                if K > len(t):
                    continue
                load = [0.0] * K
                for k in sorted(range(len(t)), key=lambda k: -steps[k]):  # longest first
                    load[load.index(min(load))] += t[k]
                predicted = launch[K] + fixed + max(load)
                measured = median_time([*ranks(K), lsmbs, *sens("%s_K%d" % (name, K))], a.runs)
                row["K"][K] = {"measured": measured, "predicted": predicted,
                               "efficiency": serial / (K * measured),
                               "predicted_efficiency": serial / (K * predicted)}
            report["cases"][name] = row
    finally:
        for f, _ in files.values():
            f.unlink(missing_ok=True)
    (out / "mpi_scaling.json").write_text(json.dumps(report, indent=1))
    if a.campaign:  # a multi-start runs 2 starts at a time in one process, or 1 per rank
        rod = str(ROOT / "data/slider_crank/slider_crank_1hole_coarse.json")
        ms = lambda d: ["optimize", rod, "--starts", "8", "--seed", "1", "--no-check", "-q",
                        "--overwrite", "-o", str(out / d)]
        local = median_time([lsmbs, *ms("starts_local")], a.runs)
        ranks = median_time([*mpi, "-np", "2", lsmbs, *ms("starts_mpi")], a.runs)
        report["campaign"] = {"local_two_threads": local, "mpi_two_ranks": ranks}
        (out / "mpi_scaling.json").write_text(json.dumps(report, indent=1))
    print("T_launch (mpirun -np K lsmbs --version): " +
          ", ".join("K=%d %.3f s" % kv for kv in launch.items()))
    for name, row in report["cases"].items():
        print("%s: serial on one core %.2f s, T_fixed %.2f s, t_k %s s, results %d bytes per "
              "evaluation" % (name, row["serial_one_core"], row["T_fixed"],
                              ", ".join("%.2f" % x for x in row["t_k"]),
                              row["result_bytes_per_evaluation"]))
        for K, r in row["K"].items():
            print("  K=%d: measured %.2f s (efficiency %.3f), model %.2f s (%.3f)" % (
                K, r["measured"], r["efficiency"], r["predicted"], r["predicted_efficiency"]))
    if a.campaign:
        c = report["campaign"]
        print("optimize --starts 8 (coarse one-hole rod): 2 threads of one process %.2f s, "
              "mpirun -np 2 %.2f s (ratio %.3f)" % (c["local_two_threads"], c["mpi_two_ranks"],
                                                    c["mpi_two_ranks"] / c["local_two_threads"]))
    print("written", out / "mpi_scaling.json")


if __name__ == "__main__":
    main()
