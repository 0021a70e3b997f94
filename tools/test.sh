#!/usr/bin/env bash
# The whole test suite: build (installing packages if needed), then ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/bootstrap.sh
cd "${AIA_BUILD_DIR:-build}"
ctest --output-on-failure -j "${AIA_JOBS:-$(nproc)}" --timeout 600 "$@"
