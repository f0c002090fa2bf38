#!/usr/bin/env bash
# Fuzzes the case loader with libFuzzer (clang, AddressSanitizer + UndefinedBehaviorSanitizer)
# for a bounded time, starting from tests/fuzz/corpus/. New interesting inputs are added to a
# work corpus in build-fuzz/corpus; crashes are written to build-fuzz/crash-*. Keep a finding
# by fixing the loader and copying the input to tests/fuzz/corpus/ (ctest replays that folder).
#   scripts/fuzz.sh [SECONDS]   (default 300)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
seconds="${1:-300}"
command -v clang++ >/dev/null || { echo "fuzz.sh: clang++ is needed (apt-get install clang)" >&2; exit 2; }
b="$root/build-fuzz"
san="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer -g -O1"
cmake -S "$root" -B "$b" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DLSMBS_FUZZ=ON -DCMAKE_CXX_FLAGS="$san -fsanitize=fuzzer-no-link" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
cmake --build "$b" -j"$(nproc)" --target case_loader_fuzz
mkdir -p "$b/corpus"
cd "$b"
# -timeout: a single input loading for more than 10 s is a hang; -rss_limit_mb: memory blow-up
./tests/case_loader_fuzz -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 -print_final_stats=1 \
  corpus "$root/tests/fuzz/corpus"
