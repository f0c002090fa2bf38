#!/usr/bin/env python3
"""Hostile strings: every name of a case and every output path is data, never code.

    hostile_strings_test.py --lsmbs BIN [-v] [--quick]

A small case (a clamped plate with one design hole, a free rigid body, a point force, five
measures, four responses, an optimization section) is written with every name replaced by one
hostile string of a class, and run by simulate (VTU every step), static, geometry, sensitivity with
two methods (methods.png), optimize (two evaluations: convergence.png, final_design/) and verify.
Separately, the output folder (-o) is given hostile names. The classes:

  gnuplot/shell     a newline followed by a gnuplot `system` command; $(…), `…`, ; and | forms
  quotes            ' and " mixed
  backslashes       \\ inside and at the end
  NUL               a NUL character inside the name (JSON "\\u0000")
  control           carriage return, tab, an ANSI escape, DEL
  long              5,000 characters
  paths             ../../escape, /abs, ., .., a/b (names that look like paths)
  markup            XML markup and entities, ]]>
  format            printf conversions (%s%n%x)
  unicode           accented letters, CJK, a right-to-left override
  dash              a leading dash (-rf)

and, apart, non-UTF-8 bytes in a case file's name and in -o (refused: exit 2, naming them).

For each run: the exit code is 0 (verify: 0 or 1, a verdict, with its report; or 2 with a message "lsmbs: error: …" for a name the format
refuses), no file named MARK appears anywhere (nothing ran), no file appears outside the output
folder, and everything written in it parses: summary.json as UTF-8 JSON whose `files` all exist,
every .vtu/.vtm/.pvd as XML, every .csv with one field count per row, every .png as a PNG that
Pillow decodes (or, without Pillow, its signature and IEND chunk). Exit status 1 when one fails.
"""
import argparse
import copy
import csv
import json
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

HOSTILE = {
    "gnuplot": "x\nsystem 'touch MARK'\n#",
    "shell": "$(touch MARK) `touch MARK`; touch MARK | touch MARK",
    "quotes": "it's \"quoted\" ''\"",
    "backslashes": "a\\b\\\\c\\n\\",
    "nul": "a\u0000b",
    "control": "r\rt\tesc\u001b[31mred\u007fdel",
    "long": "L" * 5000,
    "paths": "../../escape/../.././abs/..",
    "dotdot": "..",
    "markup": "<a x=\"1\">&amp;&lt;</a>]]><!--",
    "format": "%s%s%n%x%99999999d",
    "unicode": "µ_é 日本語 \u202eRTL",
    "dash": "-rf",
}

# names of the plate case, by field: each gets the hostile string with its own suffix (bodies,
# joints and forces share one namespace)
FIELDS = ["case", "body", "rigid", "joint", "force", "m_tip", "m_mass", "m_dy", "m_se", "m_ke",
          "r_dev", "r_m", "r_avg", "r_mx", "var", "feature"]


def plate_case(names):
    n = names
    return {
        "name": n["case"],
        "bodies": [
            {"name": n["body"], "type": "flexible",
             "mesh": {"type": "rectangle", "origin": [0, 0], "size": [0.2, 0.05],
                      "elements": [10, 3]},
             "material": {"E": 7e10, "nu": 0.3, "rho": 2700}, "thickness": 0.001},
            {"name": n["rigid"], "type": "rigid", "position": [0.3, 0], "mass": 1.0,
             "inertia": 0.01},
        ],
        "joints": [{"name": n["joint"], "type": "clamp", "flexible": n["body"],
                    "node_set": "left"}],
        "forces": [{"name": n["force"], "type": "point_force",
                    "point": {"body": n["body"], "nearest": [0.2, 0.025]},
                    "fx": {"type": "constant", "value": 0.0},
                    "fy": {"type": "ramp", "from": 0.0, "speed": -200.0, "ramp_time": 0.002,
                           "start": 0.0}}],
        "output": {
            "vtu_stride": 1,
            "measures": [
                {"name": n["m_tip"], "type": "position",
                 "point": {"body": n["body"], "nearest": [0.2, 0.025]}},
                {"name": n["m_mass"], "type": "mass", "body": n["body"]},
                {"name": n["m_dy"], "type": "distance",
                 "a": {"body": n["body"], "nearest": [0.2, 0.025]}, "b": {"ground": [0.2, 0.025]}},
                {"name": n["m_se"], "type": "strain_energy"},
                {"name": n["m_ke"], "type": "kinetic_energy"},
            ],
            "responses": [
                {"name": n["r_dev"], "measure": n["m_dy"], "aggregate": "final"},
                {"name": n["r_m"], "measure": n["m_mass"], "aggregate": "final"},
                {"name": n["r_avg"], "measure": n["m_dy"], "aggregate": "average"},
                {"name": n["r_mx"], "measure": n["m_dy"], "aggregate": "max"},
            ],
        },
        "design": {
            "variables": [{"name": n["var"], "initial": 0.01, "lower": 0.002, "upper": 0.02}],
            "geometry": [{"body": n["body"], "features": [
                {"name": n["feature"], "type": "circle", "hole": True, "cx": 0.06, "cy": 0.025,
                 "r": n["var"]}]}],
        },
        "simulation": {"h": 0.0005, "t_end": 0.004},
        "optimization": {"objective": n["r_m"],
                         "constraints": [{"response": n["r_dev"], "upper": 0.01}],
                         "stop": {"max_evaluations": 2}},
    }


def commands(case, out):
    return [
        ["simulate", case, "-o", out + "/simulate"],
        ["static", case, "-o", out + "/static"],
        ["geometry", case, "-o", out + "/geometry"],
        ["sensitivity", case, "--method", "direct-analytic,fd-central", "-o",
         out + "/sensitivity"],
        ["optimize", case, "--no-check", "-o", out + "/optimize"],
        ["verify", case, "--no-mesh-study", "-o", out + "/verify"],
    ]


def tree(root):
    """Every path below root, relative."""
    r = set()
    for d, dirs, files in os.walk(root):
        for x in dirs + files:
            r.add(os.path.relpath(os.path.join(d, x), root))
    return r


def check_png(path):
    with open(path, "rb") as f:
        data = f.read()
    if not data.startswith(b"\x89PNG\r\n\x1a\n") or b"IEND" not in data[-12:]:
        raise AssertionError(f"{path}: not a whole PNG")
    try:
        from PIL import Image
    except ImportError:
        return
    with Image.open(path) as im:
        im.load()


def check_outputs(out):
    """Everything written in out parses; summary.json lists existing files."""
    problems = []
    for d, _, files in os.walk(out):
        for f in files:
            p = os.path.join(d, f)
            try:
                if f.endswith((".vtu", ".vtm", ".pvd")):
                    ET.parse(p)
                elif f.endswith(".csv"):
                    with open(p, newline="", encoding="utf-8") as fh:
                        rows = list(csv.reader(fh))
                    if rows and len({len(r) for r in rows}) != 1:
                        raise AssertionError("rows of different lengths")
                elif f.endswith(".png"):
                    check_png(p)
                elif f == "summary.json":
                    with open(p, encoding="utf-8") as fh:
                        S = json.load(fh)
                    for g in S.get("files", []):
                        if not os.path.exists(os.path.join(d, g)):
                            raise AssertionError(f"lists {g!r}, which does not exist")
                elif f == "report.md":  # Markdown: names never split a row or carry controls
                    with open(p, encoding="utf-8") as fh:
                        text = fh.read()
                    if any(c in text for c in "\x00\x1b\x7f\r") or "<a x=" in text:
                        raise AssertionError("a control character or raw markup in the report")
                    rows = [l for l in text.splitlines() if l.startswith("| ")]
                    for l in rows:  # a row has as many unescaped '|' as its table's header
                        if l.replace("\\|", "").count("|") < 2:
                            raise AssertionError(f"a broken table row: {l[:80]!r}")
                elif ".tmp." in f:
                    raise AssertionError("a temporary file was left")
            except Exception as e:  # noqa: BLE001 - any failure to read is a finding
                problems.append(f"{os.path.relpath(p, out)!r}: {e}")
    return problems


TERMINAL_CONTROLS = ("\x1b", "\x07", "\x00", "\x7f", "\u009b")


def run(lsmbs, args, cwd, verbose):
    p = subprocess.run([lsmbs] + args, cwd=cwd, capture_output=True, timeout=600)
    err = p.stderr.decode("utf-8", "replace")
    out = p.stdout.decode("utf-8", "replace")
    # what reaches the terminal carries no control characters of the case's names (escape
    # sequences retitle, recolour or rewrite the terminal): they are printed as escapes
    for c in TERMINAL_CONTROLS:
        if c in out or c in err:
            return -1000, f"control character {c!r} printed to the terminal: " + (out + err)[:200]
    if verbose:
        print(f"  rc {p.returncode}: {' '.join(a[:40] for a in args)[:160]!r}")
    return p.returncode, err


def marks(root):
    return [os.path.join(d, f) for d, _, fs in os.walk(root) for f in fs if f.startswith("MARK")]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lsmbs", required=True)
    ap.add_argument("--quick", action="store_true", help="simulate and geometry only")
    ap.add_argument("-v", action="store_true")
    a = ap.parse_args()
    lsmbs = os.path.abspath(a.lsmbs)
    findings, runs = [], 0

    def one(label, args, work, out, allow_refusal):
        nonlocal runs
        runs += 1
        before = tree(work)
        rc, err = run(lsmbs, args, work, a.v)
        if marks(work) or marks(os.getcwd()):
            findings.append(f"{label}: a MARK file appeared (a string was run): {marks(work)}")
        new = {p for p in tree(work) - before
               if not (os.path.join(work, p) + os.sep).startswith(os.path.join(work, out) + os.sep)
               and os.path.join(work, p) != os.path.join(work, out)}
        if new:
            findings.append(f"{label}: files outside the output folder: {sorted(new)[:5]}")
        if rc == 2 and allow_refusal and err.startswith("lsmbs: error:"):
            return
        # verify's exit 1 is a verdict (a check of this 8-step case fails), with its report
        verdict = args[0] == "verify" and os.path.exists(os.path.join(work, out, "verify",
                                                                      "report.md"))
        if rc != 0 and not (rc == 1 and verdict):
            findings.append(f"{label}: exit {rc}: {err.strip()[:300]!r}")
            return
        if os.path.isdir(os.path.join(work, out)):
            for p in check_outputs(os.path.join(work, out)):
                findings.append(f"{label}: {p}")

    # 1. every name of the case, one class at a time
    for cls, h in HOSTILE.items():
        with tempfile.TemporaryDirectory() as work:
            names = {f: h + "·" + f for f in FIELDS}
            with open(os.path.join(work, "case.json"), "w", encoding="utf-8") as f:
                json.dump(plate_case(names), f, ensure_ascii=False)
            cmds = commands("case.json", "OUT")
            if a.quick:
                cmds = cmds[:1] + cmds[2:3]
            for c in cmds:
                one(f"names {cls}: {c[0]}", c, work, "OUT", allow_refusal=False)

    # 2. hostile output folders (a plain case)
    for cls, h in HOSTILE.items():
        if cls in ("nul", "paths", "dotdot", "long"):
            continue  # not a folder name of its own (NUL cannot be in argv; paths leave the work dir)
        with tempfile.TemporaryDirectory() as work:
            names = {f: f for f in FIELDS}
            with open(os.path.join(work, "case.json"), "w", encoding="utf-8") as f:
                json.dump(plate_case(names), f)
            out = "o" + h.replace("/", "_")
            for c in (["simulate", "case.json", "-o", out],
                      ["sensitivity", "case.json", "--method", "direct-analytic,fd-central",
                       "-o", out, "--overwrite"]):
                one(f"-o {cls}: {c[0]}", c, work, out, allow_refusal=False)
    # a folder name longer than the file system allows: refused as input
    with tempfile.TemporaryDirectory() as work:
        with open(os.path.join(work, "case.json"), "w", encoding="utf-8") as f:
            json.dump(plate_case({f: f for f in FIELDS}), f)
        rc, err = run(lsmbs, ["simulate", "case.json", "-o", "x" * 300], work, a.v)
        runs += 1
        if rc != 2 or "-o" not in err:
            findings.append(f"-o of 300 characters: exit {rc}, {err.strip()[:200]!r}")

    # 3. non-UTF-8: in a case file's name, in -o and in --set (refused up front, exit 2)
    with tempfile.TemporaryDirectory() as work:
        raw = json.dumps(plate_case({f: f for f in FIELDS})).replace(
            '"name": "case"', '"name": "bad\udcff"').encode("utf-8", "surrogateescape")
        with open(os.path.join(work, "case.json"), "wb") as f:
            f.write(raw)
        rc, err = run(lsmbs, ["simulate", "case.json", "-o", "o1"], work, a.v)
        runs += 1
        if rc != 2 or "case.json" not in err:
            findings.append(f"non-UTF-8 name in the case file: exit {rc}, {err.strip()[:200]!r}")
        with open(os.path.join(work, "ok.json"), "w", encoding="utf-8") as f:
            json.dump(plate_case({f: f for f in FIELDS}), f)
        bad = b"o\xff\xfe".decode("utf-8", "surrogateescape")
        for args, what in ((["simulate", "ok.json", "-o", bad], "-o"),
                           (["simulate", "ok.json", "-o", "o2", "--set", "/name=" + bad],
                            "--set")):
            rc, err = run(lsmbs, args, work, a.v)
            runs += 1
            if rc != 2 or "UTF-8" not in err:
                findings.append(f"non-UTF-8 {what}: exit {rc}, {err.strip()[:200]!r}")
        if tree(work) - {"case.json", "ok.json"}:
            findings.append(f"non-UTF-8: files written: {sorted(tree(work))}")

    print(f"hostile strings: {runs} runs, {len(HOSTILE)} classes, {len(findings)} findings")
    for f in findings:
        print("  FAIL " + f)
    return 1 if findings else 0


if __name__ == "__main__":
    sys.exit(main())
