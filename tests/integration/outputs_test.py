#!/usr/bin/env python3
"""The outputs a researcher reads directly (issue 23), for every command:

* every CSV any command writes is read by pandas.read_csv(path) with no options: its columns are
  the header's names (no "Unnamed", no comment line), and values are checked against independent
  references (statics of a hanging pendulum and a held slider: m g; the case file's bounds and
  grids; exact doubles of checkpoint.json; the gradient norms recomputed from them);
* summary.json["files"] is exactly the set of files in the output folder (summary.json included);
* summary.json["units"] gives the SI unit of every measure column and response (expected units
  written here by hand from docs/case-format.md, "Units");
* `verify` states the comparison that holds in each verdict ("worst A >= tolerance B" on failure).

Usage: outputs_test.py LSMBS_EXE SOURCE_DIR   (Debian's python3, with python3-pandas)
"""
import csv
import json
import math
import os
import re
import struct
import subprocess
import sys
import tempfile

import numpy as np
import pandas as pd

EXE, SRC = sys.argv[1], sys.argv[2]
G = 9.81
M_BOB, M_SLIDER = 1.5, 2.0


def fail(msg):
    sys.exit("FAIL: " + msg)


def run(*args, expect=0):
    quiet = [] if args[0] in ("verify", "bench") else ["-q"]
    p = subprocess.run([EXE, *args, *quiet], capture_output=True, text=True)
    if p.returncode != expect:
        fail(f"lsmbs {' '.join(args)}: exit {p.returncode}, expected {expect}\n{p.stdout}\n{p.stderr}")
    return p


def files_on_disk(out):
    found = set()
    for root, _, names in os.walk(out):
        for n in names:
            found.add(os.path.relpath(os.path.join(root, n), out))
    return found


def check_files(out, what):
    s = json.load(open(os.path.join(out, "summary.json")))
    listed = s.get("files")
    if not isinstance(listed, list):
        fail(f"{what}: summary.json files is not a list: {listed!r}")
    if listed != sorted(set(listed)):
        fail(f"{what}: summary.json files not sorted or with duplicates")
    disk = files_on_disk(out)
    if set(listed) != disk:
        fail(f"{what}: summary.json files differ from the folder: only listed {sorted(set(listed) - disk)}, "
             f"only on disk {sorted(disk - set(listed))}")
    return s


def read_csv_plain(path):
    """pandas with no options, and the header and rows by the csv module (exact float())."""
    df = pd.read_csv(path)
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header = rows[0]
    if list(df.columns) != header:
        fail(f"{path}: pandas columns {list(df.columns)} differ from the header {header}")
    if any(str(c).startswith("Unnamed") or str(c).startswith("#") for c in df.columns):
        fail(f"{path}: pandas found unnamed or comment columns: {list(df.columns)}")
    if len(df) != len(rows) - 1 or len(df) == 0:
        fail(f"{path}: pandas read {len(df)} rows, the file has {len(rows) - 1}")
    return df, header, rows[1:]


def close(a, b, rel=1e-12, abs_=0.0):
    return abs(a - b) <= rel * max(abs(a), abs(b)) + abs_


def unhex(h):
    return struct.unpack("<d", int(h, 16).to_bytes(8, "little"))[0]


work = tempfile.mkdtemp(prefix="lsmbs_outputs_")
all_csv = []

# ---------------------------------------------------------------- a case with known statics
# A pendulum hanging at rest from a pin (the pin holds m g), and a slider held horizontally by a
# prismatic joint that also locks its rotation (a force m g and a moment 0): nothing moves, so the
# constraint forces are the static ones at every step. Names with a comma and quotes exercise the
# CSV quoting.
POS = 'bob, "A"'
case = {
    "name": "statics",
    "gravity": [0, -G],
    "bodies": [
        {"name": "bob", "type": "rigid", "position": [0, -1], "mass": M_BOB, "inertia": 0.1},
        {"name": "slider", "type": "rigid", "position": [3, 0], "mass": M_SLIDER, "inertia": 0.2},
    ],
    "joints": [
        {"name": "pin", "type": "revolute", "a": {"body": "bob", "at": [0, 1]}, "b": "ground"},
        {"name": "slide", "type": "prismatic", "a": {"body": "slider", "at": [0, 0]}, "direction": [1, 0]},
    ],
    "simulation": {"t_end": 0.1, "h": 0.01},
    "design": {"variables": [{"name": "m", "initial": M_BOB, "lower": 1, "upper": 3}],
               "parameters": [{"parameter": "bob.mass", "variable": "m"}]},
    "output": {
        "measures": [
            {"name": POS, "type": "position", "point": {"body": "bob", "at": [0, 0]}},
            {"name": "speed", "type": "velocity", "point": {"body": "bob", "at": [0, 0]}},
            {"name": "swing", "type": "angle", "body": "bob"},
            {"name": "omega", "type": "angular_velocity", "body": "bob"},
            {"name": "pin", "type": "constraint_force", "joint": "pin"},
            {"name": "slide", "type": "constraint_force", "joint": "slide"},
            {"name": "ke", "type": "kinetic_energy"},
            {"name": "reach", "type": "distance", "a": {"body": "bob", "at": [0, 0]}, "b": {"body": "slider", "at": [0, 0]}},
        ],
        "responses": [
            {"name": "hold", "measure": "pin.1", "aggregate": "final"},
            {"name": "lowest, y", "measure": POS + ".y", "aggregate": "min"},
            {"name": "swing_time", "measure": "swing", "aggregate": "integral"},
            {"name": "drift", "measure": "speed.x", "aggregate": "integral"},
            {"name": "hold_steps", "measure": "pin.1", "aggregate": "per_step", "window": {"t0": 0.05, "t1": 0.1}},
            {"name": "energy", "measure": "ke", "aggregate": "max"},
        ],
    },
}
case_path = os.path.join(work, "statics.json")
json.dump(case, open(case_path, "w"))

# units, by hand from docs/case-format.md ("Units")
UNITS = {POS + ".x": "m", POS + ".y": "m", "speed.x": "m/s", "speed.y": "m/s", "swing": "rad",
         "omega": "rad/s", "pin.0": "N", "pin.1": "N", "slide.0": "N", "slide.1": "N*m", "ke": "J",
         "reach": "m"}
RESPONSE_UNITS = {"hold": "N", "lowest, y": "m", "swing_time": "rad*s", "drift": "m",
                  "hold_steps": "N", "energy": "J"}

# ---- simulate
sim = os.path.join(work, "sim")
run("simulate", case_path, "-o", sim)
S = check_files(sim, "simulate")
if S["units"] != {"t": "s", "measures": UNITS, "responses": RESPONSE_UNITS}:
    fail(f"simulate units: {S['units']}")
df, header, rows = read_csv_plain(os.path.join(sim, "history.csv"))
all_csv.append("sim/history.csv")
if header != ["t"] + list(UNITS):
    fail(f"history.csv header {header}")
last = df.iloc[-1]
if not (close(last["t"], 0.1) and len(df) == 11):
    fail(f"history.csv: {len(df)} rows ending at t = {last['t']}")
# statics: |pin force| = m_bob g (vertical), slider: |normal force| = m_slider g, moment 0
if not (close(abs(last["pin.1"]), M_BOB * G, 1e-9) and abs(last["pin.0"]) < 1e-9 * M_BOB * G):
    fail(f"pin force {last['pin.0']}, {last['pin.1']}, expected (0, ±{M_BOB * G})")
if not (close(abs(last["slide.0"]), M_SLIDER * G, 1e-9) and abs(last["slide.1"]) < 1e-9 * M_SLIDER * G):
    fail(f"slider force {last['slide.0']}, moment {last['slide.1']}, expected ±{M_SLIDER * G}, 0")
if not (close(last[POS + ".y"], -1.0, 1e-12) and close(last["reach"], math.hypot(3, 1), 1e-12)):
    fail(f"positions {last[POS + '.y']}, {last['reach']}")
if S["responses"]["hold"] != float(rows[-1][header.index("pin.1")]):
    fail("summary response 'hold' differs from the last row of history.csv")
print(f"simulate: history.csv {len(df)} rows x {len(header)} columns; pin {last['pin.1']:.6g} N, "
      f"slider {last['slide.0']:.6g} N, units ok, files ok")

# ---- sensitivity: long-form gradients.csv; d(hold)/dm = hold / m (the pin holds m g)
sens = os.path.join(work, "sens")
run("sensitivity", case_path, "--method", "direct-analytic", "-o", sens)
S = check_files(sens, "sensitivity")
if S["units"]["responses"] != RESPONSE_UNITS:
    fail(f"sensitivity units {S['units']}")
df, header, rows = read_csv_plain(os.path.join(sens, "gradients.csv"))
all_csv.append("sens/gradients.csv")
if header != ["response", "variable", "step", "t", "value", "derivative"]:
    fail(f"gradients.csv header {header}")
if set(df["response"]) != set(RESPONSE_UNITS) or set(df["variable"]) != {"m"}:
    fail(f"gradients.csv responses {set(df['response'])}, variables {set(df['variable'])}")
hold = df[df["response"] == "hold"].iloc[0]
if not (close(abs(hold["value"]), M_BOB * G, 1e-9) and close(hold["derivative"], hold["value"] / M_BOB, 1e-7)):
    fail(f"d(hold)/dm = {hold['derivative']}, expected hold / m = {hold['value'] / M_BOB}")
steps = df[df["response"] == "hold_steps"]
if list(steps["step"]) != list(range(6)) or not np.allclose(steps["t"], [0.05, 0.06, 0.07, 0.08, 0.09, 0.1], rtol=1e-12):
    fail(f"per-step rows: steps {list(steps['step'])}, t {list(steps['t'])}")
if not df[df["response"] != "hold_steps"]["t"].isna().all():
    fail("t of a scalar response is not empty/NaN")
low = df[df["response"] == "lowest, y"].iloc[0]
if float(rows[list(df["response"]).index("lowest, y")][4]) != S["responses"]["lowest, y"] or not close(low["value"], -1, 1e-12):
    fail(f"'lowest, y': {low['value']} vs summary {S['responses']['lowest, y']}")
print(f"sensitivity: gradients.csv {len(df)} rows; d(hold)/dm = {hold['derivative']:.9g} (hold/m = "
      f"{hold['value'] / M_BOB:.9g}), files ok")

# ---- geometry and optimize on the robot arm (coarse plate, short run)
arm = json.load(open(os.path.join(SRC, "data/robot_arm/robot_arm_holes.json")))
arm["bodies"][2]["mesh"]["elements"] = [30, 3]
arm["simulation"]["h"] = 0.01
arm["output"]["vtu_stride"] = 50
arm["output"]["responses"].append({"name": "dev_steps", "measure": "tip_deviation", "aggregate": "per_step",
                                   "window": {"t0": 2.45, "t1": 2.5}})
arm["optimization"]["constraints"].append({"response": "dev_steps", "upper": 0.05})
arm["optimization"]["stop"]["max_evaluations"] = 3
arm_path = os.path.join(work, "arm.json")
json.dump(arm, open(arm_path, "w"))

geo = os.path.join(work, "geo")
run("geometry", arm_path, "-o", geo, "--width", "300")
S = check_files(geo, "geometry")
if S["units"]["responses"] != {"mass.plate": "kg"}:
    fail(f"geometry units {S['units']}")

asim = os.path.join(work, "arm_sim")
run("simulate", arm_path, "-o", asim)
S = check_files(asim, "simulate (flexible body: VTU and PVD)")
if not any(f.endswith(".vtu") for f in S["files"]) or "plate.pvd" not in S["files"]:
    fail(f"simulate files without VTU/PVD: {S['files']}")
df, header, _ = read_csv_plain(os.path.join(asim, "history.csv"))
all_csv.append("arm_sim/history.csv")
if S["units"]["measures"]["plate_mass"] != "kg" or S["units"]["measures"]["tip_deviation"] != "m":
    fail(f"arm units {S['units']}")
if not close(df["plate_mass"].iloc[-1], S["responses"]["plate_mass"], 1e-15):
    fail("plate_mass column vs summary")

opt = os.path.join(work, "opt")
run("optimize", arm_path, "-o", opt, "--no-check")
S = check_files(opt, "optimize")
df, header, rows = read_csv_plain(os.path.join(opt, "history.csv"))
all_csv.append("opt/history.csv")
names = [v["name"] for v in arm["design"]["variables"]]
lower = np.array([v["lower"] for v in arm["design"]["variables"]])
upper = np.array([v["upper"] for v in arm["design"]["variables"]])
cons = ["average_tip_deviation"] + [f"dev_steps.{k}" for k in range(6)]  # t = 2.45 ... 2.5, h = 0.01
bounds = {"average_tip_deviation": 0.001, **{c: 0.05 for c in cons[1:]}}
expect = ["evaluation", "objective", "max_constraint_violation", "feasible", "wall_seconds"] + names + \
    ["objective_gradient_norm"] + [f"constraint.{c}{s}" for c in cons for s in ("", ".upper", ".gradient_norm")]
if header != expect:
    fail(f"optimize history.csv header {header}\nexpected {expect}")
ck = json.load(open(os.path.join(opt, "checkpoint.json")))["evaluations"]
if len(ck) != len(rows):
    fail(f"{len(rows)} history rows, {len(ck)} checkpoint evaluations")
for row, e in zip(rows, ck):
    r = dict(zip(header, row))
    # exact doubles: the CSV text reads back as the checkpoint's bit patterns
    if float(r["objective"]) != unhex(e["objective"]):
        fail(f"objective {r['objective']} != checkpoint {unhex(e['objective'])}")
    p = [unhex(x) for x in e["p"]]
    if [float(r[n]) for n in names] != p:
        fail("design variables differ from the checkpoint's")
    g = np.array([unhex(x) for x in e["objective_gradient"]])
    if not close(float(r["objective_gradient_norm"]), float(np.linalg.norm(g * (upper - lower))), 1e-13):
        fail(f"objective_gradient_norm {r['objective_gradient_norm']}")
    vals = [unhex(x) for x in e["constraints"]]
    grads = np.array([unhex(x) for x in e["constraint_gradient"]]).reshape((len(cons), len(names)), order="F")
    for j, c in enumerate(cons):
        if float(r[f"constraint.{c}"]) != vals[j] or float(r[f"constraint.{c}.upper"]) != bounds[c]:
            fail(f"constraint {c}: {r[f'constraint.{c}']} / {r[f'constraint.{c}.upper']}")
        if not close(float(r[f"constraint.{c}.gradient_norm"]), float(np.linalg.norm(grads[j] * (upper - lower))), 1e-13):
            fail(f"constraint {c} gradient norm")
if not close(df["objective"].iloc[0], S["initial"]["objective"], 1e-15):
    fail("pandas objective vs summary initial objective")
if not any(f.startswith("final_design/") for f in S["files"]):
    fail(f"optimize files: {S['files']}")
print(f"optimize: history.csv {len(df)} rows x {len(header)} columns equal checkpoint.json's doubles; files ok")

# ---- verify (slider-crank with a spring; no IDAS, no mesh study) with a tolerance it cannot meet
spring = os.path.join(SRC, "data/slider_crank_rigid/slider_crank_spring.json")
ver = os.path.join(work, "verify")
p = run("verify", spring, "-o", ver, "--no-idas", "--no-mesh-study", "--tol-fd", "1e-14", expect=1)
S = check_files(ver, "verify")
lines = S["verdicts"]
num = r"([0-9.]+e[-+][0-9]+)"
checked = 0
for v in lines:
    m = re.search(r"worst " + num + r" (<|>=) tolerance " + num, v)
    if not m:
        continue
    a, op, b = float(m.group(1)), m.group(2), float(m.group(3))
    if (op == "<") != (a < b) or v.startswith("PASS") != (op == "<"):
        fail(f"verdict reads the wrong way: {v}")
    checked += 1
if checked != 3 or not any(v.startswith("FAIL") and ">= tolerance 1e-14" in v for v in lines):
    fail(f"verdicts: {lines}")
for v in lines:
    if "slope" in v and ("within" in v) != v.startswith("PASS"):
        fail(f"slope verdict reads the wrong way: {v}")
df, header, _ = read_csv_plain(os.path.join(ver, "gradients.csv"))
all_csv.append("verify/gradients.csv")
if header[:4] != ["response", "variable", "step", "direct-analytic"] or not any(h.startswith("default options (") and "," in h for h in header):
    fail(f"verify gradients.csv header {header}")
sens_ref = os.path.join(work, "sens_spring")
run("sensitivity", spring, "--method", "direct-analytic", "--matrix", "refined", "-o", sens_ref)
ref = pd.read_csv(os.path.join(sens_ref, "gradients.csv"))
r0 = df.iloc[0]
g_ref = ref[(ref["response"] == r0["response"]) & (ref["variable"] == r0["variable"]) & (ref["step"] == r0["step"])]
if len(g_ref) != 1 or not close(r0["direct-analytic"], g_ref["derivative"].iloc[0], 1e-12):
    fail(f"verify's direct-analytic {r0['direct-analytic']} vs sensitivity's {list(g_ref['derivative'])}")
dp, header, _ = read_csv_plain(os.path.join(ver, "dp_study.csv"))
all_csv.append("verify/dp_study.csv")
if header != ["delta", "forward", "central"] or not np.allclose(dp["delta"], [10.0 ** -k for k in range(2, 12)], rtol=1e-12):
    fail(f"dp_study.csv: {header}, {list(dp['delta'])}")
print(f"verify: verdicts read as they hold ({checked} tolerance lines), gradients.csv and dp_study.csv read; files ok")


# ---- verify's time-step study against IDAS: h_study.csv read by pandas, and one verdict line per
# scalar response and quantity that says what the numbers say (docs/verification.md): an order
# fitted on the finest halving whose two differences exceed max(100 rtol, 4 x the largest IDAS
# self-difference) (PASS within 1.8-2.2, FAIL outside), PASS when every difference is within
# 100 rtol <= 1e-6, NOTE (inconclusive) otherwise. The spring slider-crank fits orders; the ramped
# cantilever cannot decide (its two IDAS runs differ as much as generalized-alpha and IDAS).
def check_h_study(case, out, rtol=1e-10, want=None):
    run("verify", case, "-o", out, "--no-mesh-study")  # exit 0: NOTE lines do not fail a run
    S = check_files(out, "verify")
    h = pd.read_csv(os.path.join(out, "h_study.csv"))
    all_csv.append(os.path.relpath(os.path.join(out, "h_study.csv"), work))
    all_csv.append(os.path.relpath(os.path.join(out, "h_study_plot.csv"), work))
    if list(h.columns) != ["response", "quantity", "h", "difference", "idas_self_difference"]:
        fail(f"h_study.csv columns {list(h.columns)}")
    if S["options"]["idas_rtol"] != rtol or S["options"]["idas_rtol_loose"] != 10 * rtol:
        fail(f"verify options {S['options']}")
    kinds = []
    for (resp, q), g in h.groupby(["response", "quantity"], sort=False):
        g = g.sort_values("h", ascending=False)
        d, hs = list(g["difference"]), list(g["h"])
        floor = max(1e2 * rtol, 4 * max(g["idas_self_difference"]))
        fit = None
        for k in range(len(d) - 1, 0, -1):
            if d[k - 1] > floor and d[k] > floor:
                fit = (np.log2(d[k - 1] / d[k]), hs[k])
                break
        line = [v for v in S["verdicts"] if f"— {resp} {q} " in v]
        if len(line) != 1:
            fail(f"{resp} {q}: verdict lines {line}")
        v = line[0]
        if fit:
            ok = 1.8 < fit[0] < 2.2
            m = re.search(r"order (-?[0-9.]+) \(halving to h = ([0-9.e+-]+);", v)
            if not m or abs(float(m.group(1)) - fit[0]) > 0.006 or not close(float(m.group(2)), fit[1], 1e-3) \
                    or v.startswith("PASS") != ok or not (v.startswith("PASS") or v.startswith("FAIL")):
                fail(f"{resp} {q}: order {fit} from h_study.csv, verdict {v}")
            kinds.append("fit")
        elif max(d) <= 1e2 * rtol <= 1e-6:
            if not v.startswith("PASS") or "within 100 " not in v:
                fail(f"{resp} {q}: agreement expected, verdict {v}")
            kinds.append("agree")
        else:
            if not v.startswith("NOTE") or "inconclusive" not in v:
                fail(f"{resp} {q}: inconclusive expected, verdict {v}")
            kinds.append("note")
    if want and want not in kinds:
        fail(f"{case}: no '{want}' verdict among {kinds}")
    return kinds


k1 = check_h_study(spring, os.path.join(work, "verify_idas"), want="fit")
cant = os.path.join(SRC, "tests/integration/data/cantilever_ramp.json")
k2 = check_h_study(cant, os.path.join(work, "verify_cant"), want="note")
print(f"verify h study: verdicts follow h_study.csv (spring: {k1}; cantilever: {k2})")

# ---- bench
bench = os.path.join(work, "bench")
run("bench", spring, "-o", bench, "--methods", "none", "--matrices", "none", "--repetitions", "1")
check_files(bench, "bench")

# every CSV written anywhere above was read by pandas (none left out)
written = {os.path.relpath(os.path.join(r, n), work) for r, _, ns in os.walk(work) for n in ns if n.endswith(".csv")}
unread = written - set(all_csv) - {"sens_spring/gradients.csv"}
if unread:
    for f in sorted(unread):
        read_csv_plain(os.path.join(work, f))
    print(f"also read: {sorted(unread)}")
print(f"outputs: every command's files listed, {len(written)} CSV files read by pandas.read_csv(path)")
subprocess.run(["rm", "-rf", work])
