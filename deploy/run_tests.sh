#!/usr/bin/env bash
# The tests: installs what is missing, builds, and runs every unit and cross-process test.
set -euo pipefail
cd "$(dirname "$0")/.."
./deploy/install_deps.sh
./deploy/build.sh
ctest --test-dir build --output-on-failure --timeout 600 -j "${HANDSHARE_JOBS:-2}"
