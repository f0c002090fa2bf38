#!/usr/bin/env python3
"""Exports a designed body to DXF, SVG, STEP and a body-fitted Gmsh mesh (python/lsmbs/export.py),
from the shape file `lsmbs geometry` and `lsmbs optimize` write (OUT/<body>_shape.json,
OUT/final_design/<body>_shape.json):

    python3 scripts/export_design.py OUT/final_design/plate_shape.json -o OUT/cad
    python3 scripts/export_design.py SHAPE.json -o DIR --formats dxf,svg --size 0.0025
    python3 scripts/export_design.py SHAPE.json -o DIR --case CASE.json   # also a case file of
        # the body-fitted design (DIR/<case>_body_fitted.json) that `lsmbs simulate` runs
    python3 scripts/export_design.py OUT/plate_shape.json -o DIR   # a solid body's design
        # ("kind": "solid"): STEP and its mid-section's picture (the default --formats becomes
        # step,png; msh, a body-fitted hexahedral mesh of a through-hole design, needs --size)

Needs Debian's python3-ezdxf and python3-gmsh (scripts/setup-deps.sh); not the compiled lsmbs
module. Exit 2 for a bad argument or shape file, with what was expected.
"""
import argparse
import importlib.util
import json
import os
import pathlib
import sys

HERE = pathlib.Path(__file__).resolve().parent


def load_export():
    spec = importlib.util.spec_from_file_location("lsmbs_export", HERE.parent / "python/lsmbs/export.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("shape", help="a <body>_shape.json file")
    ap.add_argument("-o", "--out", required=True, help="output folder")
    ap.add_argument("--formats", default=None,
                    help="comma-separated dxf, svg, step, msh (default: all four); a solid's: step, "
                    "png, msh (default: step,png)")
    ap.add_argument("--size", type=float, default=None,
                    help="element size of the body-fitted mesh [m] (default: the fixed mesh's)")
    ap.add_argument("--case", default=None,
                    help="the case file of the design: also write a case with the body-fitted mesh")
    a = ap.parse_args()

    def fail(msg):
        sys.exit(print("export_design: " + msg, file=sys.stderr) or 2)

    if a.size is not None and not a.size > 0:
        fail("--size: expected a positive length in m")
    try:
        shape = json.loads(pathlib.Path(a.shape).read_text())
        if not isinstance(shape, dict):
            raise ValueError("expected a JSON object (a <body>_shape.json of lsmbs geometry)")
        solid = shape.get("kind") == "solid"
        keys = (("body", "domain", "features", "region") if solid else
                ("body", "outline", "features", "region", "node_sets", "thickness", "element_size"))
        for key in keys:
            if key not in shape:
                raise ValueError("no \"%s\" (expected the <body>_shape.json that lsmbs geometry "
                                 "writes for a %s body)" % (key, "solid" if solid else "planar"))
    except (OSError, ValueError) as e:
        fail("%s: %s" % (a.shape, e))
    formats = [f for f in (a.formats or ("step,png" if solid else "dxf,svg,step,msh")).split(",")
               if f]
    known = ("step", "png", "msh") if solid else ("dxf", "svg", "step", "msh")
    bad = [f for f in formats if f not in known]
    if bad:
        fail("--formats: %s not written for a %s body's design (expected %s)" %
             (", ".join(bad), "solid" if solid else "planar", ", ".join(known)))
    if solid and (a.case or "msh" in formats) and a.size is None:
        fail("%s is a solid body's design: its body-fitted hexahedral mesh (msh, --case) needs "
             "--size" % a.shape)
    if a.case and "msh" not in formats:
        formats.append("msh")
    ex = load_export()
    out = ex.export(shape, a.out, formats, a.size)
    if a.case:
        stem = pathlib.Path(a.case).stem
        out["case"] = ex.body_fitted_case(a.case, shape["body"], out["msh"],
                                          os.path.join(a.out, stem + "_body_fitted.json"))
    for k, v in out.items():
        if k in ("dxf", "svg", "step", "png", "msh", "case"):
            print("%-5s %s" % (k, v))
    for name, curves in out.get("node_sets", {}).items():
        if not curves:
            print("warning: node set '%s' lies along no boundary curve of the design: the "
                  "body-fitted mesh has no such set" % name, file=sys.stderr)
    for n in out["notes"]:
        print("note:", n, file=sys.stderr)


if __name__ == "__main__":
    main()
