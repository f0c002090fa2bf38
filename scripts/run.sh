#!/usr/bin/env bash
# The main job: installs missing packages, builds Release, and runs the fully coupled
# optimization of the §6 robot arm (five super-ellipse holes, 15 design variables, NLopt MMA,
# direct-analytic sensitivities) with the shipped case. Results go to out/robot_arm/ (a few
# minutes on 2 cores); the tables comparing with the paper are written by
# paper_results/robot_arm_tables.py.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/setup-deps.sh"
bash "$root/scripts/build.sh"
out="${1:-$root/out/robot_arm}"
"$root/build/src/lsmbs" optimize "$root/data/robot_arm/robot_arm_holes.json" -o "$out" --overwrite
python3 "$root/paper_results/robot_arm_tables.py" "$out" "$out/tables.md"
echo "results: $out/summary.json, $out/history.csv, $out/convergence.png, $out/final_design/plate.png, $out/tables.md"
