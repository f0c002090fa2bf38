#!/usr/bin/env bash
# Installs missing packages, builds (Release with tests), and runs every test through ctest (the
# MPI tests too: OpenMPI is among the packages; they run on localhost with --oversubscribe).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/setup-deps.sh"
bash "$root/scripts/build.sh" -DLSMBS_BUILD_TESTS=ON
cd "${LSMBS_BUILD_DIR:-$root/build}"
ctest --output-on-failure -j"$(nproc)" "$@"
