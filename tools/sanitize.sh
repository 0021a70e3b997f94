#!/usr/bin/env bash
# The sanitizer tree (docs/hardening.md): clang with AddressSanitizer and
# UndefinedBehaviorSanitizer on every target, plus the libFuzzer harnesses;
# builds it and runs its tests (tools/test.sh does this when CI=true or
# AIA_SANITIZE=1).
#   tools/sanitize.sh [--configure-only] [BUILD_DIR]     (default build-asan)
# AIA_SANITIZE_LABELS picks the ctest labels (default below); system
# libraries' own leaks are suppressed by tools/sanitizers/*.supp.
set -euo pipefail
cd "$(dirname "$0")/.."
configure_only=0
if [ "${1:-}" = "-h" ] || [ "${1:-}" = "--help" ]; then
  sed -n '2,8p' "$0" | sed 's/^# \{0,1\}//'
  exit 0
fi
[ "${1:-}" = "--configure-only" ] && { configure_only=1; shift; }
dir=${1:-build-asan}
if [ ! -f "$dir/build.ninja" ]; then
  CC=clang CXX=clang++ cmake -S . -B "$dir" -G Ninja \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" \
    -DAIA_SANITIZE=ON -DAIA_FUZZ=ON -DAIA_BUILD_BENCHMARKS=OFF
fi
[ "$configure_only" = 1 ] && exit 0
jobs=${AIA_JOBS:-$(nproc)}
cmake --build "$dir" -j "$jobs"
supp=$PWD/tools/sanitizers
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:suppressions=$supp/asan.supp
export LSAN_OPTIONS=suppressions=$supp/lsan.supp:print_suppressions=0
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1:suppressions=$supp/ubsan.supp
labels=${AIA_SANITIZE_LABELS:-core|estimation|comm|scenario|world|sim|planning|learning|render|fuzz|runtime|commands}
# Left out here: the golden traces (recorded with the main build's gcc; clang's
# floating point differs in the last bits and missions diverge from there)
# the two-rank MPI test (OpenMPI's plugins leak and are unloaded before
# LeakSanitizer reports, so their leaks cannot be told from ours), and the
# experiment drivers (Python over aia; the commands they call run under the
# sanitizers in the CLI tests; 2-4 minutes here), and the filter's
# 100 000-step numerical stress test (the same arithmetic as the main tree's
# run of it, 200 s here; the filter's memory is checked by every other
# estimation test).
exclude='^golden\.|TwoMpiRanksGiveTheFilesOfOneProcess|^ExperimentTest\.|HundredThousandStepsKeepEveryBlockSpd'
# Run with leak detection off (AddressSanitizer and UBSan still on): at this
# test's exit LeakSanitizer's tracer crashes reading a dynamic TLS block of
# the dlopen'd libtorch plugin (`Tracer caught signal 11`, a bogus DTLS range;
# clang 14's compiler-rt on glibc 2.36) after the test has passed; valgrind
# finds nothing in the same test.
no_leak_check='IgbNetPolicyTest\.NoUndoMovesOnWhereNothingIsOpen'
cd "$dir"
status=0
ctest --output-on-failure -j "$jobs" --timeout 900 -L "$labels" \
  -E "$exclude|$no_leak_check" || status=$?
ASAN_OPTIONS=${ASAN_OPTIONS/detect_leaks=1/detect_leaks=0} \
  ctest --output-on-failure --timeout 900 -R "$no_leak_check" || status=$?
exit "$status"
