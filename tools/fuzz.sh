#!/usr/bin/env bash
# Runs one libFuzzer harness for a while (docs/hardening.md):
#   tools/fuzz.sh NAME SECONDS [BUILD_DIR]
# NAME: scenario, map, mjcf, dataset or model. Builds BUILD_DIR (default
# build-asan: clang, ASan + UBSan, AIA_FUZZ=ON) when needed, fuzzes a scratch
# copy of fuzz/corpus/NAME (new inputs stay out of the repository) with a
# 2 GiB memory and 30 s time limit per input, and writes crashes into
# fuzz-out/NAME/crashes/. Exit code 0: no crash.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 2 ] || [ "$1" = "-h" ] || [ "$1" = "--help" ]; then
  sed -n '2,9p' "$0" | sed 's/^# \{0,1\}//'
  [ $# -ge 2 ] && exit 0 || exit 2
fi
name=$1 seconds=$2 build=${3:-build-asan}
case $name in scenario|map|mjcf|dataset|model) ;; *)
  echo "error: command line: NAME: unknown harness '$name' (scenario, map, mjcf, dataset, model)" >&2
  exit 2 ;;
esac
[[ $seconds =~ ^[0-9]+$ ]] || { echo "error: command line: SECONDS: not a whole number: $seconds" >&2; exit 2; }
tools/sanitize.sh --configure-only "$build"
cmake --build "$build" --target "${name}_fuzzer" -j "${AIA_JOBS:-$(nproc)}"
out=fuzz-out/$name
mkdir -p "$out/corpus" "$out/crashes"
cp -n fuzz/corpus/"$name"/* "$out/corpus/" 2>/dev/null || true
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1}:suppressions=$PWD/tools/sanitizers/asan.supp
export LSAN_OPTIONS=suppressions=$PWD/tools/sanitizers/lsan.supp
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1:suppressions=$PWD/tools/sanitizers/ubsan.supp
echo "[fuzz] $name for $seconds s; crashes go to $out/crashes/"
# Fork mode keeps fuzzing after a crash, so that SECONDS are spent in full;
# every crash is saved and counted.
# A dictionary where the harness has one (the scenario's serves mjcf too).
dict=fuzz/dict/$name.dict
[ "$name" = mjcf ] && dict=fuzz/dict/scenario.dict
dict_flag=()
[ -f "$dict" ] && dict_flag=(-dict="$dict")
"$build/fuzz/${name}_fuzzer" "${dict_flag[@]}" -max_total_time="$seconds" -rss_limit_mb=2048 \
  -timeout=30 -artifact_prefix="$out/crashes/" -print_final_stats=1 \
  -fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1 "$out/corpus"
found=$(find "$out/crashes" -type f | wc -l)
echo "[fuzz] $name: $found crash/oom/timeout inputs in $out/crashes/"
[ "$found" -eq 0 ]
