#!/usr/bin/env bash
# Behaviour lock: every scenario in scenarios/ with every built-in policy must
# give byte-identical trace.csv and summary.json (wall time aside) to the
# recorded ones in tests/golden/ (the summaries verbatim, the traces by
# SHA-256, since they are large).
#
#   tools/golden.sh check [AIA]   compare (the test suite runs this)
#   tools/golden.sh write [AIA]   record anew, after a deliberate change
#
# AIA defaults to build/aia. Runs from the repository root, with relative
# scenario paths, so that summary.json's scenario_file is the same anywhere.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-check}
aia=${2:-build/aia}
golden=tests/golden
# NAME or NAME:KEY=VALUE (a policy parameter set, recorded as NAME-VALUE):
# igbnet with its default coordination (rules) and with none, the network
# alone.
policies=(random greedy expert decsb igbnet igbnet:policy.coordination=none)
[ "$mode" = check ] || [ "$mode" = write ] || {
  echo "usage: tools/golden.sh check|write [AIA]" >&2
  exit 2
}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The run's summary without its wall time.
normalize() { sed -E 's/("wall_s": )[-0-9.eE+]+/\10/' "$1"; }

failed=0
sums="$work/traces.sha256"
: >"$sums"
for scenario in scenarios/*.yaml; do
  name=$(basename "$scenario" .yaml)
  for entry in "${policies[@]}"; do
    policy=${entry%%:*}
    label=$policy
    sets=()
    if [ "$entry" != "$policy" ]; then
      sets=(--set "${entry#*:}")
      label="$policy-${entry##*=}"
    fi
    out="$work/$name.$label"
    "$aia" run "$scenario" --policy "$policy" "${sets[@]}" --out "$out" --quiet >/dev/null
    normalize "$out/summary.json" >"$work/$name.$label.summary.json"
    (cd "$out" && sha256sum trace.csv | sed "s|trace.csv|$name.$label.trace.csv|") >>"$sums"
    if [ "$mode" = check ]; then
      if ! cmp -s "$work/$name.$label.summary.json" "$golden/$name.$label.summary.json"; then
        echo "DIFFERS: $name with $label: summary.json" >&2
        diff "$golden/$name.$label.summary.json" "$work/$name.$label.summary.json" >&2 || true
        failed=1
      fi
    fi
  done
done
if [ "$mode" = write ]; then
  mkdir -p "$golden"
  cp "$work"/*.summary.json "$sums" "$golden/"
  echo "recorded $(wc -l <"$sums") runs in $golden/"
  exit 0
fi
if ! diff "$golden/traces.sha256" "$sums" >&2; then
  echo "DIFFERS: trace.csv of the runs above (< recorded, > now)" >&2
  failed=1
fi
[ "$failed" = 0 ] && echo "all $(wc -l <"$sums") runs match $golden/"
exit "$failed"
