#!/usr/bin/env python3
"""Writes a planar case as a spatial one ("dimension": 3, all motion in z = 0), for comparing the
two formulations on the same mechanism (python/lsmbs/planar.py says how each kind is written):

    python3 scripts/planar_to_spatial.py data/andrews/andrews_squeezer.json -o andrews_3d.json
    lsmbs sensitivity andrews_3d.json -o out3d --method direct-analytic

Needs no compiled module. Exit 2, with the JSON path and the reason, for a case that has parts
without a spatial counterpart here (flexible bodies, point masses, pressure loads, …).
"""
import argparse
import importlib.util
import json
import pathlib
import sys

HERE = pathlib.Path(__file__).resolve().parent


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case", help="a planar case file")
    ap.add_argument("-o", "--output", required=True, help="the spatial case file to write")
    ap.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    a = ap.parse_args()
    spec = importlib.util.spec_from_file_location("lsmbs_planar", HERE.parent / "python/lsmbs/planar.py")
    planar = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(planar)
    src, dst = pathlib.Path(a.case), pathlib.Path(a.output)
    try:
        doc = json.loads(src.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        print(f"error: {src}: {e}", file=sys.stderr)
        return 2
    if dst.is_dir():
        print(f"error: -o {dst}: a folder; expected a file name", file=sys.stderr)
        return 2
    if not dst.parent.is_dir():
        print(f"error: -o {dst}: the folder {dst.parent} does not exist", file=sys.stderr)
        return 2
    if dst.exists() and not a.overwrite:
        print(f"error: {dst} exists (give --overwrite to replace it)", file=sys.stderr)
        return 2
    try:
        out, notes = planar.to_spatial(doc, source=src.name, src_dir=str(src.parent.resolve()),
                                       out_dir=str(dst.parent.resolve()))
    except (ValueError, KeyError, TypeError, AttributeError, IndexError) as e:
        print(f"error: {src}: {e}", file=sys.stderr)
        return 2
    for n in notes:
        print(f"note: {n}", file=sys.stderr)
    tmp = dst.with_name(dst.name + ".tmp")
    try:
        tmp.write_text(json.dumps(out, indent=1) + "\n")
        tmp.replace(dst)
    except OSError as e:
        tmp.unlink(missing_ok=True)
        print(f"error: -o {dst}: {e}", file=sys.stderr)
        return 2
    print(f"wrote {dst}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
