#!/usr/bin/env bash
# Regenerates the tables of docs/scenarios.md from the declarations in the
# code (`aia schema --markdown`, `aia policies --markdown`). The test suite
# fails when the file and the declarations disagree.
#   tools/update_docs.sh [AIA]     (AIA defaults to build/aia)
set -euo pipefail
cd "$(dirname "$0")/.."
aia=${1:-build/aia}
doc=docs/scenarios.md
replace() {  # replace the lines between the markers of $1 with stdin
  local name=$1 body
  body=$(cat)
  # The body goes through the environment: awk -v would unescape it.
  BODY=$body awk -v name="$name" '
    $0 == "<!-- BEGIN " name " -->" { print; print ENVIRON["BODY"]; skip = 1; next }
    $0 == "<!-- END " name " -->" { skip = 0 }
    !skip { print }' "$doc" >"$doc.tmp"
  mv "$doc.tmp" "$doc"
}
"$aia" schema --markdown | replace "aia schema --markdown"
"$aia" policies --markdown | replace "aia policies --markdown"
echo "updated $doc"
