#!/usr/bin/env python3
"""Tables 1 and 3 of Tromme et al. (slider-crank connecting rod, section 5) side by side with
`lsmbs optimize` runs, and the topology evolution of Fig. 8.

usage: slider_crank_tables.py ONE_HOLE_OUT THREE_HOLES_OUT [TABLES.md] [--lsmbs PATH]

ONE_HOLE_OUT and THREE_HOLES_OUT are the output folders of
    lsmbs optimize data/slider_crank/slider_crank_1hole.json -o ONE_HOLE_OUT
    lsmbs optimize data/slider_crank/slider_crank_3holes.json -o THREE_HOLES_OUT
The maximum elongation of a design is the largest per-step constraint value (summary.json
"constraints_max", in m). For Fig. 8 the script maps
the designs of selected iterations with `lsmbs geometry` into THREE_HOLES_OUT/fig8/.
"""
import argparse
import csv
import json
import os
import subprocess

BOUND_UM = 16.0
PAPER_T1 = {"mass": (295.664, 271.337), "elong": (13.508, 15.996), "p": (0.001, 0.0819), "iterations": 7}
PAPER_T3 = {"mass": (293.832, 261.348), "elong": (13.612, 15.996), "iterations": 18,
            "p": [("p1", 0.01, 0.0573, "0 - 0.08"), ("p2", 0.015, 0.0761, "0 - 0.095"),
                  ("p3", 0.0875, 0.06906, "0.0668 - 0.0968"), ("p4", 0.003, 0.000973, "0 - 0.004"),
                  ("p5", 0.0493, 0.0430, "0.0418 - 0.0718")]}


def load(out):
    s = json.load(open(os.path.join(out, "summary.json")))
    h = list(csv.DictReader(open(os.path.join(out, "history.csv"))))
    return s, h


def elong_um(raw_max):
    return 1e6 * raw_max


def pct(ours, paper):
    return f"{100 * (ours / paper - 1):+.2f} %"


def header(s):
    return (f"Run: `{s['command']}` (commit {s['git_commit']}, case SHA-256 {s['case_sha256'][:12]}…), "
            f"optimizer {s['options']['optimization']['optimizer']}, {s['counts']['evaluations']} simulations, "
            f"stop: {s['nlopt']['status']}.")


def table1(out):
    s, h = load(out)
    m0, m1 = 1e3 * s["initial"]["objective"], 1e3 * s["final"]["objective"]
    e0, e1 = elong_um(s["initial"]["constraints_max"]), elong_um(s["final"]["constraints_max"])
    p0, p1 = s["initial"]["design"]["p"], s["final"]["design"]["p"]
    lines = ["## Table 1 — one elliptical hole (§5.2)", "", header(s), "",
             "| quantity | paper initial | ours initial | difference | paper optimal | ours optimal | difference |",
             "|---|---|---|---|---|---|---|",
             f"| Mass, g | {PAPER_T1['mass'][0]:.3f} | {m0:.3f} | {pct(m0, PAPER_T1['mass'][0])} | "
             f"{PAPER_T1['mass'][1]:.3f} | {m1:.3f} | {pct(m1, PAPER_T1['mass'][1])} |",
             f"| Elongation, µm | {PAPER_T1['elong'][0]:.3f} | {e0:.3f} | {pct(e0, PAPER_T1['elong'][0])} | "
             f"{PAPER_T1['elong'][1]:.3f} | {e1:.3f} | {pct(e1, PAPER_T1['elong'][1])} |",
             f"| Design variable p (0.001 – 0.15) | {PAPER_T1['p'][0]} | {p0:.4g} | | {PAPER_T1['p'][1]} | {p1:.4f} | "
             f"{pct(p1, PAPER_T1['p'][1])} |",
             f"| Mass reduction | | | | {100 * (1 - PAPER_T1['mass'][1] / PAPER_T1['mass'][0]):.1f} % | "
             f"{100 * (1 - m1 / m0):.1f} % | |",
             f"| Iterations (simulations) | | | | {PAPER_T1['iterations']} | {len(h)} | |", ""]
    return lines


def table3(out):
    s, h = load(out)
    m0, m1 = 1e3 * s["initial"]["objective"], 1e3 * s["final"]["objective"]
    e0, e1 = elong_um(s["initial"]["constraints_max"]), elong_um(s["final"]["constraints_max"])
    lines = ["## Table 3 — three elliptical holes (§5.3, Table 2 parameterization)", "", header(s), "",
             "| quantity | paper initial | ours initial | difference | paper optimal | ours optimal | difference |",
             "|---|---|---|---|---|---|---|",
             f"| Mass, g | {PAPER_T3['mass'][0]:.3f} | {m0:.3f} | {pct(m0, PAPER_T3['mass'][0])} | "
             f"{PAPER_T3['mass'][1]:.3f} | {m1:.3f} | {pct(m1, PAPER_T3['mass'][1])} |",
             f"| Elongation, µm | {PAPER_T3['elong'][0]:.3f} | {e0:.3f} | {pct(e0, PAPER_T3['elong'][0])} | "
             f"{PAPER_T3['elong'][1]:.3f} | {e1:.3f} | {pct(e1, PAPER_T3['elong'][1])} |"]
    for name, pi, po, bounds in PAPER_T3["p"]:
        ours0, ours1 = s["initial"]["design"][name], s["final"]["design"][name]
        lines.append(f"| {name} ({bounds}) | {pi} | {ours0:.4g} | | {po} | {ours1:.5f} | |")
    lines += [f"| Mass reduction | | | | {100 * (1 - PAPER_T3['mass'][1] / PAPER_T3['mass'][0]):.1f} % | "
              f"{100 * (1 - m1 / m0):.1f} % | |",
              f"| Iterations (simulations) | | | | {PAPER_T3['iterations']} | {len(h)} | |", ""]
    return lines


def fig8(out, case, lsmbs, link_base):
    """Designs of selected iterations mapped on the mesh (Fig. 8: the holes merge)."""
    _, h = load(out)
    names = ["p1", "p2", "p3", "p4", "p5"]
    n = len(h)
    picks = sorted(set([0, 1, 2, 3, n // 4, n // 2, (3 * n) // 4, n - 1]))
    d = os.path.join(out, "fig8")
    os.makedirs(d, exist_ok=True)
    lines = ["## Fig. 8 — topology evolution (three holes)", "",
             "Designs of selected iterations, mapped with `lsmbs geometry` (black: material).", "",
             "| iteration | mass, g | void area, mm² | picture |", "|---|---|---|---|"]
    for k in picks:
        row = h[k]
        sub = os.path.join(d, f"iter_{k + 1:02d}")
        # --overwrite: the pictures of an earlier run of this script (their summary lists them)
        cmd = [lsmbs, "geometry", case, "-o", sub, "--width", "900", "--overwrite"]
        for nm in names:
            cmd += ["--set", f"{nm}={float(row[nm])!r}"]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        g = json.load(open(os.path.join(sub, "summary.json")))["bodies"][0]
        lines.append(f"| {k + 1} | {1e3 * g['mass']:.3f} | {1e6 * g['void_area']:.1f} | "
                     f"![iteration {k + 1}]({os.path.relpath(os.path.join(sub, 'rod.png'), link_base)}) |")
    return lines + [""]


def main():
    ap = argparse.ArgumentParser(description="Tables 1 and 3, Fig. 8")
    ap.add_argument("one_hole")
    ap.add_argument("three_holes")
    ap.add_argument("target", nargs="?")
    here = os.path.dirname(os.path.abspath(__file__))
    ap.add_argument("--lsmbs", default=os.path.join(here, "..", "build", "src", "lsmbs"))
    ap.add_argument("--case3", default=os.path.join(here, "..", "data", "slider_crank", "slider_crank_3holes.json"))
    a = ap.parse_args()
    lines = ["# Slider-crank connecting rod (§5): Tables 1 and 3", "",
             "The rod, the pressure curve and the crank radius are reconstructed (data/slider_crank/README.md); "
             "the initial one-hole design is calibrated to the paper's mass and elongation. Elongations are the "
             "maximum over the 171 steps.", ""]
    lines += table1(a.one_hole) + table3(a.three_holes) + fig8(a.three_holes, a.case3, a.lsmbs,
                                                              os.path.dirname(os.path.abspath(a.target)) if a.target else ".")
    text = "\n".join(lines)
    if a.target:
        open(a.target, "w").write(text)
    print(text)


if __name__ == "__main__":
    main()
