#!/usr/bin/env bash
# lsmbs simulate end to end: provenance in summary.json, exit codes 0 / 1 / 2, and nothing
# written when the input is invalid.
set -u
exe="$1"; src="$2"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

case_file="$src/data/slider_crank_rigid/slider_crank_rigid.json"
"$exe" simulate "$case_file" -o "$tmp/ok" -q || fail "simulate returned $?"
python3 - "$tmp/ok/summary.json" "$case_file" <<'PY' || fail "summary.json content"
import hashlib, json, sys
s = json.load(open(sys.argv[1]))
sha = hashlib.sha256(open(sys.argv[2], 'rb').read()).hexdigest()
assert s["case_sha256"] == sha, (s["case_sha256"], sha)
assert s["status"] == "complete"
assert s["git_commit"] and s["version"]
assert s["options"]["generalized_alpha"]["h"] == 2.5e-4
assert "max_piston_x" in s["responses"]
print("summary.json ok")
PY
head -1 "$tmp/ok/history.csv" | grep -q "^t,piston.x,piston.y" || fail "history.csv header"
# The recorded commit is the one the binary was built from (refreshed at build time, not at
# configure time): compare with git itself.
if head=$(git -C "$src" rev-parse HEAD 2>/dev/null); then
  rec=$(python3 -c "import json; print(json.load(open('$tmp/ok/summary.json'))['git_commit'])")
  [ "${rec%-dirty}" = "$head" ] || fail "summary.json git_commit $rec, source tree at $head (stale build?)"
fi

# Same input, same numbers.
"$exe" simulate "$case_file" -o "$tmp/again" -q || fail "second run"
cmp -s "$tmp/ok/history.csv" "$tmp/again/history.csv" || fail "history.csv differs between identical runs"

# Invalid input: exit 2, message with the JSON path, nothing written.
python3 -c "
import json,sys
c=json.load(open('$case_file')); c['bodies'][0]['mass']=-1; json.dump(c,open('$tmp/bad.json','w'))"
"$exe" simulate "$tmp/bad.json" -o "$tmp/bad_out" 2> "$tmp/err.txt"; rc=$?
[ $rc -eq 2 ] || fail "invalid input returned $rc, expected 2"
grep -q "/bodies/0/mass: expected a non-negative number" "$tmp/err.txt" || fail "message: $(cat "$tmp/err.txt")"
[ ! -e "$tmp/bad_out" ] || fail "output written for invalid input"
# a number out of double range (found by the fuzzer: it used to be an "internal error", exit 1)
printf '{"name": 1e999}' > "$tmp/overflow.json"
"$exe" simulate "$tmp/overflow.json" -o "$tmp/ov_out" 2> "$tmp/err_ov.txt"; rc=$?
[ $rc -eq 2 ] || fail "number overflow returned $rc, expected 2"
grep -q "overflow.json: invalid JSON" "$tmp/err_ov.txt" || fail "message: $(cat "$tmp/err_ov.txt")"
# Readers and values that were misread or replaced without a word: exit 2, the file and line or
# the options named, nothing written. A table field with a unit (read as 1.2 before), a Gmsh
# element line with a node tag too many (the extra tag was ignored), a --set given twice (the last
# won), a --seed of -1 (it wrapped to 18446744073709551615).
python3 - "$tmp" <<'PY' || fail "writing the reader cases"
import json, sys
tmp = sys.argv[1]
pend = {"name": "law", "bodies": [{"name": "bob", "type": "rigid", "position": [1, 0], "mass": 1, "inertia": 0.1}],
        "joints": [{"name": "pin", "type": "revolute", "a": {"body": "bob", "at": [-1, 0]}, "b": "ground"},
                   {"name": "motor", "type": "rotation_driver", "body": "bob", "law": {"type": "table", "file": "law.csv"}}],
        "simulation": {"t_end": 0.02, "h": 0.01},
        "output": {"measures": [{"name": "bob", "type": "position", "point": {"body": "bob"}}]}}
json.dump(pend, open(tmp + "/law.json", "w"))
open(tmp + "/law.csv", "w").write("t,angle\n0,0\n1,1.2x\n")
msh = ("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 6 1 6\n2 1 0 6\n1\n2\n3\n4\n5\n6\n"
       "0 0 0\n1 0 0\n2 0 0\n0 1 0\n1 1 0\n2 1 0\n$EndNodes\n$Elements\n1 2 1 2\n2 1 3 2\n"
       "1 1 2 5 4 6\n2 2 3 6 5\n$EndElements\n")
open(tmp + "/plate.msh", "w").write(msh)
plate = {"name": "plate", "bodies": [{"name": "p", "type": "flexible", "mesh": {"type": "gmsh", "file": "plate.msh"},
         "material": {"E": 1e9, "nu": 0.3, "rho": 1000}, "thickness": 0.01}],
         "simulation": {"t_end": 0.002, "h": 0.001}, "output": {"measures": []}}
json.dump(plate, open(tmp + "/msh.json", "w"))
PY
refused() {  # refused EXPECTED-MESSAGE ARGS...: exit 2, the message, no output folder
  local want="$1"; shift
  rm -rf "$tmp/refused"
  "$exe" "$@" -o "$tmp/refused" 2> "$tmp/err_r.txt"; local rc=$?
  [ $rc -eq 2 ] || fail "$* returned $rc, expected 2: $(cat "$tmp/err_r.txt")"
  grep -qF -- "$want" "$tmp/err_r.txt" || fail "$*: expected '$want' in: $(cat "$tmp/err_r.txt")"
  [ ! -e "$tmp/refused/summary.json" ] || fail "$*: summary.json written on bad input"
}
refused "law.json: /joints/1/law/file: $tmp/law.csv: line 3: y: expected a finite number, got '1.2x'" \
  simulate "$tmp/law.json"
refused "plate.msh: line 23: expected an element: its tag and 4 node tags (5 fields), got 6 fields: '1 1 2 5 4 6'" \
  simulate "$tmp/msh.json"
refused "--set /simulation/h=1e-3 and --set /simulation/h=2e-3 set the same value (/simulation/h)" \
  simulate "$case_file" --set /simulation/h=1e-3 --set /simulation/h=2e-3
refused "--seed: expected a non-negative integer, got '-1'" \
  optimize "$src/data/robot_arm/robot_arm_holes.json" --starts 2 --seed -1
# A level-set hole that starts off its plate (a design variable may move it in): simulate runs and
# warns, in summary.json; a non-design ring off the plate (nothing moves it) is refused.
python3 - "$tmp" <<'PY' || fail "writing the feature cases"
import copy, json, sys
tmp = sys.argv[1]
c = {"name": "plate", "bodies": [{"name": "p", "type": "flexible",
     "mesh": {"type": "rectangle", "origin": [0, 0], "size": [1, 0.2], "elements": [10, 2]},
     "material": {"E": 1e9, "nu": 0.3, "rho": 1000}, "thickness": 0.01}],
     "joints": [{"name": "c", "type": "clamp", "flexible": "p", "node_set": "left"}],
     "simulation": {"t_end": 0.002, "h": 0.001},
     "output": {"measures": [{"name": "m", "type": "mass", "body": "p"}]},
     "design": {"variables": [{"name": "cx", "initial": 2.5, "lower": 0.2, "upper": 3}],
                "geometry": [{"body": "p", "features": [{"name": "hole", "type": "circle", "cx": "cx", "cy": 0.1, "r": 0.05}]}]}}
json.dump(c, open(tmp + "/hole_off.json", "w"))
c["design"]["variables"][0]["initial"] = 0.5
c["design"]["geometry"][0]["features"].append({"name": "ring", "type": "circle", "cx": 5, "cy": 5, "r": 0.1, "non_design": True})
json.dump(c, open(tmp + "/ring_off.json", "w"))
PY
"$exe" simulate "$tmp/hole_off.json" -o "$tmp/hole_off" > "$tmp/hole_off.txt" 2>&1 || fail "simulate with a hole off the plate"
grep -qF "warning: body 'p': level-set feature 'hole' lies wholly outside the body" "$tmp/hole_off.txt" || fail "no warning: $(cat "$tmp/hole_off.txt")"
python3 -c "import json,sys; w=json.load(open(sys.argv[1]))['warnings']; assert any(\"feature 'hole' lies wholly outside\" in x for x in w), w" \
  "$tmp/hole_off/summary.json" || fail "summary.json warnings"
refused "ring_off.json: /design/geometry/0/features/1: non-design feature 'ring' lies wholly outside body 'p'" \
  simulate "$tmp/ring_off.json"

# Numerical failure: exit 1, partial results flagged.
python3 -c "
import json
c=json.load(open('$case_file')); c['simulation'].update(max_iter=1, max_halvings=0); json.dump(c,open('$tmp/fail.json','w'))"
"$exe" simulate "$tmp/fail.json" -o "$tmp/fail_out" -q 2> "$tmp/err2.txt"; rc=$?
[ $rc -eq 1 ] || fail "numerical failure returned $rc, expected 1"
grep -q "Newton did not converge" "$tmp/err2.txt" || fail "failure message: $(cat "$tmp/err2.txt")"
python3 -c "import json; assert json.load(open('$tmp/fail_out/summary.json'))['status']=='partial'" || fail "partial flag"
# Flexible body: VTU files and a PVD series that ParaView can read (well-formed XML).
python3 -c "
import json
c=json.load(open('$src/data/robot_arm/robot_arm.json')); c['simulation']['t_end']=0.05; c['output']['vtu_stride']=5
c['output']['responses']=[r for r in c['output']['responses'] if 'window' not in r]  # windows after 0.05 s are refused
json.dump(c,open('$tmp/arm.json','w'))"
"$exe" simulate "$tmp/arm.json" -o "$tmp/arm" -q || fail "robot arm short run"
python3 - "$tmp/arm" <<'PY' || fail "VTU/PVD"
import sys, os, xml.etree.ElementTree as ET
out = sys.argv[1]
pvd = ET.parse(os.path.join(out, "plate.pvd")).getroot()
files = [d.get("file") for d in pvd.iter("DataSet")]
assert len(files) == 3, files  # steps 0, 5, 10
for f in files:
    piece = ET.parse(os.path.join(out, f)).getroot().find(".//Piece")
    assert piece.get("NumberOfPoints") == "1331" and piece.get("NumberOfCells") == "1200"
print("vtu ok")
PY
# Geometry: μ_e as VTU and PNG, summary with the mass; --set overrides a design variable.
"$exe" geometry "$src/data/robot_arm/robot_arm_holes.json" -o "$tmp/geo" --set a1=0.03 --width 600 -q || fail "geometry"
python3 - "$tmp/geo" <<'PY' || fail "geometry outputs"
import sys, os, json, struct, zlib
out = sys.argv[1]
s = json.load(open(os.path.join(out, "summary.json")))
b = s["bodies"][0]
assert s["design"]["a1"] == 0.03 and 0.18 < b["mass"] < 0.2025, b["mass"]
png = open(os.path.join(out, "plate.png"), "rb").read()
assert png[:8] == b"\x89PNG\r\n\x1a\n"
w, h = struct.unpack(">II", png[16:24])
idat = b"".join(png[i + 8:i + 8 + struct.unpack(">I", png[i:i + 4])[0]] for i in [png.index(b"IDAT") - 4])
raw = zlib.decompress(idat)
assert w == 600 and png[25] == 2 and len(raw) == h * (3 * w + 1), (w, h, len(raw))  # RGB
assert len(png) < len(raw) / 20, (len(png), len(raw))  # deflated by zlib (was stored blocks)
assert s["files"] == ["plate.png", "plate.vtu", "plate_shape.json", "summary.json"], s["files"]
print("geometry ok: PNG", len(png), "bytes for", len(raw), "bytes of scanlines")
PY
"$exe" geometry "$case_file" -o "$tmp/nogeo" 2> "$tmp/err3.txt"; rc=$?
[ $rc -eq 2 ] || fail "geometry without design returned $rc"
grep -q "no design section" "$tmp/err3.txt" || fail "message: $(cat "$tmp/err3.txt")"
# Sensitivity: gradients in summary.json and gradients.csv; an unknown method is a usage error.
spring="$src/data/slider_crank_rigid/slider_crank_spring.json"
"$exe" sensitivity "$spring" --method direct-analytic --matrix refined -o "$tmp/sens" -q || fail "sensitivity"
python3 - "$tmp/sens" <<'PY' || fail "sensitivity outputs"
import sys, os, json, csv
out = sys.argv[1]
s = json.load(open(os.path.join(out, "summary.json")))
g = s["gradients"]["final_crank_angle"]
assert set(g) == {"k", "c"} and all(isinstance(v, float) for v in g.values()), g
assert len(s["gradients"]["piston_x_per_step"]["k"]) == len(s["responses"]["piston_x_per_step"]) == 51
assert s["options"]["sensitivity"]["method"] == "direct-analytic" and s["counts"]["back_solves"] > 0
rows = list(csv.DictReader(open(os.path.join(out, "gradients.csv"))))  # long form, plain header
assert list(rows[0]) == ["response", "variable", "step", "t", "value", "derivative"], list(rows[0])
fc = {r["variable"]: float(r["derivative"]) for r in rows if r["response"] == "final_crank_angle"}
assert fc == g, (fc, g)  # the same doubles as summary.json
assert len([r for r in rows if r["response"] == "piston_x_per_step"]) == 2 * 51
print("sensitivity ok")
PY
# The default matrix is the exact one; --check adds a directional central difference (2 runs).
"$exe" sensitivity "$spring" --check -o "$tmp/sens_check" -q || fail "sensitivity --check"
python3 - "$tmp/sens_check/summary.json" "$tmp/sens/summary.json" <<'PY' || fail "gradient check in summary.json"
import json, sys
s, r = (json.load(open(f)) for f in sys.argv[1:3])
assert s["options"]["sensitivity"]["matrix"] == "converged", s["options"]["sensitivity"]
for resp, g in r["gradients"].items():  # --matrix refined (the run above) and the default agree
    for v, x in g.items():
        y = s["gradients"][resp][v]
        xs, ys = (x, y) if isinstance(x, list) else ([x], [y])
        n = max(abs(a) for a in xs) or 1
        assert max(abs(a - b) for a, b in zip(xs, ys)) <= 1e-9 * n, (resp, v)
c = s["gradient_check"]
assert c["verdict"] == "pass" and c["completed"] and c["simulations"] == 2 and c["worst"] < 1e-5, c
assert set(c["responses"]) == set(s["responses"]), c["responses"]
assert abs(sum(x * x for x in c["direction"]) - 1) < 1e-12
print("gradient check ok: worst", c["worst"], c["worst_response"])
PY
# --matrix last (the paper's Algorithm 2 literally) warns where steps took one Newton iteration.
python3 -c "
import json
c=json.load(open('$spring')); c['simulation'].pop('tol_r'); c['simulation']['h']=6.25e-5
json.dump(c,open('$tmp/spring_fine.json','w'))"
"$exe" sensitivity "$tmp/spring_fine.json" --matrix last -o "$tmp/sens_last" -q 2> "$tmp/err_last.txt" || fail "--matrix last"
grep -q "warning: --matrix last:" "$tmp/err_last.txt" || fail "no warning for --matrix last: $(cat "$tmp/err_last.txt")"
python3 -c "
import json; s=json.load(open('$tmp/sens_last/summary.json'))
assert s['counts']['predictor_matrix_steps'] > 0 and len(s['warnings']) == 1, s['counts']" || fail "last: counts"
# A failed run reports no responses (null) and writes no gradients.csv; what it aggregated before
# the failure is kept apart.
cat > "$tmp/fails.json" <<'JSON'
{"bodies":[{"name":"bob","type":"rigid","position":[1,0],"mass":1,"inertia":0.1}],
 "joints":[{"name":"pin","type":"revolute","a":{"body":"bob","at":[-1,0]},"b":"ground"}],
 "forces":[{"name":"f","type":"point_force","point":{"body":"bob"},"force":[0,1e30]}],
 "simulation":{"t_end":0.5,"h":0.01,"max_halvings":1},
 "design":{"variables":[{"name":"m","initial":1,"lower":0.5,"upper":2}],"parameters":[{"parameter":"bob.mass","variable":"m"}]},
 "output":{"measures":[{"name":"a","type":"angle","body":"bob"}],"responses":[{"name":"fa","measure":"a","aggregate":"final"}]}}
JSON
"$exe" sensitivity "$tmp/fails.json" -o "$tmp/sens_fail" -q 2> /dev/null; rc=$?
[ $rc -eq 1 ] || fail "failing sensitivity returned $rc"
[ ! -e "$tmp/sens_fail/gradients.csv" ] || fail "a failed run wrote gradients.csv"
python3 -c "
import json; s=json.load(open('$tmp/sens_fail/summary.json'))
assert s['status'] == 'partial' and s['responses'] == {'fa': None} and 'partial_responses_until_failure' in s, s" || fail "failed run summary"
# Bad command-line values and pathological files: exit 2, a message naming the option or file.
"$exe" sensitivity "$spring" --method idas --rtol nan -o "$tmp/bad1" 2> "$tmp/e1.txt"; rc=$?
[ $rc -eq 2 ] && grep -q "^lsmbs: error: --rtol nan" "$tmp/e1.txt" && [ ! -e "$tmp/bad1" ] || fail "--rtol nan: rc $rc $(cat "$tmp/e1.txt")"
"$exe" simulate "$spring" --rtol -1 --integrator idas -o "$tmp/bad2" 2> "$tmp/e2.txt"; rc=$?
[ $rc -eq 2 ] && grep -q -- "--rtol" "$tmp/e2.txt" || fail "--rtol -1: rc $rc $(cat "$tmp/e2.txt")"
"$exe" simulate "$spring" --set k=-3 -o "$tmp/bad3" 2> "$tmp/e3.txt"; rc=$?
[ $rc -eq 2 ] && grep -q "outside the bounds" "$tmp/e3.txt" && [ ! -e "$tmp/bad3" ] || fail "--set outside bounds: rc $rc"
touch "$tmp/a_file"
for o in "$tmp/a_file" /proc/x ""; do  # unusable output folders: exit 2 with a plain message
  "$exe" simulate "$spring" -o "$o" 2> "$tmp/eo.txt"; rc=$?
  [ $rc -eq 2 ] && grep -q "^lsmbs: error: -o" "$tmp/eo.txt" || fail "-o '$o': rc $rc $(cat "$tmp/eo.txt")"
done
# Pictures are drawn in memory (cairo), without a shell or an interpreter: a quote in the output
# path is harmless (tests/robustness/hostile_strings_test.py tries the other classes)
"$exe" verify "$spring" --no-idas -o "$tmp/it's \"quoted\"" > "$tmp/vq.txt" 2>&1 || fail "verify into a quoted path"
[ -s "$tmp/it's \"quoted\"/dp_study.png" ] || fail "no picture in a quoted path: $(ls "$tmp/it's \"quoted\"")"
python3 -c "print('[' * 200000 + ']' * 200000)" > "$tmp/deep.json"
"$exe" simulate "$tmp/deep.json" -o "$tmp/bad4" 2> "$tmp/e4.txt"; rc=$?
[ $rc -eq 2 ] && grep -q "nested deeper than" "$tmp/e4.txt" || fail "deeply nested JSON: rc $rc $(cat "$tmp/e4.txt")"
"$exe" sensitivity "$spring" --method adjoint-continuous -o "$tmp/sens2" 2> "$tmp/err4.txt"; rc=$?
[ $rc -eq 2 ] || fail "unknown method returned $rc"
grep -q "expected one of semi-analytical" "$tmp/err4.txt" || fail "message: $(cat "$tmp/err4.txt")"
# The discrete adjoint refuses the spring case's per-step response, naming the direct method
"$exe" sensitivity "$spring" --method adjoint -o "$tmp/sens3" 2> "$tmp/err5.txt"; rc=$?
[ $rc -eq 2 ] && grep -q "piston_x_per_step.*use --method direct-analytic" "$tmp/err5.txt" \
  || fail "adjoint with a per-step response: rc $rc $(cat "$tmp/err5.txt")"
[ ! -e "$tmp/sens3/summary.json" ] || fail "a refused adjoint run left a summary.json"
grep -q "/output/responses/[0-9]" "$tmp/err5.txt" || fail "the refusal names no response entry: $(cat "$tmp/err5.txt")"
# A memory bound the checkpoints cannot meet names the command's option (not a case path) and the
# least memory that works
python3 -c "
import json
c=json.load(open('$spring')); c['output']['responses']=[r for r in c['output']['responses'] if r['aggregate']!='per_step']
json.dump(c, open('$tmp/noper.json','w'))"
"$exe" sensitivity "$tmp/noper.json" --method adjoint --adjoint-memory 0.0001 -o "$tmp/sens_mem" 2> "$tmp/err_mem.txt"; rc=$?
[ $rc -eq 2 ] && grep -q -- "--adjoint-memory 0.0001: the adjoint of .* needs at least [0-9.e-]* MB" "$tmp/err_mem.txt" \
  || fail "adjoint memory bound: rc $rc $(cat "$tmp/err_mem.txt")"
need=$(sed -n 's/.*needs at least \([0-9.e-]*\) MB.*/\1/p' "$tmp/err_mem.txt")
"$exe" sensitivity "$tmp/noper.json" --method adjoint --adjoint-memory "$need" -o "$tmp/sens_mem2" -q \
  || fail "the stated least memory $need MB is refused"
# Optimization stopped after 4 evaluations by the testing hook (as an interruption would stop it),
# then resumed: it ends at the same design as an uninterrupted run, simulating only the rest.
python3 -c "
import json
c=json.load(open('$src/data/robot_arm/robot_arm_holes.json')); c['bodies'][2]['mesh']['elements']=[30,3]
c['simulation']['h']=0.01; c['output']['vtu_stride']=0; c['optimization']['stop']['max_evaluations']=12
json.dump(c,open('$tmp/opt.json','w'))"
"$exe" optimize "$tmp/opt.json" -o "$tmp/opt_full" -q || fail "optimize"
# a design whose two holes coincide (a second circle on the first, the skeptical user's case):
# its gradients are one-sided, and optimize says so for the initial and the final design
python3 -c "
import json
c=json.load(open('$src/tests/integration/data/cantilever_ramp.json'))
c['design']['geometry'][0]['features'].append({'name': 'h2', 'type': 'circle', 'cx': 0.06, 'cy': 0.025, 'r': 0.01})
c['optimization']['stop']['max_evaluations']=1
json.dump(c,open('$tmp/opt_twin.json','w'))"
"$exe" optimize "$tmp/opt_twin.json" -o "$tmp/opt_twin" -q --no-check 2> "$tmp/twin.txt" || fail "optimize with coincident holes: exit $?"
grep -q "warning: initial design: body 'pl': two level-set features coincide" "$tmp/twin.txt" \
  && python3 -c "
import json
S = json.load(open('$tmp/opt_twin/summary.json'))
assert any(w.startswith('initial design: ') for w in S['warnings']), S['warnings']" || fail "coincident holes in optimize: $(cat "$tmp/twin.txt")"
# a run that ends outside its constraints says so (it exited 0 with the usual lines only): a
# deviation bound 50x below the initial design's, two evaluations
python3 -c "
import json
c=json.load(open('$tmp/opt.json')); c['optimization']['constraints'][0]['upper']=1e-5
c['optimization']['stop']['max_evaluations']=2
json.dump(c,open('$tmp/opt_infeasible.json','w'))"
"$exe" optimize "$tmp/opt_infeasible.json" -o "$tmp/opt_infeasible" -q --no-check 2> "$tmp/inf.txt" || fail "optimize ending infeasible: exit $?"
python3 -c "
import json
S = json.load(open('$tmp/opt_infeasible/summary.json'))
tol = S['options']['optimization']['tol_constraint']
assert S['final']['max_violation'] > tol and any('final design is infeasible' in w for w in S['warnings']), S['warnings']
S2 = json.load(open('$tmp/opt_full/summary.json'))
assert S2['final']['max_violation'] > tol or not any('infeasible' in w for w in S2['warnings']), S2['warnings']
# why it stopped, apart from whether the design is optimal: cut off, hence not converged
assert S['stop_reason'] == 'max_evaluations' and S['converged'] is False, (S['stop_reason'], S['converged'])
assert S2['converged'] == (S2['stop_reason'] in ('ftol', 'xtol') and S2['kkt']['verdict'] == 'satisfied'
                           and S2['final']['max_violation'] <= tol), S2" \
  && grep -q "warning: the final design is infeasible" "$tmp/inf.txt" || fail "infeasible final design: $(cat "$tmp/inf.txt")"
LSMBS_STOP_AFTER_EVALUATIONS=4 "$exe" optimize "$tmp/opt.json" -o "$tmp/opt_killed" -q 2> "$tmp/stop.txt"; rc=$?
[ $rc -eq 130 ] && grep -q "interrupted after 4 evaluations" "$tmp/stop.txt" || fail "stop hook: rc $rc $(cat "$tmp/stop.txt")"
[ -f "$tmp/opt_killed/checkpoint.json" ] || fail "no checkpoint after the stop"
python3 -c "
import json; s=json.load(open('$tmp/opt_killed/summary.json'))
assert s['status'] == 'interrupted' and s['counts']['simulations_this_run'] == 4, (s['status'], s['counts'])" || fail "stopped run's summary"
LSMBS_STOP_AFTER_EVALUATIONS=0 "$exe" optimize "$tmp/opt.json" -o "$tmp/opt_bad_hook" -q 2> "$tmp/stop_bad.txt"; rc=$?
[ $rc -eq 2 ] && grep -q "LSMBS_STOP_AFTER_EVALUATIONS=0: expected a positive integer" "$tmp/stop_bad.txt" || fail "bad hook value: rc $rc"
"$exe" optimize "$tmp/opt.json" -o "$tmp/opt_killed" --resume -q || fail "resume"
python3 - "$tmp/opt_full/summary.json" "$tmp/opt_killed/summary.json" <<'PY' || fail "resumed design differs"
import json, sys
a, b = (json.load(open(f)) for f in sys.argv[1:3])
assert a["final"]["design"] == b["final"]["design"], (a["final"]["design"], b["final"]["design"])
assert a["final"]["objective"] == b["final"]["objective"]
full, done = a["counts"]["simulations_this_run"], 4
assert a["counts"]["evaluations"] == full and full > done, a["counts"]
assert b["counts"]["simulations_this_run"] == full - done, (b["counts"], full)
assert b["counts"]["evaluations"] == full, b["counts"]
assert a["initial"] == b["initial"], (a["initial"], b["initial"])
def rows(f):  # history.csv without the wall_seconds column (timing differs between runs)
    lines = [l.split(",") for l in open(f.replace("summary.json", "history.csv")).read().splitlines()]
    i = lines[0].index("wall_seconds")
    return [l[:i] + l[i + 1:] for l in lines]
assert rows(sys.argv[1]) == rows(sys.argv[2]), "the resumed run's history.csv differs from the uninterrupted run's"
gc = a["gradient_check"]  # optimize checks the gradient at the initial design by default
assert gc["verdict"] == "pass" and set(gc["responses"]) == {"plate_mass", "average_tip_deviation"}, gc
print("stop/resume ok:", b["counts"], "gradient check", gc["worst"], gc["worst_response"])
PY
# Resuming a finished run replays it (no simulation) and leaves the same complete results.
"$exe" optimize "$tmp/opt.json" -o "$tmp/opt_killed" --resume -q || fail "resume of a finished run"
python3 - "$tmp/opt_full/summary.json" "$tmp/opt_killed/summary.json" <<'PY' || fail "resume of a finished run"
import json, sys
a, b = (json.load(open(f)) for f in sys.argv[1:3])
assert b["status"] == "complete" and b["final"] == a["final"] and b["counts"]["simulations_this_run"] == 0, b["counts"]
ra, rb = (open(f.replace("summary.json", "history.csv")).read().splitlines() for f in sys.argv[1:3])
assert len(ra) == len(rb) and [l.split(",")[:4] for l in ra] == [l.split(",")[:4] for l in rb]
PY
# A simulation that fails inside optimize (the initial design runs, a later one does not): exit 1,
# status partial, and the failure says which evaluation, where and why.
cat > "$tmp/optfail.json" <<'JSON'
{"name":"pend_fail","gravity":[0,-9.81],
 "bodies":[{"name":"bob","type":"rigid","position":[1,0],"mass":1,"inertia":0.1}],
 "joints":[{"name":"pin","type":"revolute","a":{"body":"bob","at":[-1,0]},"b":"ground"}],
 "forces":[{"name":"push","type":"point_force","point":{"body":"bob"},"force":[0,-1]}],
 "simulation":{"t_end":0.2,"h":0.02,"max_iter":4,"max_halvings":0},
 "design":{"variables":[{"name":"s","initial":1,"lower":0,"upper":1e7}],"parameters":[{"parameter":"push.scale","variable":"s"}]},
 "output":{"measures":[{"name":"bob","type":"position","point":{"body":"bob"}}],
  "responses":[{"name":"final_y","measure":"bob.y","aggregate":"final"}]},
 "optimization":{"objective":"final_y","constraints":[],"optimizer":"mma"}}
JSON
"$exe" optimize "$tmp/optfail.json" -o "$tmp/optfail" -q 2> "$tmp/eof.txt"; rc=$?
[ $rc -eq 1 ] && grep -q "numerical failure: evaluation 2 at p = " "$tmp/eof.txt" || fail "failed evaluation in optimize: rc $rc $(cat "$tmp/eof.txt")"
python3 -c "
import json; s=json.load(open('$tmp/optfail/summary.json'))
assert s['status'] == 'partial' and 'Newton did not converge' in s['failure'], s.get('failure')" || fail "optimize failure summary"
# An output folder holding an earlier run is refused (its files would mix with this run's) unless
# --overwrite, which removes that run's files and keeps the user's own.
python3 -c "
import json
c=json.load(open('$src/data/robot_arm/robot_arm.json')); c['simulation']['t_end']=0.05; c['output']['vtu_stride']=5
c['output']['responses']=[r for r in c['output']['responses'] if 'window' not in r]
json.dump(c,open('$tmp/arm_short.json','w'))"
"$exe" simulate "$tmp/arm_short.json" -o "$tmp/reuse" -q || fail "simulate into a new folder"
echo "my notes" > "$tmp/reuse/notes.txt"
"$exe" simulate "$spring" -o "$tmp/reuse" -q 2> "$tmp/er.txt"; rc=$?
[ $rc -eq 2 ] && grep -q "holds an earlier run" "$tmp/er.txt" || fail "reused folder: rc $rc $(cat "$tmp/er.txt")"
"$exe" simulate "$spring" -o "$tmp/reuse" -q --overwrite || fail "--overwrite"
[ ! -e "$tmp/reuse/plate.pvd" ] && [ ! -e "$tmp/reuse/vtu" ] && [ -f "$tmp/reuse/notes.txt" ] || fail "--overwrite: $(ls "$tmp/reuse")"
# --overwrite with an input that does not load exits 2 and leaves the earlier run as it was
cp "$tmp/reuse/summary.json" "$tmp/reuse_before.json"
"$exe" simulate "$spring" -o "$tmp/reuse" -q --overwrite --set /simulation/h=-1 2> "$tmp/er2.txt"; rc=$?
[ $rc -eq 2 ] && cmp -s "$tmp/reuse/summary.json" "$tmp/reuse_before.json" \
  || fail "--overwrite with bad input: rc $rc, summary changed or removed: $(cat "$tmp/er2.txt")"
"$exe" verify "$spring" -o "$tmp/reuse" --overwrite --idas-rtol 0 2> "$tmp/er3.txt"; rc=$?
[ $rc -eq 2 ] && grep -q -- "--idas-rtol: expected a relative tolerance in \[1e-14, 1e-4\], got 0" "$tmp/er3.txt" \
  && cmp -s "$tmp/reuse/summary.json" "$tmp/reuse_before.json" || fail "verify --idas-rtol 0: rc $rc $(cat "$tmp/er3.txt")"
# an option that only the command can judge (the adjoint's memory is known once the model is
# built): the earlier run, set aside by --overwrite, comes back whole, and no stash remains
ls -A "$tmp/reuse" > "$tmp/reuse_ls_before.txt"
"$exe" sensitivity "$tmp/noper.json" --method adjoint --adjoint-memory 0.0001 -o "$tmp/reuse" --overwrite 2> "$tmp/er4.txt"; rc=$?
ls -A "$tmp/reuse" > "$tmp/reuse_ls_after.txt"
[ $rc -eq 2 ] && grep -q -- "--adjoint-memory 0.0001" "$tmp/er4.txt" && cmp -s "$tmp/reuse/summary.json" "$tmp/reuse_before.json" \
  && cmp -s "$tmp/reuse_ls_before.txt" "$tmp/reuse_ls_after.txt" \
  || fail "--overwrite with a bad --adjoint-memory: rc $rc $(cat "$tmp/er4.txt"); $(diff "$tmp/reuse_ls_before.txt" "$tmp/reuse_ls_after.txt")"
# a stash left by a killed run is removed by the next claim
mkdir -p "$tmp/reuse/.lsmbs-replaced-run" && touch "$tmp/reuse/.lsmbs-replaced-run/old.vtu"
"$exe" simulate "$spring" -o "$tmp/reuse" -q --overwrite && [ ! -e "$tmp/reuse/.lsmbs-replaced-run" ] \
  && [ -f "$tmp/reuse/notes.txt" ] || fail "a run over a left stash: $(ls -A "$tmp/reuse")"
# a run killed during --overwrite (SIGKILL: no summary.json of its own, its history.csv half
# written, the earlier run in the stash): the next run puts the earlier run back before it judges
# the folder, so the earlier run is never lost (it was deleted with the stash)
"$exe" simulate "$spring" -o "$tmp/killed" -q || fail "simulate into killed/"
cp "$tmp/killed/history.csv" "$tmp/killed_history_before.csv"
cp "$tmp/killed/summary.json" "$tmp/killed_summary_before.json"
mkdir -p "$tmp/killed/.lsmbs-replaced-run"
for f in $(python3 -c "import json; print(' '.join(json.load(open('$tmp/killed/summary.json'))['files']))"); do
  [ -e "$tmp/killed/$f" ] && mkdir -p "$(dirname "$tmp/killed/.lsmbs-replaced-run/$f")" \
    && mv "$tmp/killed/$f" "$tmp/killed/.lsmbs-replaced-run/$f"
done
echo "t,partial" > "$tmp/killed/history.csv"
"$exe" simulate "$spring" -o "$tmp/killed" -q 2> "$tmp/erk.txt"; rc=$?
[ $rc -eq 2 ] && grep -q "holds an earlier run" "$tmp/erk.txt" && [ ! -e "$tmp/killed/.lsmbs-replaced-run" ] \
  && cmp -s "$tmp/killed/history.csv" "$tmp/killed_history_before.csv" \
  && cmp -s "$tmp/killed/summary.json" "$tmp/killed_summary_before.json" \
  || fail "the earlier run after a killed --overwrite: rc $rc $(cat "$tmp/erk.txt"); $(ls -A "$tmp/killed")"
# a static run writes <body>.vtu and model.vtm beside summary.json; a run that replaces it with
# --overwrite leaves none of them: the folder holds exactly what the new summary.json lists
cant="$src/tests/integration/data/cantilever_ramp.json"
"$exe" static "$cant" -o "$tmp/st" -q || fail "static"
[ -f "$tmp/st/pl.vtu" ] || fail "static wrote no pl.vtu: $(ls "$tmp/st")"
# a user's file at a path this run would write, which the earlier (static) run does not list:
# kept, and the message says the earlier run does not list it (not that there is no earlier run)
echo "mine" > "$tmp/st/history.png"
"$exe" simulate "$cant" -o "$tmp/st" -q --overwrite 2> "$tmp/er_st.txt"; rc=$?
[ $rc -eq 2 ] && grep -q "holds history.png, which this run would write; the earlier run in this folder (its summary.json) does not list it as its own" "$tmp/er_st.txt" \
  && [ "$(cat "$tmp/st/history.png")" = mine ] || fail "user's history.png in a static run's folder: rc $rc $(cat "$tmp/er_st.txt")"
rm "$tmp/st/history.png"
# units of every column static writes, as simulate's (a tip displacement in m, by hand)
python3 -c "
import csv, json
S = json.load(open('$tmp/st/summary.json'))
cols = next(csv.reader(open('$tmp/st/history.csv')))
u = S['units']
assert u['t'] == 's' and all(c == 't' or c in u['measures'] for c in cols), (cols, u)
assert all(v == 'm' for k, v in u['measures'].items() if k.startswith('tip.')), u" || fail "static units"
"$exe" simulate "$spring" -o "$tmp/st" -q --overwrite || fail "simulate --overwrite over a static run"
python3 -c "
import json, os
d='$tmp/st'; listed=set(json.load(open(d+'/summary.json'))['files'])
on_disk={os.path.relpath(os.path.join(r,n),d) for r,_,ns in os.walk(d) for n in ns}
assert on_disk == listed | {'summary.json'} or on_disk == listed, (sorted(on_disk - listed), sorted(listed - on_disk))" \
  || fail "files of the replaced static run remain"
# Interruptions of simulate: SIGINT finishes the step, writes everything with status partial and
# reason interrupted, exits 130; SIGKILL over an earlier complete run leaves no complete-looking
# summary.json beside the new files.
for sig in INT KILL; do
  d="$tmp/sim_$sig"
  "$exe" simulate "$spring" -o "$d" -q || fail "simulate before $sig"   # an earlier complete run
  "$exe" simulate "$src/data/robot_arm/robot_arm.json" -o "$d" -q --overwrite & pid=$!
  for _ in $(seq 1 500); do ls "$d/vtu" 2> /dev/null | grep -q vtu && break; sleep 0.01; done
  kill -$sig $pid; wait $pid; rc=$?
  if [ $sig = INT ]; then
    [ $rc -eq 130 ] || fail "SIGINT: exit $rc, expected 130"
    python3 -c "
import json; s=json.load(open('$d/summary.json'))
assert s['status'] == 'partial' and s['reason'] == 'interrupted' and all(v is None for v in s['responses'].values()), s" || fail "SIGINT summary"
    [ -s "$d/history.csv" ] && [ -s "$d/plate.pvd" ] || fail "SIGINT: history.csv or plate.pvd missing"
  else
    [ $rc -eq 137 ] || fail "SIGKILL: exit $rc"
    if [ -f "$d/summary.json" ]; then
      python3 -c "import json; assert json.load(open('$d/summary.json'))['case_name'] == 'robot_arm'" || fail "SIGKILL: the earlier run's summary survived"
    fi
  fi
done
# IDAS sensitivities from the command line: statistics, quadratures with gradients, options as run.
"$exe" sensitivity "$spring" --method idas --rtol 1e-10 -o "$tmp/sens_idas" -q || fail "sensitivity --method idas"
python3 - "$tmp/sens_idas/summary.json" <<'PY' || fail "idas summary.json"
import json, sys
s = json.load(open(sys.argv[1]))
assert s["idas"]["steps"] > 0 and s["idas"]["nonlinear_iterations"] > 0 and "error_test_failures" in s["idas"]
o = s["options"]["sensitivity"]["idas"]
assert o["rtol"] == 1e-10 and o["atol"] == 1e-10 and o["t_end"] == 0.25, o
q = s["quadratures"]["energy_integral"]
assert q["value"] > 0 and set(q["gradient"]) == {"k", "c"}, q
print("idas sensitivity ok")
PY
# IDAS adjoint sensitivities: the quadratures' gradients agree with the forward ones above; the
# grid responses carry no gradient; a case without a time-integral response is refused.
"$exe" sensitivity "$spring" --method idas-adjoint --rtol 1e-10 -o "$tmp/sens_adj" -q || fail "sensitivity --method idas-adjoint"
python3 - "$tmp/sens_idas/summary.json" "$tmp/sens_adj/summary.json" <<'PY' || fail "idas-adjoint summary.json"
import json, sys
f, a = (json.load(open(x)) for x in sys.argv[1:3])
assert a["options"]["sensitivity"]["method"] == "idas-adjoint"
ad = a["idas"]["adjoint"]
assert ad["backward_problems"] == 2 and ad["steps"] > 0 and ad["residual_evaluations"] > 0, ad
for name in ("energy_integral", "mean_piston_x"):  # relative to each response's largest gradient
    gf, ga = f["quadratures"][name]["gradient"], a["quadratures"][name]["gradient"]
    n = max(abs(x) for x in gf.values())
    for v in gf:  # at rtol 1e-10 (atol 1e-10): measured 4e-8, bound 1e-6
        assert abs(ga[v] - gf[v]) <= 1e-6 * n, (name, v, ga[v], gf[v])
assert a["gradients"]["final_crank_angle"]["k"] is None, a["gradients"]["final_crank_angle"]
print("idas adjoint ok")
PY
python3 -c 'import json,sys; c=json.load(open(sys.argv[1])); c["output"]["responses"]=[r for r in c["output"]["responses"] if r["aggregate"] not in ("average","integral")]; json.dump(c,open(sys.argv[2],"w"))' \
  "$spring" "$tmp/no_integrals.json"
! "$exe" sensitivity "$tmp/no_integrals.json" --method idas-adjoint -o "$tmp/sens_adj_bad" -q 2> "$tmp/adj_err.txt" || fail "idas-adjoint without integrals accepted"
grep -q "no_integrals.json: /output/responses: the idas-adjoint method" "$tmp/adj_err.txt" || fail "idas-adjoint refusal: $(cat "$tmp/adj_err.txt")"
# IDAS simulation options reach IDAS and summary.json.
"$exe" simulate "$spring" --integrator idas --rtol 1e-7 --error-test positions --max-order 3 -o "$tmp/sim_idas" -q || fail "simulate --integrator idas"
python3 - "$tmp/sim_idas/summary.json" <<'PY' || fail "idas simulate summary.json"
import json, sys
s = json.load(open(sys.argv[1]))
c, o = s["counts"], s["options"]["idas"]
assert c["error_test"] == "positions" and c["steps"] > 0 and "nonlinear_convergence_failures" in c, c
assert o["rtol"] == 1e-7 and o["atol"] == 1e-7 and o["max_order"] == 3 and o["error_test"] == "positions", o
assert o["klu_pivot_tolerance"] == 1.0 and c["max_order"] == 3, (o, c)
assert "energy_integral" in s["quadratures"]
print("idas simulate ok")
PY
# Without --max-order the order is resolved from the model: 5 for the rigid spring crank.
"$exe" simulate "$spring" --integrator idas --rtol 1e-6 -o "$tmp/sim_idas_auto" -q || fail "simulate --integrator idas (auto order)"
python3 -c 'import json,sys; s=json.load(open(sys.argv[1])); assert s["options"]["idas"]["max_order"] == "auto" and s["counts"]["max_order"] == 5, s["counts"]' \
  "$tmp/sim_idas_auto/summary.json" || fail "idas auto order"
# Progress (issue 9): not on a terminal, optimize prints its final summary only (no row per
# evaluation, no progress line); --verbose adds the rows; on a terminal (a pseudo-terminal from
# script(1)) a self-overwriting progress line with time, step and Newton iterations appears.
"$exe" optimize "$tmp/opt.json" -o "$tmp/opt_quiet" > "$tmp/opt_out.txt" 2>&1 || fail "optimize (not a terminal)"
grep -q "objective" "$tmp/opt_out.txt" || fail "no final summary: $(cat "$tmp/opt_out.txt")"
! grep -q $'\r' "$tmp/opt_out.txt" || fail "progress line written to a file"
! grep -qE "^ +1 +[0-9.]" "$tmp/opt_out.txt" || fail "evaluation rows without a terminal"
"$exe" optimize "$tmp/opt.json" -o "$tmp/opt_verbose" -v > "$tmp/opt_verb.txt" 2>&1 || fail "optimize -v"
grep -qE "^ +1 +[0-9.]" "$tmp/opt_verb.txt" || fail "--verbose: no evaluation rows: $(cat "$tmp/opt_verb.txt")"
if command -v script > /dev/null; then
  script -qec "'$exe' sensitivity '$spring' -o '$tmp/sens_tty'" /dev/null > "$tmp/tty.txt" 2>&1 || fail "sensitivity on a pty"
  grep -qE $'\r.*t = [0-9.]+ s .*step [0-9]+ +Newton [0-9]' "$tmp/tty.txt" || fail "no progress line on a terminal"
  script -qec "'$exe' sensitivity '$spring' -o '$tmp/sens_tty_q' -q" /dev/null > "$tmp/tty_q.txt" 2>&1 || fail "-q on a pty"
  [ ! -s "$tmp/tty_q.txt" ] || fail "--quiet printed: $(cat -v "$tmp/tty_q.txt")"
fi
# Bench: the step/floor ratio and the sensitivity overheads are recorded.
"$exe" bench "$spring" -o "$tmp/bench" --repetitions 5 > /dev/null || fail "bench"
python3 -c "
import json, math; b=json.load(open('$tmp/bench/bench.json'))
assert b['primal']['steps'] == 250
p, f = b['primal'], b['floor_seconds']
assert p['factorizations_per_step'] == p['newton_per_step']  # full Newton: one factorization per iteration
# the timings are recorded (their values depend on the machine and its load: not asserted)
assert all(isinstance(x, float) for x in (p['step_over_floor'], p['setup_seconds'], f['factor'], f['solve']))
s = b['sensitivities']
assert set(s) == {'direct-analytic', 'semi-analytical-central', 'direct-analytic/last', 'semi-analytical-central/last'}, set(s)
assert all(v['ok'] for v in s.values())
assert s['direct-analytic']['matrix'] == 'converged' and s['direct-analytic/last']['matrix'] == 'last'
# the default refactorizes once per step more than the paper's last-iteration matrix
assert s['direct-analytic']['factorizations'] == s['direct-analytic/last']['factorizations'] + s['direct-analytic']['steps']
assert b['peak_rss_kb'] > 0" || fail "bench.json"
# verify says what it will cost after the primal run, and shows progress inside its parts off a
# terminal (LSMBS_PROGRESS_SECONDS=0: every report); the plan's count is the documented one:
# 6 gradient runs + 2n fd-central + 21 Δp runs + Σ h0/h of the time-step study (4h, 2h, h, h/2)
LSMBS_PROGRESS_SECONDS=0 "$exe" verify "$spring" -o "$tmp/vprog" > /dev/null 2> "$tmp/vprog.txt" || fail "verify with progress: $(tail -3 "$tmp/vprog.txt")"
grep -q "lsmbs verify: one simulation took .* s; the verification runs about [0-9]* simulations' worth" "$tmp/vprog.txt" \
  && grep -q "lsmbs verify:   IDAS t = " "$tmp/vprog.txt" || fail "verify's plan and progress lines: $(head -5 "$tmp/vprog.txt")"
python3 -c "
import json; S = json.load(open('$tmp/vprog/summary.json')); c = S['cost']
h0 = json.load(open('$spring'))['simulation']['h']
assert c['simulations_planned_besides_idas'] == 6 + 2 * 2 + 21 + sum(h0 / h for h in S['options']['h_study_steps']), c" || fail "verify's cost in summary.json"
# verify on a rigid mechanism nobody here wrote (a skeptical user's): the forward semi-analytical
# method fails at Δp = 1e-2 and 1e-3 (the pendulum mass's pseudo-load; its derivative is not
# finite); the study records the failed points and the verification goes on to its report
pend="$src/tests/integration/data/slider_pendulum_rigid.json"
"$exe" verify "$pend" -o "$tmp/verify_pend" --no-idas --no-mesh-study > "$tmp/vp.txt" 2>&1; rc=$?
[ $rc -eq 0 ] && [ -s "$tmp/verify_pend/report.md" ] \
  && grep -q "NOTE — Δp study: semi-analytical at Δp = 1e-02" "$tmp/vp.txt" || fail "verify with a failed Δp run: rc $rc $(tail -5 "$tmp/vp.txt")"
python3 -c "
import csv, math
rows = {r['delta']: r for r in csv.DictReader(open('$tmp/verify_pend/dp_study.csv'))}
assert math.isnan(float(rows['1.0e-02']['forward'])), rows['1.0e-02']
assert all(math.isfinite(float(r['central'])) for r in rows.values())" || fail "dp_study.csv of the failed points"
echo "cli: all checks passed"
