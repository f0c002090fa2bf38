#!/usr/bin/env bash
# AddressSanitizer + UndefinedBehaviorSanitizer build (build-asan/) and test run, with UBSan
# reports fatal and Eigen's own assertions on (a Debug build at -O1: the assertions found a
# wrongly sized constraint Hessian that the Release build silently tolerated).
#   scripts/sanitize.sh          every test (about 18 minutes of tests on 2 cores)
#   scripts/sanitize.sh --ci     every unit test and the integration tests that run in seconds
#                                under ASan (what .ci/run does: about 5 minutes incl. the build)
#   scripts/sanitize.sh [--ci] [more ctest arguments]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
ci=0
if [ "${1:-}" = "--ci" ]; then ci=1; shift; fi
bash "$root/scripts/setup-deps.sh"
build="$root/build-asan"
# unity build: the Eigen-heavy translation units compile about twice as fast batched
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g1" -DLSMBS_WITH_SANITIZERS=ON \
  -DLSMBS_BUILD_TESTS=ON -DCMAKE_UNITY_BUILD=ON >/dev/null
cmake --build "$build" -j"$(nproc)"
cd "$build"
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
if [ $ci -eq 1 ]; then
  # integration tests that take more than 20 s under ASan (the full run above covers them)
  slow='^(Sensitivity\.(RobotArm|SemiAnalyticalError)|Idas\.GeneralizedAlphaConvergesToIdasAtSecondOrderOnAFlexibleModel|IdasAdjoint\.GradientsAgreeWithForwardSensitivitiesOnAFlexibleArm|RobotArm\.SolidPlate|Optimization\.Coarse|cli_end_to_end|verify_connecting_rod|gradient_corpus|structure_fuzz|fault_injection)'
  ctest --output-on-failure -j"$(nproc)" --timeout 600 -E "$slow" "$@"
else
  ctest --output-on-failure -j"$(nproc)" --timeout 1800 "$@"
fi
