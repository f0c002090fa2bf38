#!/usr/bin/env python3
"""Are the stored results in paper_results/ what the current code gives? Each folder's
summary.json records the command that made it; this runs that command again with the given lsmbs
into a scratch folder and compares the final objective, the constraint violation, the number of
evaluations and the final design with the stored ones. Writes a table (Markdown) and exits 1 when
a stored result differs from the re-run beyond --rtol (0 when all agree, 2 for bad arguments).

    python3 scripts/check_paper_results.py --lsmbs build/src/lsmbs [--only robot_arm_mma,...]
        [--rtol 1e-6] [--report paper_results/freshness.md] [--write]

--write regenerates instead: each folder is re-run into a scratch folder and the files the new
run's summary.json lists replace the stored ones (nothing else is touched), then the tables made from the folders
(robot_arm_tables.py → <folder>/tables.md, slider_crank_tables.py → slider_crank_tables.md). The
table still says what changed against the stored result. README's numbers are then to be read off
the new tables.

Long (every shipped optimization, about an hour on two cores): .ci/scheduled runs it. A folder
whose command is not `lsmbs optimize` (or has no summary.json) is listed as not checked.
"""
import argparse
import json
import pathlib
import shlex
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent


def rerun_command(command, lsmbs, out):
    """The stored command with this lsmbs, the output in `out`, quiet and overwriting."""
    words = shlex.split(command)
    if len(words) < 2 or words[1] != "optimize":
        return None
    args, skip = [], False
    for k, w in enumerate(words[2:]):
        if skip:
            skip = False
            continue
        if w in ("-o", "--output"):
            skip = True
            continue
        if w.startswith("--output="):
            continue
        args.append(w)
    return [lsmbs, "optimize", *args, "-o", str(out), "-q", "--overwrite"]


def compare(stored, fresh, rtol):
    """Differences between two optimize summaries, in words (empty: the same result)."""
    diffs = []
    if "ranking" in stored or "ranking" in fresh:  # a multi-start: the best start
        a, b = stored.get("ranking", {}), fresh.get("ranking", {})
        for key in ("best", "best_start", "median", "worst"):
            x, y = a.get(key), b.get(key)
            if isinstance(x, float) and isinstance(y, float):
                if abs(x - y) > rtol * max(abs(x), abs(y)):
                    diffs.append("%s %.9g → %.9g" % (key, x, y))
            elif x != y:
                diffs.append("%s %s → %s" % (key, x, y))
        return diffs
    fs, ff = stored.get("final", {}), fresh.get("final", {})
    for key in ("objective", "max_violation"):
        x, y = fs.get(key), ff.get(key)
        if x is None or y is None or abs(x - y) > rtol * max(abs(x), abs(y), 1e-300):
            diffs.append("final %s %s → %s" % (key, x, y))
    es = stored.get("counts", {}).get("evaluations")
    ef = fresh.get("counts", {}).get("evaluations")
    if es != ef:
        diffs.append("evaluations %s → %s" % (es, ef))
    ds, df = fs.get("design", {}), ff.get("design", {})
    worst = max((abs(ds[k] - df.get(k, float("nan"))) for k in ds), default=0.0)
    if not worst <= rtol * max(1.0, max((abs(v) for v in ds.values()), default=1.0)):
        diffs.append("final design moved by up to %.3g" % worst)
    return diffs


def remake_tables(lsmbs):
    """The tables made from the folders (paper_results/README.md says which)."""
    pr = ROOT / "paper_results"
    for name in ("robot_arm_mma", "robot_arm_ccsaq"):
        if (pr / name / "summary.json").is_file():
            subprocess.run([sys.executable, str(pr / "robot_arm_tables.py"), str(pr / name),
                            str(pr / name / "tables.md")], cwd=ROOT, check=True)
    subprocess.run([sys.executable, str(pr / "slider_crank_tables.py"), str(pr / "slider_crank_1hole"),
                    str(pr / "slider_crank_3holes"), str(pr / "slider_crank_tables.md"),
                    "--lsmbs", lsmbs], cwd=ROOT, check=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--lsmbs", required=True)
    ap.add_argument("--only", default="", help="comma-separated folder names")
    ap.add_argument("--rtol", type=float, default=1e-6)
    ap.add_argument("--report", default=None, help="write the Markdown table here too")
    ap.add_argument("--write", action="store_true",
                    help="regenerate: re-run each folder in place and remake the tables")
    a = ap.parse_args()
    lsmbs = pathlib.Path(a.lsmbs)
    if not lsmbs.is_file():
        print("check_paper_results: --lsmbs: no file %s" % lsmbs, file=sys.stderr)
        return 2
    only = {x for x in a.only.split(",") if x}
    folders = sorted(p for p in (ROOT / "paper_results").iterdir() if p.is_dir())
    unknown = only - {p.name for p in folders}
    if unknown:
        print("check_paper_results: --only: no folder %s in paper_results/" % ", ".join(sorted(unknown)),
              file=sys.stderr)
        return 2
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip() or "unknown"
    rows, stale = [], 0
    scratch = pathlib.Path(tempfile.mkdtemp(prefix="lsmbs_paper_results_"))
    for folder in folders:
        if only and folder.name not in only:
            continue
        summary = folder / "summary.json"
        if not summary.is_file():
            rows.append((folder.name, "not checked", "no summary.json", ""))
            continue
        stored = json.loads(summary.read_text())
        cmd = rerun_command(stored.get("command", ""), str(lsmbs.resolve()), scratch / folder.name)
        if cmd is None:
            rows.append((folder.name, "not checked", "its command is not `lsmbs optimize`", ""))
            continue
        t0 = time.monotonic()
        p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
        wall = "%.0f s" % (time.monotonic() - t0)
        fresh_file = scratch / folder.name / "summary.json"
        if p.returncode not in (0, 1) or not fresh_file.is_file():
            rows.append((folder.name, "failed", "exit %d: %s" % (p.returncode, p.stderr.strip()[-200:]), wall))
            stale += 1
            continue
        fresh = json.loads(fresh_file.read_text())
        diffs = compare(stored, fresh, a.rtol)
        stale += bool(diffs)
        if a.write:  # the run's own files (its summary lists them) replace the stored ones
            for name in [*fresh.get("files", []), "summary.json"]:
                src, dst = scratch / folder.name / name, folder / name
                if src.is_dir():
                    shutil.copytree(src, dst, dirs_exist_ok=True)
                elif src.is_file():
                    dst.parent.mkdir(parents=True, exist_ok=True)
                    shutil.copy2(src, dst)
        rows.append((folder.name, "differs" if diffs else "same", "; ".join(diffs), wall))
        print("%-40s %s %s" % (folder.name, rows[-1][1], rows[-1][2]), flush=True)
    if a.write:
        remake_tables(str(lsmbs.resolve()))
    lines = ["# Stored results against a re-run", "",
             "`python3 scripts/check_paper_results.py --lsmbs build/src/lsmbs` at commit %s "
             "(relative tolerance %g)." % (commit, a.rtol), "",
             "| folder | result | differences | re-run time |", "|---|---|---|---|"]
    lines += ["| %s | %s | %s | %s |" % r for r in rows]
    text = "\n".join(lines) + "\n"
    print(text)
    if a.report:
        pathlib.Path(a.report).write_text(text)
    return 1 if stale else 0


if __name__ == "__main__":
    sys.exit(main())
