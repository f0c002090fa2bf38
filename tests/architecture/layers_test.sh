#!/usr/bin/env bash
# The module layers are enforced by the build: each module compiles against an include tree with
# only the modules below it (src/CMakeLists.txt). This test checks that the trees do what they
# claim, against the graph written independently here (docs/architecture.md): every header of an
# allowed module is found, and a header of every module above is not.
#   layers_test.sh CXX LAYERS_DIR GENERATED_DIR SRC_DIR [-I...]
set -u
cxx=$1 layers=$2 generated=$3 src=$4
shift 4
extra=("$@")
declare -A below=(
  [core]="" [linalg]="core" [fem]="core linalg" [geometry]="core linalg fem" [mbs]="core linalg fem"
  [design]="core linalg fem geometry mbs" [responses]="core linalg fem mbs" [integrators]="core linalg fem mbs"
  [sensitivity]="core linalg fem geometry mbs design responses integrators"
  [records]="core linalg fem geometry mbs design responses integrators sensitivity"
  [optimization]="core linalg fem geometry mbs design responses integrators sensitivity records"
  [io]="core linalg fem geometry mbs design responses integrators sensitivity records optimization"
  [runs]="core linalg fem geometry mbs design responses integrators sensitivity records optimization io")
modules="core linalg fem geometry mbs design responses integrators sensitivity records optimization io runs"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0 checked=0
for m in $modules; do
  for other in $modules; do
    [ "$other" = "$m" ] && continue
    header=$(cd "$src/lsmbs/$other" && ls *.hpp | head -1)
    echo "#include \"lsmbs/$other/$header\"" > "$tmp/t.cpp"
    allowed=0
    for b in ${below[$m]}; do [ "$b" = "$other" ] && allowed=1; done
    out=$("$cxx" -std=c++20 -E -o /dev/null -I "$layers/$m" -I "$generated" "${extra[@]}" "$tmp/t.cpp" 2>&1)
    rc=$?
    checked=$((checked + 1))
    if [ $allowed = 1 ] && [ $rc != 0 ]; then
      echo "FAIL: $m may include lsmbs/$other/$header, but it does not compile:"; echo "$out" | head -5; fail=1
    elif [ $allowed = 0 ] && ! grep -q "lsmbs/$other/$header: No such file" <<<"$out"; then
      echo "FAIL: $m must not see lsmbs/$other/$header (a module above it), but its include tree has it"; fail=1
    fi
  done
done
echo "$checked module pairs checked"
exit $fail
