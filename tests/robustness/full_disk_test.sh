#!/usr/bin/env bash
# A full disk is a failure, never a complete run: lsmbs writes into a small tmpfs (mounted in a
# private mount namespace) of several sizes, from one that holds nothing to one that holds
# everything. Whatever the size:
#   * exit 0 means a complete run: summary.json says complete and every file it lists is whole;
#   * otherwise exit 1, the system's reason ("No space left on device") on stderr, no temporary
#     file left, and no summary.json that says complete (a partial one, listing only whole files,
#     or none when not even it fits);
# and at least one size must end each way. An optimization that ran out of space resumes to the
# uninterrupted run's design once the disk has room again (the tmpfs remounted larger).
#   full_disk_test.sh LSMBS SOURCE_DIR        (exit 77: no tmpfs can be mounted here; skipped)
set -uo pipefail
exe="$(readlink -f "$1")"
src="$(readlink -f "$2")"
if [ "${LSMBS_IN_NAMESPACE:-}" != 1 ]; then
  for how in "-m" "-rm"; do
    if unshare $how true 2> /dev/null; then
      LSMBS_IN_NAMESPACE=1 exec unshare $how bash "$0" "$@"
    fi
  done
  echo "full_disk: no private mount namespace here (unshare -m / -rm refused): skipped"
  exit 77
fi
tmp="$(mktemp -d)"
disk="$tmp/disk"
mkdir -p "$disk"
mount -t tmpfs -o size=4k tmpfs "$disk" 2> /dev/null || {
  echo "full_disk: cannot mount a tmpfs: skipped"
  exit 77
}
fail() {
  echo "FAIL: $*" >&2
  umount "$disk" 2> /dev/null
  exit 1
}
python3 - "$src/tests/integration/data/cantilever_ramp.json" "$tmp" << 'PY'
import json, sys
c = json.load(open(sys.argv[1]))
c["simulation"]["t_end"] = 0.02
c["output"] = dict(c["output"], vtu_stride=2)
json.dump(c, open(sys.argv[2] + "/case.json", "w"))
c["optimization"]["stop"]["max_evaluations"] = 3
json.dump(c, open(sys.argv[2] + "/opt.json", "w"))
PY

# check OUT RC STDERR: the invariants above; prints "complete" or "failed"
check() {
  local out=$1 rc=$2 err=$3
  find "$out" -name '*.tmp.*' 2> /dev/null | grep -q . && fail "temporary files left: $(find "$out" -name '*.tmp.*')"
  if [ "$rc" -eq 0 ]; then
    python3 - "$out" << 'PY' || fail "exit 0 but the results are not whole: $out"
import json, os, sys
out = sys.argv[1]
S = json.load(open(os.path.join(out, "summary.json")))
assert S["status"] == "complete", S["status"]
for f in S["files"]:
    p = os.path.join(out, f)
    assert os.path.isfile(p) or os.path.isdir(p), f
    if f.endswith(".png"):
        d = open(p, "rb").read()
        assert d.startswith(b"\x89PNG") and d[-8:-4] == b"IEND", f
PY
    echo complete
    return
  fi
  [ "$rc" -eq 1 ] || fail "exit $rc (expected 0 or 1): $(cat "$err")"
  grep -q "No space left on device" "$err" || fail "the reason is not given: $(cat "$err")"
  if [ -f "$out/summary.json" ]; then
    python3 - "$out" << 'PY' || fail "a summary that lies after a full disk: $out"
import json, os, sys
out = sys.argv[1]
S = json.load(open(os.path.join(out, "summary.json")))
assert S["status"] != "complete", S["status"]
assert "No space left on device" in S.get("failure", ""), S.get("failure")
for f in S.get("files", []):
    assert os.path.exists(os.path.join(out, f)), f
PY
  fi
  echo failed
}

seen=""
for size in 8k 24k 48k 96k 160k 256k 2m; do
  mount -o remount,size=$size "$disk" || fail "remount"
  rm -rf "${disk:?}"/*
  "$exe" simulate "$tmp/case.json" -o "$disk/out" -q 2> "$tmp/err.txt"
  rc=$?
  seen="$seen $(check "$disk/out" $rc "$tmp/err.txt")" || exit 1
done
case "$seen" in *complete*failed* | *failed*complete*) ;; *) fail "sizes did not give both outcomes: $seen" ;; esac
echo "simulate on tmpfs of 8k … 2m:$seen"

# optimize: out of space, then --resume once there is room
mount -o remount,size=4m "$disk"
rm -rf "${disk:?}"/*
"$exe" optimize "$tmp/opt.json" -o "$disk/ref" -q --no-check 2> "$tmp/err.txt" || fail "reference optimization: $(cat "$tmp/err.txt")"
cp "$disk/ref/summary.json" "$tmp/ref_summary.json"
rm -rf "${disk:?}"/*
mount -o remount,size=40k "$disk"
"$exe" optimize "$tmp/opt.json" -o "$disk/opt" -q --no-check 2> "$tmp/err.txt"
rc=$?
[ "$(check "$disk/opt" $rc "$tmp/err.txt")" = failed ] || fail "optimize on 40k did not run out of space"
mount -o remount,size=4m "$disk"
"$exe" optimize "$tmp/opt.json" -o "$disk/opt" -q --no-check --resume 2> "$tmp/err.txt" || fail "resume: $(cat "$tmp/err.txt")"
python3 - "$tmp/ref_summary.json" "$disk/opt/summary.json" << 'PY' || fail "the resumed design differs"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:])
assert b["status"] == "complete" and a["final"]["design"] == b["final"]["design"], (a["final"], b["final"])
PY
echo "optimize out of space, then --resume: the reference's design"
umount "$disk"
rm -rf "$tmp"
echo "full_disk: pass"
