#!/usr/bin/env python3
"""Redraws the design pictures of result folders with the current `lsmbs geometry`.

Each design folder (a folder holding a summary.json written by `lsmbs geometry`: an optimization's
final_design/, the fig8/iter_*/ snapshots) is mapped again from the design and case its summary
names, at the width of its PNG, and replaced only when the new mapping gives the same mass as the
old one (relative 1e-12): the geometry, not the picture, must be what the result was.

  python3 paper_results/redraw_designs.py [--lsmbs build/src/lsmbs] FOLDER...
  (each FOLDER is searched for design folders)
"""
import argparse
import json
import pathlib
import shutil
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent


def design_folders(top):
    for s in sorted(pathlib.Path(top).rglob("summary.json")):
        doc = json.loads(s.read_text())
        if str(doc.get("command", "")).split(" ")[0].endswith("geometry") or \
                " geometry " in str(doc.get("command", "")):
            yield s.parent, doc


def case_path(doc):
    p = pathlib.Path(doc["case_file"])
    if not p.is_absolute():
        p = ROOT / p
    return p.resolve()


def png_width(folder):
    from PIL import Image
    pngs = sorted(folder.glob("*.png"))
    return Image.open(pngs[0]).size[0] if pngs else 1600


def redraw(lsmbs, folder, doc):
    with tempfile.TemporaryDirectory() as tmp:
        out = pathlib.Path(tmp) / "g"
        cmd = [lsmbs, "geometry", str(case_path(doc)), "-o", str(out), "-q",
               "--width", str(png_width(folder))]
        for name, value in doc["design"].items():
            cmd += ["--set", f"{name}={value!r}"]
        subprocess.run(cmd, check=True)
        new = json.loads((out / "summary.json").read_text())
        for a, b in zip(doc["bodies"], new["bodies"]):
            if abs(a["mass"] - b["mass"]) > 1e-12 * abs(a["mass"]):
                raise SystemExit(f"{folder}: mass {b['mass']!r} differs from the result's "
                                 f"{a['mass']!r}: the case's geometry changed; not redrawn")
        for f in folder.iterdir():
            if f.is_file():
                f.unlink()
        for f in out.iterdir():
            shutil.copy2(f, folder / f.name)
    print(f"{folder}: redrawn (mass {new['bodies'][0]['mass']:.9g} kg unchanged)")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lsmbs", default=str(ROOT / "build" / "src" / "lsmbs"))
    ap.add_argument("folders", nargs="+")
    a = ap.parse_args()
    for top in a.folders:
        for folder, doc in design_folders(top):
            redraw(a.lsmbs, folder, doc)
    return 0


if __name__ == "__main__":
    sys.exit(main())
