#!/usr/bin/env bash
# A sensitivity run whose gradient is NaN or infinite is a numerical failure (exit 1, summary
# partial, no gradients.csv), never a complete run with null entries. Case: the generated free
# three-link chain of corpus seed 0 (chaotic, 2,000 steps), where the forward semi-analytical
# pseudo-load with a relative step of 1e-4 overflows; with 1e-6 it is finite (exit 0).
set -u
lsmbs="$1"; root="$2"
t="$(mktemp -d)"; trap 'rm -rf "$t"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
python3 "$root/verification/corpus/gen_mechanisms.py" --seed 0 -o "$t/case.json" || fail "generator"
"$lsmbs" sensitivity "$t/case.json" --method semi-analytical --delta 1e-4 -o "$t/big" -q 2>"$t/err"
rc=$?
[ "$rc" = 1 ] || fail "expected exit 1 for a non-finite gradient, got $rc"
grep -q "not finite" "$t/err" || fail "message does not say the gradient is not finite: $(cat "$t/err")"
python3 - "$t/big/summary.json" <<'PY' || fail "summary"
import json, sys
s = json.load(open(sys.argv[1]))
assert s["status"] == "partial", s["status"]
assert "not finite" in s.get("failure", ""), s.get("failure")
PY
[ ! -e "$t/big/gradients.csv" ] || fail "gradients.csv written for a failed run"
"$lsmbs" sensitivity "$t/case.json" --method semi-analytical --delta 1e-6 -o "$t/small" -q || fail "delta 1e-6 should succeed"
echo PASS
