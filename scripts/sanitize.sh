#!/usr/bin/env bash
# Builds with AddressSanitizer + UndefinedBehaviorSanitizer (build-asan/) and runs the tests with
# UBSan reports made fatal. About 16 minutes on 2 cores (8.6 min build, 7.5 min tests), so CI
# does not run it on every submission (its budget is 20 minutes); run it before releases.
#   scripts/sanitize.sh [ctest arguments, e.g. -L unit]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/setup-deps.sh"
LSMBS_BUILD_DIR="$root/build-asan" LSMBS_BUILD_TYPE=RelWithDebInfo bash "$root/scripts/build.sh" -DLSMBS_WITH_SANITIZERS=ON
cd "$root/build-asan"
UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 ASAN_OPTIONS=detect_leaks=1 ctest --output-on-failure -j"$(nproc)" "$@"
