#!/usr/bin/env python3
"""Tables 4 and 5 of Tromme et al. (robot arm, §6) side by side with an `lsmbs optimize` run.

usage: robot_arm_tables.py OPTIMIZE_OUTPUT_DIR [TABLES.md]

Reads OUT/summary.json and OUT/history.csv of
    lsmbs optimize data/robot_arm/robot_arm_holes.json -o OUT
and writes a Markdown table (paper value, ours, difference) for Table 4 (mass, average tip
deviation, initial and optimal) and Table 5 (feature parameters). The average deviation is the
constraint response (eq. 45) of the initial and final designs in summary.json.
"""
import json
import sys

PAPER_T4 = {"mass_g": (186.498, 130.778), "deviation_mm": (0.6037, 0.9983)}
# Table 5, optimal values: a, b [m] and c_x [mm]
PAPER_T5 = [(39.99e-3, 14.47e-3, 665.03), (38.04e-3, 14.46e-3, 480.18), (38.85e-3, 13.99e-3, 530.56),
            (38.89e-3, 14.49e-3, 614.54), (39.99e-3, 14.94e-3, 749.99)]
BOUND = 0.001  # m, constraint (45)


def main():
    out = sys.argv[1]
    target = sys.argv[2] if len(sys.argv) > 2 else None
    s = json.load(open(f"{out}/summary.json"))
    dev0, dev1 = s["initial"]["constraints_max"], s["final"]["constraints_max"]
    m0, m1 = 1e3 * s["initial"]["objective"], 1e3 * s["final"]["objective"]
    rows = [("Mass (flexible arm), g, initial", PAPER_T4["mass_g"][0], m0),
            ("Mass (flexible arm), g, optimal", PAPER_T4["mass_g"][1], m1),
            ("Average deviation, mm, initial", PAPER_T4["deviation_mm"][0], 1e3 * dev0),
            ("Average deviation, mm, optimal", PAPER_T4["deviation_mm"][1], 1e3 * dev1),
            ("Mass reduction, %", 100 * (1 - 130.778 / 186.498), 100 * (1 - m1 / m0))]
    lines = ["# Robot arm (§6): Tables 4 and 5", "",
             f"Run: `{s['command']}` (commit {s['git_commit']}, case SHA-256 {s['case_sha256'][:12]}…), "
             f"{s['counts']['evaluations']} evaluations, NLopt status: {s['nlopt']['status']}.", "",
             "## Table 4", "", "| quantity | paper | lsmbs | difference |", "|---|---|---|---|"]
    for name, p, o in rows:
        lines.append(f"| {name} | {p:.4f} | {o:.4f} | {100 * (o / p - 1):+.1f} % |")
    lines += ["", "## Table 5 (optimal values; a, b in mm, c_x in mm from the elbow joint)", "",
              "| feature | a paper | a ours | b paper | b ours | c_x paper | c_x ours |", "|---|---|---|---|---|---|---|"]
    d = s["final"]["design"]
    for i, (a, b, cx) in enumerate(PAPER_T5, start=1):
        lines.append(f"| LS {i} | {1e3 * a:.2f} | {1e3 * d[f'a{i}']:.2f} | {1e3 * b:.2f} | {1e3 * d[f'b{i}']:.2f} | "
                     f"{cx:.2f} | {1e3 * d[f'cx{i}']:.2f} |")
    lines += ["", f"KKT at the final design: {json.dumps(s.get('kkt', {}))}", ""]
    text = "\n".join(lines)
    if target:
        open(target, "w").write(text)
    print(text)


if __name__ == "__main__":
    main()
