#!/usr/bin/env bash
# The main job: build (installing packages if needed), run the default
# scenario with the default policy, then film it. Results land in
# renders/default/: summary.json, trace.csv, trace.png, default.mp4.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/bootstrap.sh
build/aia run scenarios/default.yaml --out renders/default "$@"
build/aia render scenarios/default.yaml --out renders/default/default.mp4 --heatmap 0 "$@"
/usr/bin/python3 tools/plot_trace.py renders/default/trace.csv --out renders/default/trace.png
