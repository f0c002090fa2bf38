#!/usr/bin/env bash
# Issue 19, messages that pointed at the wrong cause, and the classes behind them: each input must
# end with the stated exit code and a message naming the JSON path (or option) and the real cause.
#   messages_test.sh LSMBS SOURCE_DIR
set -u
exe="$1"; src="$2"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
rigid="$src/data/slider_crank_rigid/slider_crank_rigid.json"
rod="$src/data/slider_crank/slider_crank_1hole_coarse.json"
# case NAME FROM 'PYTHON' — FROM's JSON as c, modified by PYTHON, written to $tmp/NAME.json (file
# references made absolute, so the case can live in $tmp)
case_() {
  python3 - "$2" "$tmp/$1.json" "$3" <<'PY'
import json, os, sys
src, dst, code = sys.argv[1:4]
c = json.load(open(src))
d = os.path.dirname(os.path.abspath(src))
for b in c.get("bodies", []):
    if "mesh" in b and "file" in b["mesh"]:
        b["mesh"]["file"] = os.path.join(d, b["mesh"]["file"])
for f in c.get("forces", []):
    if "table" in f and "file" in f["table"]:
        f["table"]["file"] = os.path.join(d, f["table"]["file"])
exec(code)
json.dump(c, open(dst, "w"), indent=1)
PY
}
# expect RC NAME 'REGEX' [command...] — runs the command (default: simulate NAME), checks the exit
# code and that stderr matches REGEX (grep -E); exit 2 must write nothing
expect() {
  local rc_want="$1" name="$2" re="$3"; shift 3
  local cmd=("$@")
  [ ${#cmd[@]} -eq 0 ] && cmd=(simulate "$tmp/$name.json")
  [ "${cmd[0]}" != verify ] && cmd+=(-q)
  "$exe" "${cmd[@]}" -o "$tmp/out_$name" 2> "$tmp/err_$name.txt"; local rc=$?
  [ $rc -eq "$rc_want" ] || fail "$name: exit $rc, expected $rc_want: $(cat "$tmp/err_$name.txt")"
  grep -qE "$re" "$tmp/err_$name.txt" || fail "$name: message does not match '$re': $(cat "$tmp/err_$name.txt")"
  if [ "$rc_want" -eq 2 ] && [ -e "$tmp/out_$name" ]; then fail "$name: output written for invalid input"; fi
  return 0
}

# A crank of 1e308 kg overflows in β′M (the run blamed the joint 'cylinder': "has no mass"): refused
# at load, naming the body's JSON entry and its parameters; same for an inertia and another body.
case_ heavy_crank "$rigid" 'c["bodies"][0]["mass"] = 1e308'
expect 2 heavy_crank "heavy_crank.json: /bodies/0: rigid body 'crank': .*not finite.*mass = 1e\+308"
! grep -q cylinder "$tmp/err_heavy_crank.txt" || fail "heavy crank: still blames the cylinder"
case_ heavy_rod_inertia "$rigid" 'c["bodies"][1]["inertia"] = 1.5e308'
expect 2 heavy_rod_inertia "/bodies/1: rigid body 'rod'.*inertia = 1.5e\+308"
case_ heavy_point_mass "$rigid" 'c["forces"] = [{"name": "lump", "type": "point_mass", "point": {"body": "rod", "at": [0.1, 0]}, "mass": 1e308}]'
expect 2 heavy_point_mass "/forces/0: point mass 'lump'.*mass = 1e\+308"
# A spring of 1e308 N/m: every entry is finite, but the factorization multiplies them ("consistent
# initial accelerations are not finite" before): entries beyond 1e100 are refused, naming the spring
case_ stiff_spring "$src/data/slider_crank_rigid/slider_crank_spring.json" 'c["design"]["variables"][0].update(initial=1e308, upper=1e308)'
expect 2 stiff_spring "/forces/0: spring 'spring': its iteration-matrix entries reach 1e\+308 .*stiffness = 1e\+308"
# A penalty 1e300 (exit 0 with a side force of 1e277 N before): far from the automatic scaling
case_ zeta "$src/data/slider_crank_rigid/slider_crank_spring.json" 'c["simulation"]["zeta"] = 1e300'
expect 2 zeta "/simulation/zeta: 1e\+300 is more than 1e8 times away from the automatic scaling"
# ... while a heavy crank within the range (1e60 kg, fully driven: β′M = 6e67) runs, and the
# piston keeps its closed-form stroke (a driven crank's mass does not enter the motion): top dead
# centre x = r + l = 0.1806 m at t = 0; bottom dead centre l − r = 0.0906 m, reached between grid
# steps (ω h = 0.105 rad: the grid minimum lies within (r/2)(1 + r/l)(ω h / 2)² = 8e-5 m above it)
case_ heavy_ok "$rigid" 'c["bodies"][0]["mass"] = 1e60'
"$exe" simulate "$tmp/heavy_ok.json" -o "$tmp/out_heavy_ok" -q || fail "a 1e60 kg driven crank no longer runs"
python3 - "$tmp/out_heavy_ok/summary.json" <<'PY' || fail "heavy crank: piston stroke"
import json, sys
r = json.load(open(sys.argv[1]))["responses"]
assert abs(r["max_piston_x"] - 0.1806) < 1e-9, r  # 1e-9 m: the constraint tolerance (1e-12 x length scale) with margin
assert 0.0906 <= r["min_piston_x"] + 1e-12 and r["min_piston_x"] < 0.0906 + 8e-5, r
PY
# A measure that is not finite at t = 0 (a point 1e300 m away: every response of it was NaN in a
# run reported complete)
case_ far_point "$rigid" 'c["output"]["measures"][2]["b"]["at"] = [0, 1e300]'
expect 2 far_point "/output/measures/2: measure 'rod_length_change' is not finite at t = 0"
# Overflowing geometry: a mesh scale or an origin beyond double precision, named with its path
case_ huge_scale "$rod" 'c["bodies"][2]["mesh"]["scale"] = 1e306'
expect 2 huge_scale "/bodies/2/mesh/scale: the scaled mesh coordinates are out of range"
case_ far_plate "$src/data/robot_arm/robot_arm.json" 'c["bodies"][2]["mesh"]["origin"] = [0, -1.5e298]'
expect 2 far_plate "robot_arm|far_plate.json: /bodies/2/mesh"

# Files named in a case: a folder, a device, a missing file say so, with the case's JSON path
# (a mesh folder gave "not a Gmsh file", a table folder "expected at least two points").
case_ mesh_folder "$rod" 'c["bodies"][2]["mesh"]["file"] = d'
expect 2 mesh_folder "mesh file: is a folder, not a file .*mesh_folder.json: /bodies/2/mesh/file"
case_ mesh_device "$rod" 'c["bodies"][2]["mesh"]["file"] = "/dev/zero"'
expect 2 mesh_device "/dev/zero: mesh file: is not a regular file .*/bodies/2/mesh/file"
case_ table_folder "$rod" 'c["forces"][0]["table"]["file"] = d'
expect 2 table_folder "/forces/0/table/file: .*table file: is a folder, not a file"
case_ table_missing "$rod" 'c["forces"][0]["table"]["file"] = d + "/missing.csv"'
expect 2 table_missing "/forces/0/table/file: .*missing.csv: table file: no such file"
expect 2 case_folder "case file: is a folder|File is actually a directory|directory" simulate "$src/data"
# Table options are checked with their JSON path (x_scale 0 blamed the CSV's x values)
case_ x_scale0 "$rod" 'c["forces"][0]["table"]["x_scale"] = 0'
expect 2 x_scale0 "x_scale0.json: /forces/0/table/x_scale: expected a positive number, got 0"
case_ x_scal "$rod" 'c["forces"][0]["table"]["x_scal"] = 2'
expect 2 x_scal "/forces/0/table/x_scal: unknown key"
case_ file_and_points "$rod" 'c["forces"][0]["table"]["points"] = [[0, 1], [1, 2]]'
expect 2 file_and_points "/forces/0/table: expected either \"file\" or \"points\", not both"
case_ law_xs "$rigid" 'c["joints"][4]["law"] = {"type": "table", "points": [[0, 0], [1, 1]], "x_scale": -1}'
expect 2 law_xs "/joints/4/law/x_scale: expected a positive number, got -1"
# h longer than t_end: a run without a step was reported complete
case_ long_h "$rigid" 'c["simulation"]["h"] = 1.0'
expect 2 long_h "/simulation/h: h = 1 is longer than t_end = 0.0425"

# An initial design that cannot be simulated: the optimization says when, why and for which design
# (it said "a per-step constraint produced 44 values instead of 171"), exit 1, summary partial.
case_ opt_fail "$rod" 'c["simulation"].update(max_iter=1, max_halvings=0)'
expect 1 opt_fail "the initial design could not be simulated: evaluation 1 at p = \[0.001\] failed: t = 0.00025 \(step 1, h = 0.00025\): Newton did not converge" optimize "$tmp/opt_fail.json" --no-check
! grep -q "values instead of" "$tmp/err_opt_fail.txt" || fail "opt_fail: the old message"
python3 - "$tmp/out_opt_fail" <<'PY' || fail "opt_fail: summary or history"
import json, math, sys
out = sys.argv[1]
s = json.load(open(out + "/summary.json"))
assert s["status"] == "partial" and "Newton did not converge" in s["failure"] and "p = [0.001]" in s["failure"], s
rows = open(out + "/history.csv").read().splitlines()
assert len(rows) == 2, rows
obj, viol, feasible = rows[1].split(",")[1:4]
assert math.isnan(float(obj)) and feasible == "0", rows  # a failed run's aggregates are not responses
PY

# optimize's gradient check compares the responses it uses (objective, constraints) with the
# perturbed runs' responses of the same name (it took the response at the same position: an
# objective that was not the first response was compared with another response).
cat > "$tmp/pend.json" <<'JSON'
{"name": "pend", "gravity": [0, -9.81],
 "bodies": [{"name": "bob", "type": "rigid", "position": [1, 0], "mass": 1, "inertia": 0.1}],
 "joints": [{"name": "pin", "type": "revolute", "a": {"body": "bob", "at": [-1, 0]}, "b": "ground"}],
 "forces": [{"name": "push", "type": "point_force", "point": {"body": "bob"}, "force": [0, -1]}],
 "simulation": {"t_end": 0.2, "h": 0.01},
 "design": {"variables": [{"name": "s", "initial": 1, "lower": 0, "upper": 5}],
            "parameters": [{"parameter": "push.scale", "variable": "s"}]},
 "output": {"measures": [{"name": "bob", "type": "position", "point": {"body": "bob"}}],
  "responses": [{"name": "trace", "measure": "bob.x", "aggregate": "per_step"},
                {"name": "max_x", "measure": "bob.x", "aggregate": "max"},
                {"name": "final_y", "measure": "bob.y", "aggregate": "final"}]},
 "optimization": {"objective": "final_y", "constraints": [], "optimizer": "mma", "stop": {"max_evaluations": 2}}}
JSON
"$exe" optimize "$tmp/pend.json" -o "$tmp/out_pend" -q 2> "$tmp/err_pend.txt" || fail "gradient check of a later response: $(cat "$tmp/err_pend.txt")"
python3 -c "
import json; g = json.load(open('$tmp/out_pend/summary.json'))['gradient_check']
assert g['verdict'] == 'pass' and list(g['responses']) == ['final_y'], g" || fail "gradient check entries"

# verify reads the case through the loader's depth bound (it parsed it first without one: a crash)
python3 -c "print('[' * 200000 + ']' * 200000)" > "$tmp/deep.json"
expect 2 deep "byte 256: invalid JSON: nested deeper than 256 levels" verify "$tmp/deep.json"
[ -n "${SHOW:-}" ] && head -v -n 3 "$tmp"/err_*.txt
echo "robustness messages: all checks passed"
