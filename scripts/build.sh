#!/usr/bin/env bash
# Configures and builds lsmbs (Release by default) in build/ or $LSMBS_BUILD_DIR.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${LSMBS_BUILD_DIR:-$root/build}"
type="${LSMBS_BUILD_TYPE:-Release}"
# Ninja for a new build folder: it compiles the library layers in parallel (Make waits for each
# layer's objects before starting the next; docs/performance.md 'CI time'); an existing folder
# keeps its generator
generator=()
[ -f "$build/CMakeCache.txt" ] || { command -v ninja >/dev/null && generator=(-G Ninja); }
cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE="$type" "$@" >/dev/null
cmake --build "$build" -j"$(nproc)"
