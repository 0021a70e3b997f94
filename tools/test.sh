#!/usr/bin/env bash
# The whole test suite: build (installing packages if needed), then ctest;
# with CI=true or AIA_SANITIZE=1 also the sanitizer tree (tools/sanitize.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
tools/bootstrap.sh
(cd "${AIA_BUILD_DIR:-build}" &&
  ctest --output-on-failure -j "${AIA_JOBS:-$(nproc)}" --timeout 600 "$@")
# In CI (or on request): the ASan + UBSan tree and the fuzz corpora
# (docs/hardening.md).
if [ "${CI:-}" = "true" ] || [ "${AIA_SANITIZE:-0}" = "1" ]; then
  tools/sanitize.sh
fi
