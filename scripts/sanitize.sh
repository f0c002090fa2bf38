#!/usr/bin/env bash
# AddressSanitizer + UndefinedBehaviorSanitizer build (build-asan/) and test run, with UBSan
# reports fatal and Eigen's own assertions on (a Debug build at -O1: the assertions found a
# wrongly sized constraint Hessian that the Release build silently tolerated).
#   scripts/sanitize.sh          every test (about 18 minutes of tests on 2 cores)
#   scripts/sanitize.sh --ci     every unit test and the integration tests that run in seconds
#                                under ASan (a quick local check; about 25 minutes incl. the build
#                                on a slow 2-core machine, so neither CI entry point runs it)
#   scripts/sanitize.sh --full   every test, including the heavy ones --ci skips, and a report of
#                                the run in verification/reports/sanitizer/full.md (commit, date,
#                                result, failures, slowest tests); the scheduled run (.ci/scheduled,
#                                e.g. weekly) — commit the report it writes
#   scripts/sanitize.sh --tsan   ThreadSanitizer build (build-tsan/) of the library and the tests
#                                of evaluations that run at once (Concurrency.*, the design as a
#                                value); the scheduled run (.ci/scheduled) runs it
#   scripts/sanitize.sh [--ci|--full] [more ctest arguments]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
mode=all
case "${1:-}" in
  --ci) mode=ci; shift ;;
  --full) mode=full; shift ;;
  --tsan) mode=tsan; shift ;;
esac
if [ "$mode" = tsan ]; then
  bash "$root/scripts/setup-deps.sh"
  build="$root/build-tsan"
  generator=()
  [ -f "$build/CMakeCache.txt" ] || { command -v ninja >/dev/null && generator=(-G Ninja); }
  cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g1" \
    -DLSMBS_WITH_TSAN=ON -DLSMBS_WITH_MPI=OFF -DLSMBS_BUILD_TESTS=ON -DLSMBS_BUILD_EXAMPLES=OFF -DCMAKE_UNITY_BUILD=ON >/dev/null
  cmake --build "$build" -j"$(nproc)" --target test_concurrency
  cd "$build"
  # halt_on_error: a data race fails the test; second_deadlock_stack: both stacks of an inversion
  export TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1
  exec ./tests/test_concurrency "$@"
fi
bash "$root/scripts/setup-deps.sh"
build="$root/build-asan"
# unity build: the Eigen-heavy translation units compile about twice as fast batched
build_start=$(date +%s)
# --ci builds no examples (their slow ones are not run under --ci; the fast one runs in Release)
examples=ON
[ "$mode" = ci ] && examples=OFF
generator=()  # Ninja for a new folder, as scripts/build.sh
[ -f "$build/CMakeCache.txt" ] || { command -v ninja >/dev/null && generator=(-G Ninja); }
# without MPI: OpenMPI's own allocations at MPI_Init read as leaks to LeakSanitizer; the MPI
# paths are tested in the Release build (ctest mpi_scale_out)
cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g1" -DLSMBS_WITH_SANITIZERS=ON -DLSMBS_WITH_MPI=OFF \
  -DLSMBS_BUILD_TESTS=ON -DLSMBS_BUILD_EXAMPLES=$examples -DCMAKE_UNITY_BUILD=ON >/dev/null
cmake --build "$build" -j"$(nproc)"
build_seconds=$(( $(date +%s) - build_start ))
cd "$build"
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
# integration tests that take more than 20 s under ASan (--ci skips them; --full and the default run them;
# the Release ctest runs every one)
slow='^(Sensitivity\.(RobotArm|SemiAnalyticalError)|CantileverFrequency\.FirstFrequency|Idas\.ReferencePresetIntegratesTheFlexibleConnectingRod|DesignMap\.ThreeHolesOfTable2|Idas\.GeneralizedAlphaConvergesToIdasAtSecondOrderOnAFlexibleModel|IdasAdjoint\.GradientsAgreeWithForwardSensitivitiesOnAFlexibleArm|Adjoint\.(RobotArmFifteenVariables|CoarseRodOneHole)|RobotArm\.SolidPlate|Optimization\.Coarse|PaperTable5|cli_end_to_end|verify_connecting_rod|gradient_corpus|structure_fuzz|fault_injection|andrews_squeezer|idas_adjoint_values|gradient_check_shipped|Idas\.ForwardSensitivitiesOnLevelSetVariables|Idas\.DirectionalSensitivities|outputs_pandas|interrupt_resume|example_design_loop|example_robot_arm|module_layers|Stress\.(DesignGradients|IdasGradients)|Concurrency\.(FlexibleRodWithALevelSetDesign|OneThreadGivesTheBitsOfTwo)|adjoint_corpus|adjoint_corpus_new_loads|hostile_strings|interrupt_phases|install_and_consume|robustness_messages)'
case $mode in
  ci) ctest --output-on-failure -j"$(nproc)" --timeout 600 -E "$slow" "$@" ;;
  all) ctest --output-on-failure -j"$(nproc)" --timeout 1800 "$@" ;;
  full)
    report_dir="$root/verification/reports/sanitizer"
    mkdir -p "$report_dir"
    log="$report_dir/full.log"
    test_start=$(date +%s)
    set +e
    ctest --output-on-failure -j"$(nproc)" --timeout 1800 "$@" 2>&1 | tee "$log"
    rc=${PIPESTATUS[0]}
    set -e
    test_seconds=$(( $(date +%s) - test_start ))
    commit=$(git -C "$root" rev-parse HEAD 2>/dev/null || echo unknown)
    dirty=$(git -C "$root" status --porcelain --untracked-files=no 2>/dev/null | grep -q . && echo " (uncommitted changes)" || true)
    {
      echo "# Full sanitizer run"
      echo
      echo "\`scripts/sanitize.sh --full\` (AddressSanitizer + UBSan, UBSan fatal, Debug -O1 with Eigen's assertions),"
      echo "every ctest test including the heavy ones \`--ci\` skips."
      echo
      echo "| | |"
      echo "|---|---|"
      echo "| date | $(date -u +%Y-%m-%dT%H:%MZ) |"
      echo "| commit | \`$commit\`$dirty |"
      echo "| machine | $(nproc) cores, $(uname -sr) |"
      echo "| compiler | $("${CXX:-c++}" --version 2>/dev/null | head -1) |"
      echo "| build | ${build_seconds} s |"
      echo "| tests | ${test_seconds} s |"
      echo "| result | $(grep -E '^[0-9]+% tests passed' "$log" | tail -1) (exit $rc) |"
      echo
      if grep -q '^The following tests FAILED' "$log"; then
        echo "## Failed"
        echo
        sed -n '/^The following tests FAILED/,$p' "$log" | grep -E '^[[:space:]]+[0-9]+ - ' | sed 's/^[[:space:]]*/- /'
        echo
      fi
      if grep -qE 'ERROR: (AddressSanitizer|LeakSanitizer)|runtime error:' "$log"; then
        echo "## Sanitizer reports"
        echo
        echo '```'
        grep -E 'ERROR: (AddressSanitizer|LeakSanitizer)|runtime error:' "$log" | sort | uniq -c | head -40
        echo '```'
        echo
      fi
      echo "## Slowest tests"
      echo
      echo "| test | seconds |"
      echo "|---|---|"
      grep -E 'Test +#[0-9]+: ' "$log" | sed -E 's/.*Test +#[0-9]+: ([^ ]+) .* ([0-9.]+) sec$/\2 \1/' | sort -rn | head -12 |
        awk '{print "| " $2 " | " $1 " |"}'
    } > "$report_dir/full.md"
    echo "report: $report_dir/full.md (log: $log)"
    exit "$rc"
    ;;
esac
