#!/usr/bin/env python3
"""Crossover of the discrete adjoint against direct-analytic on the robot arm (issue 24).

Generates robot-arm cases from data/robot_arm/robot_arm_holes.json with N super-ellipse features
laid out on a regular grid over the plate, and times, in separate processes under
`/usr/bin/time -f "%e %U %M"` (wall s, user s, peak RSS KB):

  lsmbs simulate CASE                                          (the primal cost)
  lsmbs sensitivity CASE --method direct-analytic --threads 2
  lsmbs sensitivity CASE --method adjoint

each `--repeats` times (default 2; the machine may be shared: the smallest wall time is kept,
with the user time and peak RSS of that run). For every N the adjoint and direct gradients are
compared: per response, max_i |g_adjoint_i - g_direct_i| / max_i |g_direct_i|.

  bench/adjoint_crossover.py --lsmbs BIN --out DIR [--features 5,10,20,40] [--many 100]
  bench/adjoint_crossover.py --emit-case 20 FILE     # the N-feature case with an adjoint optimization
                                                     # (the shipped output strides kept)

Cases (identical to the shipped one apart from the design and the outputs):
  - the mesh, time horizon, h, model and the variable kinds/bounds of the shipped case: per
    feature cx (bounds of the shipped cx), a and b (bounds of the shipped a, b), xi = eta and cy
    fixed; N = 5 reproduces the shipped initial design exactly;
  - layout: r rows (a divisor of N close to sqrt(N / 10), so that the cells are about square on
    the 10:1 plate) of c = N / r features; centres span the shipped cx range (0.26-0.74 m) in x
    and are at the middle of r equal bands of the plate height in y; half-sizes
    a = min(shipped a, 0.35 dx), b = min(shipped b, 0.35 dy) so that the features' bounding
    boxes do not overlap at the initial design (checked);
  - responses: plate_mass and average_tip_deviation only (per_step responses and the max are
    removed); VTU output off (vtu_stride 0), so that `simulate` times the primal and its CSV.

Writes DIR/crossover.csv (features, variables, method, wall_s, user_s, peak_rss_mb, agreement;
agreement = on the adjoint rows, the largest per-response relative difference to direct),
DIR/agreement.csv (per response), DIR/crossover.json (every run, commands, load averages),
DIR/crossover.md (a table to paste) and DIR/crossover.png (matplotlib: wall time vs variables).

For the `--many` case the direct method is only run if a linear fit of the direct wall times of
the other cases predicts at most --direct-limit seconds (default 600), or with --force-direct.
Python 3 standard library only.
"""
import argparse
import json
import math
import os
import pathlib
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
BASE = ROOT / "data" / "robot_arm" / "robot_arm_holes.json"
KEEP_RESPONSES = ("plate_mass", "average_tip_deviation")
FILL = 0.35  # half-size / pitch: bounding boxes cover 70 % of the pitch, never overlap


def base_layout(base):
    """Variable bounds, the feature template and the plate extent from the shipped case."""
    var = {v["name"]: v for v in base["design"]["variables"]}
    geo = base["design"]["geometry"][0]
    feats = geo["features"]
    f0 = feats[0]
    cxs = [var[f["cx"]]["initial"] for f in feats]
    body = next(b for b in base["bodies"] if b["name"] == geo["body"])
    return {
        "var": var,
        "geo": geo,
        "template": f0,
        "cx_span": (min(cxs), max(cxs)),
        "cx_bounds": (var[f0["cx"]]["lower"], var[f0["cx"]]["upper"]),
        "a_init": var[f0["a"]]["initial"],
        "a_bounds": (var[f0["a"]]["lower"], var[f0["a"]]["upper"]),
        "b_init": var[f0["b"]]["initial"],
        "b_bounds": (var[f0["b"]]["lower"], var[f0["b"]]["upper"]),
        "y0": body["mesh"]["origin"][1],
        "height": body["mesh"]["size"][1],
    }


def rows_for(n):
    target = math.sqrt(n / 10.0)
    divisors = [d for d in range(1, n + 1) if n % d == 0]
    return min(divisors, key=lambda d: (abs(d - target), d))


def make_case(base, n, optimization=None, vtu_off=True):
    lay = base_layout(base)
    r = rows_for(n)
    c = n // r
    x0, x1 = lay["cx_span"]
    dx = (x1 - x0) / (c - 1) if c > 1 else (x1 - x0)
    dy = lay["height"] / r
    a = min(lay["a_init"], FILL * dx)
    b = min(lay["b_init"], FILL * dy)
    if not (2 * a < dx and 2 * b < dy):
        raise SystemExit(f"layout of {n} features overlaps")
    case = json.loads(json.dumps(base))
    case["name"] = f"robot_arm_{n}_features"
    variables, features = [], []
    k = 0
    for j in range(r):
        cy = 0.0 if r == 1 else lay["y0"] + (j + 0.5) * dy
        for i in range(c):
            k += 1
            cx = 0.5 * (x0 + x1) if c == 1 else x0 + i * dx
            variables += [
                {"name": f"cx{k}", "initial": round(cx, 12), "lower": lay["cx_bounds"][0], "upper": lay["cx_bounds"][1]},
                {"name": f"a{k}", "initial": round(a, 12), "lower": lay["a_bounds"][0], "upper": lay["a_bounds"][1]},
                {"name": f"b{k}", "initial": round(b, 12), "lower": lay["b_bounds"][0], "upper": lay["b_bounds"][1]},
            ]
            f = dict(lay["template"])
            f.update({"name": f"LS{k}", "cx": f"cx{k}", "cy": round(cy, 12), "a": f"a{k}", "b": f"b{k}"})
            features.append(f)
    case["design"]["variables"] = variables
    case["design"]["geometry"][0]["features"] = features
    case["description"] = (
        f"Robot arm of section 6 (data/robot_arm/robot_arm_holes.json: same model, mesh, time horizon) "
        f"with {n} super-ellipse features ({3 * n} design variables cx, a, b; bounds as the shipped ones) "
        f"on a regular {r} x {c} grid: cx from {x0} to {x1} m, a = {a:.6g} m, b = {b:.6g} m, "
        f"cy = {'0' if r == 1 else 'middle of ' + str(r) + ' bands of the plate height'}; "
        f"generated by bench/adjoint_crossover.py."
    )
    finish_case(case, optimization, vtu_off)
    return case, {"rows": r, "cols": c, "dx": dx, "dy": dy, "a": a, "b": b}


def finish_case(case, optimization, vtu_off):
    """The generated case's outputs and problem: plate_mass and average_tip_deviation only (no
    per-step responses), VTU off if asked, the given optimization section or none."""
    out = case["output"]
    out["responses"] = [
        x for x in out["responses"] if x["name"] in KEEP_RESPONSES and x.get("aggregate") != "per_step"
    ]
    if vtu_off:
        out["vtu_stride"] = 0
    if optimization is None:
        case.pop("optimization", None)
    else:
        case["optimization"] = optimization


def timed(cmd, tfile):
    load = open("/proc/loadavg").read().split()[:3]
    t0 = time.time()
    p = subprocess.run(["/usr/bin/time", "-o", str(tfile), "-f", "%e %U %M", *cmd], capture_output=True, text=True)
    if p.returncode != 0:
        sys.stderr.write(p.stdout + p.stderr)
        raise SystemExit(f"failed ({p.returncode}): {' '.join(cmd)}")
    line = pathlib.Path(tfile).read_text().strip().splitlines()[-1]
    wall, user, rss = line.split()
    return {"wall_s": float(wall), "user_s": float(user), "peak_rss_mb": float(rss) / 1024.0,
            "loadavg_before": load, "elapsed_python_s": time.time() - t0}


def agreement(direct, adjoint):
    res = {}
    for resp, gd in direct.items():
        ga = adjoint[resp]
        scale = max(abs(v) for v in gd.values())
        diff = max(abs(ga[k] - gd[k]) for k in gd)
        res[resp] = diff / scale if scale > 0 else diff
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--lsmbs", help="lsmbs binary")
    ap.add_argument("--out", help="output folder")
    ap.add_argument("--features", default="5,10,20,40")
    ap.add_argument("--many", type=int, default=100, help="features of the many-variable case (0: none)")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--direct-limit", type=float, default=600.0)
    ap.add_argument("--force-direct", action="store_true")
    ap.add_argument("--emit-case", nargs=2, metavar=("N", "FILE"),
                    help="write the N-feature case with the shipped optimization (sensitivity: adjoint) and exit")
    args = ap.parse_args()
    base = json.loads(BASE.read_text())

    if args.emit_case:
        n, path = int(args.emit_case[0]), args.emit_case[1]
        opt = json.loads(json.dumps(base["optimization"]))
        opt["sensitivity"] = {"method": "adjoint"}
        case, _ = make_case(base, n, optimization=opt, vtu_off=False)
        case["description"] += (" Responses plate_mass and average_tip_deviation only; the optimization of the shipped "
                                "case (objective, constraint, MMA, stop rules) with the discrete adjoint sensitivities.")
        pathlib.Path(path).write_text(json.dumps(case, indent=1) + "\n")
        return
    if not args.lsmbs or not args.out:
        ap.error("--lsmbs and --out are required")

    binary = os.path.abspath(args.lsmbs)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "cases").mkdir(exist_ok=True)
    (out / "runs").mkdir(exist_ok=True)
    version = subprocess.run([binary, "--version"], capture_output=True, text=True).stdout.strip()

    counts = [int(x) for x in args.features.split(",") if x]
    plan = [(n, False) for n in counts]
    if args.many:
        plan.append((args.many, True))

    methods = {
        "primal": lambda c, d: [binary, "simulate", c, "-o", d, "-q", "--overwrite"],
        "direct-analytic": lambda c, d: [binary, "sensitivity", c, "--method", "direct-analytic", "--threads", "2",
                                         "-o", d, "-q", "--overwrite"],
        "adjoint": lambda c, d: [binary, "sensitivity", c, "--method", "adjoint", "-o", d, "-q", "--overwrite"],
    }
    record = {"binary": binary, "version": version, "command": " ".join(sys.argv), "repeats": args.repeats,
              "cases": []}
    rows, agree_rows = [], []
    for n, many in plan:
        case, layout = make_case(base, n)
        cfile = out / "cases" / f"robot_arm_{n}_features.json"
        cfile.write_text(json.dumps(case, indent=1) + "\n")
        nv = 3 * n
        entry = {"features": n, "variables": nv, "layout": layout, "case": str(cfile), "runs": {}}
        todo = ["primal", "direct-analytic", "adjoint"]
        if many and not args.force_direct:
            pts = [(r["variables"], r["wall_s"]) for r in rows if r["method"] == "direct-analytic"]
            if len(pts) >= 2:
                mx = sum(p[0] for p in pts) / len(pts)
                my = sum(p[1] for p in pts) / len(pts)
                sxx = sum((p[0] - mx) ** 2 for p in pts)
                slope = sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx if sxx else 0.0
                pred = my + slope * (nv - mx)
                entry["direct_predicted_wall_s"] = pred
                if pred > args.direct_limit:
                    todo.remove("direct-analytic")
                    entry["direct_skipped"] = f"predicted {pred:.0f} s > {args.direct_limit:.0f} s"
                    print(f"  {n} features: direct-analytic skipped (predicted {pred:.0f} s)", flush=True)
        for m in todo:
            best = None
            for rep in range(args.repeats):
                d = out / "runs" / f"n{n}" / f"{m}_{rep}"
                d.parent.mkdir(parents=True, exist_ok=True)
                cmd = methods[m](str(cfile), str(d))
                t = timed(cmd, out / "runs" / f"n{n}" / f"{m}_{rep}.time")
                t["command"] = " ".join(cmd)
                summ = json.loads((d / "summary.json").read_text())
                t["summary_wall_seconds"] = summ.get("wall_seconds")
                if m != "primal":
                    t["gradients"] = summ["gradients"]
                    t["counts"] = summ.get("counts", {})
                    t["warnings"] = summ.get("warnings", [])
                entry["runs"].setdefault(m, []).append({k: v for k, v in t.items() if k != "gradients"})
                print(f"  {n:4d} features {nv:4d} vars {m:16s} run {rep + 1}: {t['wall_s']:8.2f} s wall "
                      f"{t['user_s']:8.2f} s user {t['peak_rss_mb']:8.1f} MB", flush=True)
                if best is None or t["wall_s"] < best["wall_s"]:
                    best = t
            entry[m] = best
        agree = None
        if "direct-analytic" in entry and "adjoint" in entry:
            agree = agreement(entry["direct-analytic"]["gradients"], entry["adjoint"]["gradients"])
            entry["agreement"] = agree
            for resp, v in agree.items():
                agree_rows.append((n, nv, resp, v))
        for m in ("primal", "direct-analytic", "adjoint"):
            if m not in entry:
                continue
            b = entry[m]
            ag = ""
            if m == "adjoint" and agree is not None:
                ag = f"{max(agree.values()):.3e}"
            elif m == "adjoint":
                ag = "direct not run"
            rows.append({"features": n, "variables": nv, "method": m, "wall_s": b["wall_s"], "user_s": b["user_s"],
                         "peak_rss_mb": b["peak_rss_mb"], "agreement": ag})
        for m in ("direct-analytic", "adjoint"):
            if m in entry:
                entry[m] = {k: v for k, v in entry[m].items() if k != "gradients"}
        record["cases"].append(entry)

    with open(out / "crossover.csv", "w") as f:
        f.write("features,variables,method,wall_s,user_s,peak_rss_mb,agreement\n")
        for r in rows:
            f.write(f"{r['features']},{r['variables']},{r['method']},{r['wall_s']:.2f},{r['user_s']:.2f},"
                    f"{r['peak_rss_mb']:.1f},{r['agreement']}\n")
    with open(out / "agreement.csv", "w") as f:
        f.write("features,variables,response,max_rel_diff\n")
        for n, nv, resp, v in agree_rows:
            f.write(f"{n},{nv},{resp},{v:.3e}\n")
    (out / "crossover.json").write_text(json.dumps(record, indent=1) + "\n")

    # Markdown table: one line per case
    lines = ["| features | variables | primal (simulate) | direct-analytic | adjoint | adjoint / primal | "
             "direct / primal | peak RSS primal / direct / adjoint | adjoint memory | max rel. diff adjoint-direct |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for e in record["cases"]:
        p, d, a = e["primal"], e.get("direct-analytic"), e["adjoint"]
        def cell(x):
            return f"{x['wall_s']:.2f} s ({x['user_s']:.2f} s user)" if x else "not run"
        mem = a.get("counts", {}).get("adjoint_memory_bytes")
        lines.append(
            f"| {e['features']} | {e['variables']} | {cell(p)} | {cell(d)} | {cell(a)} | "
            f"{a['wall_s'] / p['wall_s']:.2f} | {(d['wall_s'] / p['wall_s']) if d else float('nan'):.2f} | "
            f"{p['peak_rss_mb']:.0f} / {d['peak_rss_mb'] if d else float('nan'):.0f} / {a['peak_rss_mb']:.0f} MB | "
            f"{(mem or 0) / 2**20:.1f} MiB | "
            + (", ".join(f"{k} {v:.1e}" for k, v in e["agreement"].items()) if "agreement" in e else "direct not run")
            + " |")
    (out / "crossover.md").write_text("\n".join(lines) + "\n")

    # Plot (matplotlib, no script interpreter: the output path is only ever a file name)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(9, 6))
    styles = {"direct-analytic": ("o-", "direct-analytic (--threads 2)"),
              "adjoint": ("s-", "discrete adjoint"), "primal": ("^--", "primal (simulate)")}
    for m, (style, label) in styles.items():
        pts = sorted((r["variables"], r["wall_s"]) for r in rows if r["method"] == m)
        if pts:
            ax.plot(*zip(*pts), style, lw=2, label=label)
    ax.set_xscale("log")
    ax.set_xlim(10, 500)
    ax.set_ylim(bottom=0)
    ax.grid(True)
    ax.legend(loc="upper left")
    ax.set_title("Robot arm, 500 steps: wall time of one gradient (2 responses) vs number of "
                 "design variables", fontsize=10)
    ax.set_xlabel("design variables n_v (3 per super-ellipse feature)")
    ax.set_ylabel(f"wall time [s] (smallest of {args.repeats} runs)")
    fig.savefig(out / "crossover.png", dpi=100)
    print((out / "crossover.md").read_text())


if __name__ == "__main__":
    main()
