#!/usr/bin/env bash
# Configures and builds lsmbs (Release by default) in build/ or $LSMBS_BUILD_DIR.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${LSMBS_BUILD_DIR:-$root/build}"
type="${LSMBS_BUILD_TYPE:-Release}"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE="$type" "$@" >/dev/null
cmake --build "$build" -j"$(nproc)"
