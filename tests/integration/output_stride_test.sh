#!/usr/bin/env bash
# history.csv keeps the last recorded step whatever csv_stride is (a stride larger than the step
# count once left only the t = 0 row), every n-th step otherwise; a model of rigid bodies only gets
# its bodies in vtu/ every vtu_stride-th step (a multiblock each, listing every body of the case).
set -u
lsmbs="$1"; root="$2"
t="$(mktemp -d)"; trap 'rm -rf "$t"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
python3 - "$root/data/slider_crank_rigid/slider_crank_rigid.json" "$t" <<'PY' || fail "case set-up"
import json, sys
c = json.load(open(sys.argv[1]))
c["simulation"]["t_end"] = 0.01
c["simulation"]["h"] = 1e-3
for name, stride in (("s1", 1), ("s3", 3), ("s99", 99)):
    c["output"]["csv_stride"] = stride
    c["output"]["vtu_stride"] = 2
    json.dump(c, open("%s/%s.json" % (sys.argv[2], name), "w"))
PY
for s in s1 s3 s99; do "$lsmbs" simulate "$t/$s.json" -o "$t/$s" -q || fail "simulate $s"; done
python3 - "$t" <<'PY' || fail "VTK files of a rigid model"
import json, os, sys, xml.etree.ElementTree as ET
d = sys.argv[1] + "/s1"
bodies = {b["name"] for b in json.load(open(sys.argv[1] + "/s1.json"))["bodies"]}
vtms = sorted(f for f in os.listdir(d + "/vtu") if f.endswith(".vtm"))
assert vtms == sorted("model_%d.vtm" % k for k in range(0, 11, 2)), vtms  # 10 steps, stride 2
for f in vtms:
    names = {e.get("name") for e in ET.parse(d + "/vtu/" + f).getroot().iter("DataSet")}
    assert names == bodies, (f, names, bodies)
PY
python3 - "$t" <<'PY' || fail "strides"
import csv, sys
d = sys.argv[1]
rows = {s: list(csv.reader(open("%s/%s/history.csv" % (d, s))))[1:] for s in ("s1", "s3", "s99")}
times = lambda s: [round(float(r[0]), 9) for r in rows[s]]
assert times("s1") == [round(0.001 * i, 9) for i in range(11)], times("s1")  # t_end / h = 10 steps
assert times("s3") == [0.0, 0.003, 0.006, 0.009, 0.01], times("s3")
assert times("s99") == [0.0, 0.01], times("s99")
assert rows["s99"][-1] == rows["s1"][-1] and rows["s3"][-1] == rows["s1"][-1]
PY
echo PASS
