#!/usr/bin/env bash
# The main job: build (installing packages if needed), then run the default
# scenario with the default policy. Results land in renders/default/.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/bootstrap.sh
build/aia run scenarios/default.yaml --out renders/default "$@"
