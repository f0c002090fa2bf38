#!/usr/bin/env python3
"""Cost of the discrete adjoint over the primal with many design variables, whole process.

Cases: the robot arm of section 6 (data/robot_arm/robot_arm_holes.json: model, mesh, time
horizon; responses plate_mass and average_tip_deviation only, VTU off) with
  - `grid N`: N super-ellipse features of 3 variables on a regular grid
    (bench/adjoint_crossover.py's layout; N = 100 is its 300-variable case);
  - `bspline H M`: H closed B-spline holes of M control points each (2 H M variables) in a row
    (two rows when H > 10) of equal cells over the plate; each hole starts as an ellipse of
    0.3 × the cell, and every control-point coordinate may move within ±0.45 of the cell about its
    hole's centre, so that the curve (inside its control points' hull) stays in its cell.

Each command runs in its own process under `/usr/bin/time -f "%e %U %M"`, `--repeats` times;
the smallest wall time is kept. Writes DIR/freeform_cost.json and DIR/freeform_cost.md.

  bench/freeform_cost.py --lsmbs BIN --out DIR [--cases grid:100,bspline:10:15,bspline:20:25]
  bench/freeform_cost.py --emit bspline:5:10[:INIT:XB:YB] FILE [--optimize]   # one case, exit
(INIT: the starting ellipse's size, XB, YB: the control points' bounds, in cells; default
0.3, 0.45, 0.45.)
"""
import argparse
import json
import math
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "bench"))
import adjoint_crossover as ac  # noqa: E402


def bspline_case(base, holes, points, optimization=None, vtu_off=True, init=0.3, xbound=0.45,
                 ybound=0.45):
    lay = ac.base_layout(base)
    rows = 1 if holes <= 10 else 2
    cols = math.ceil(holes / rows)
    x0, x1 = 0.2, 0.8  # the plate: 0.2 … 0.8 m in the design frame of the shipped case
    x0 += 0.06
    x1 -= 0.06
    dx = (x1 - x0) / cols
    dy = lay["height"] / rows
    case = json.loads(json.dumps(base))
    case["name"] = f"robot_arm_{holes}_bsplines_{points}_points"
    variables, features = [], []
    k = 0
    for j in range(rows):
        cy = lay["y0"] + (j + 0.5) * dy
        for i in range(cols):
            if k == holes:
                break
            k += 1
            cx = x0 + (i + 0.5) * dx
            pts = []
            for m in range(points):
                t = 2 * math.pi * m / points
                for axis, (c, half, v) in enumerate(((cx, dx, math.cos(t)), (cy, dy, math.sin(t)))):
                    name = f"{'xy'[axis]}{k}_{m + 1}"
                    bound = (xbound, ybound)[axis]
                    variables.append({"name": name, "initial": round(c + init * half * v, 12),
                                      "lower": round(c - bound * half, 12),
                                      "upper": round(c + bound * half, 12)})
                    pts.append(name)
            features.append({"name": f"B{k}", "type": "bspline",
                             "control_points": [pts[2 * m:2 * m + 2] for m in range(points)]})
    case["design"]["variables"] = variables
    case["design"]["geometry"][0]["features"] = features
    case["description"] = (
        f"Robot arm of section 6 (data/robot_arm/robot_arm_holes.json: same model, mesh, time "
        f"horizon) with {holes} closed B-spline holes of {points} control points "
        f"({2 * holes * points} design variables: every control point's x and y) in {rows} row(s) "
        f"of cells {dx:.4g} m x {dy:.4g} m; each starts as an ellipse of {init} x its cell, its "
        f"control points move within +-{xbound} of the cell in x and +-{ybound} in y; generated "
        f"by bench/freeform_cost.py.")
    ac.finish_case(case, optimization, vtu_off)
    return case


def make(base, spec, **kw):
    kind, *n = spec.split(":")
    if kind == "grid":
        case, _ = ac.make_case(base, int(n[0]), **kw)
        return case, 3 * int(n[0])
    if kind == "bspline":
        h, m = int(n[0]), int(n[1])
        shape = dict(zip(("init", "xbound", "ybound"), map(float, n[2:5])))
        return bspline_case(base, h, m, **kw, **shape), 2 * h * m
    raise SystemExit(f"unknown case {spec!r} (grid:N or bspline:H:M)")


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--lsmbs")
    ap.add_argument("--out")
    ap.add_argument("--cases", default="grid:100,bspline:10:15,bspline:20:25")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--emit", nargs=2, metavar=("CASE", "FILE"))
    ap.add_argument("--optimize", action="store_true",
                    help="with --emit: the shipped optimization, adjoint sensitivities, VTU on")
    args = ap.parse_args()
    base = json.loads(ac.BASE.read_text())
    if args.emit:
        opt = None
        if args.optimize:
            opt = json.loads(json.dumps(base["optimization"]))
            opt["sensitivity"] = {"method": "adjoint"}
        case, _ = make(base, args.emit[0], optimization=opt, vtu_off=not args.optimize)
        pathlib.Path(args.emit[1]).write_text(json.dumps(case, indent=1) + "\n")
        return
    if not args.lsmbs or not args.out:
        ap.error("--lsmbs and --out are required")
    binary = str(pathlib.Path(args.lsmbs).resolve())
    out = pathlib.Path(args.out)
    (out / "cases").mkdir(parents=True, exist_ok=True)
    version = subprocess.run([binary, "--version"], capture_output=True, text=True).stdout.strip()
    record = {"binary": binary, "version": version, "command": " ".join(sys.argv), "cases": []}
    lines = ["| case | variables | primal (`simulate`) | adjoint | adjoint / primal | "
             "peak RSS primal / adjoint | mapping with derivatives |",
             "|---|---|---|---|---|---|---|"]
    for spec in args.cases.split(","):
        case, nv = make(base, spec)
        cfile = out / "cases" / (spec.replace(":", "_") + ".json")
        cfile.write_text(json.dumps(case, indent=1) + "\n")
        entry = {"case": spec, "variables": nv, "file": str(cfile)}
        for m, extra in (("primal", ["simulate"]), ("adjoint", ["sensitivity", "--method", "adjoint"])):
            best = None
            for rep in range(args.repeats):
                d = out / "runs" / spec.replace(":", "_") / f"{m}_{rep}"
                d.parent.mkdir(parents=True, exist_ok=True)
                cmd = [binary, extra[0], str(cfile), *extra[1:], "-o", str(d), "-q", "--overwrite"]
                t = ac.timed(cmd, d.parent / f"{m}_{rep}.time")
                t["command"] = " ".join(cmd)
                if m == "adjoint":
                    t["timings"] = json.loads((d / "summary.json").read_text()).get("timings", {})
                print(f"  {spec:16s} {nv:5d} vars {m:8s} run {rep + 1}: {t['wall_s']:7.2f} s wall "
                      f"{t['user_s']:7.2f} s user {t['peak_rss_mb']:6.1f} MB", flush=True)
                if best is None or t["wall_s"] < best["wall_s"]:
                    best = t
            entry[m] = best
        g = subprocess.run(["/usr/bin/time", "-f", "%e", binary, "geometry", str(cfile), "-o",
                            str(out / "runs" / spec.replace(":", "_") / "geometry"), "-q",
                            "--overwrite"], capture_output=True, text=True)
        entry["geometry_wall_s"] = float(g.stderr.strip().splitlines()[-1]) if g.returncode == 0 \
            else None
        record["cases"].append(entry)
        p, a = entry["primal"], entry["adjoint"]
        lines.append(f"| {spec} | {nv} | {p['wall_s']:.2f} s ({p['user_s']:.2f} s user) | "
                     f"{a['wall_s']:.2f} s ({a['user_s']:.2f} s user) | "
                     f"{a['wall_s'] / p['wall_s']:.2f} | {p['peak_rss_mb']:.0f} / "
                     f"{a['peak_rss_mb']:.0f} MB | `geometry` {entry['geometry_wall_s']} s |")
    (out / "freeform_cost.json").write_text(json.dumps(record, indent=1) + "\n")
    (out / "freeform_cost.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
