#!/usr/bin/env bash
# Configures and builds handshare into ./build (RelWithDebInfo) with 2 jobs, warnings as errors
# (the `ci` preset of CMakePresets.json). Extra configure arguments come from
# HANDSHARE_CMAKE_ARGS, e.g. "-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache",
# or "-DHANDSHARE_WARNINGS_AS_ERRORS=OFF" for a compiler newer than the project's gcc 12.
# HANDSHARE_TARGETS (space-separated CMake targets) builds only those, e.g. "handshare_programs":
# what a session runs and `cmake --install` installs, without the tests, fuzz targets and benches.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset ci ${HANDSHARE_CMAKE_ARGS:-}
targets=()
for t in ${HANDSHARE_TARGETS:-}; do targets+=(--target "$t"); done
cmake --build build -j "${HANDSHARE_JOBS:-2}" "${targets[@]}"
