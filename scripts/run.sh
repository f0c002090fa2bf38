#!/usr/bin/env bash
# The main job: installs missing packages, builds Release, and simulates the robot arm of §6
# (solid plate, initial design) with the shipped case. Results go to out/robot_arm/.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/setup-deps.sh"
bash "$root/scripts/build.sh"
out="${1:-$root/out/robot_arm}"
"$root/build/src/lsmbs" simulate "$root/data/robot_arm/robot_arm.json" -o "$out"
echo "results: $out/summary.json, $out/history.csv, $out/plate.pvd (ParaView)"
