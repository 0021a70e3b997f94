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
# intercept_tls_get_addr=0: at the exit of a process that loaded the
# libtorch plugin, LeakSanitizer's tracer crashed reading the plugin's
# dynamic TLS blocks (`Tracer caught signal 11`, a bogus DTLS range; clang
# 14's compiler-rt on glibc 2.36), after the test had passed, in whichever
# test of the learning suite it struck (valgrind finds nothing there). Not
# tracking dynamic TLS ends it; leaks are still checked everywhere.
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:intercept_tls_get_addr=0:suppressions=$supp/asan.supp
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
cd "$dir"
status=0
ctest --output-on-failure -j "$jobs" --timeout 900 -L "$labels" \
  -E "$exclude" || status=$?
exit "$status"
