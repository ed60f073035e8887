#!/usr/bin/env bash
# Configures and builds handshare into ./build (RelWithDebInfo) with 2 jobs.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo ${HANDSHARE_CMAKE_ARGS:-}
cmake --build build -j "${HANDSHARE_JOBS:-2}"
