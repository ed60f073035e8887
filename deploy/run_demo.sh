#!/usr/bin/env bash
# The demo: installs what is missing, builds the programs (not the tests), installs the build into build/install, and runs a
# shared session on loopback DDS from there (bin/handshare-demo, deploy/handshare-demo here): the
# encyclopedia tour of a world server, two haptic users (a simulated hand, and a HIRO II on its
# simulated plant), a headless spectator writing PNG frames, and the audio guide writing one
# WAV per message-board text; then prints the session report. Output goes to ./out/demo (or $1).
set -euo pipefail
cd "$(dirname "$0")/.."
./deploy/install_deps.sh
# Only the programs the session runs (the test command builds everything).
HANDSHARE_TARGETS="${HANDSHARE_TARGETS:-handshare_programs}" ./deploy/build.sh

out="$(realpath -m "${1:-out/demo}")"
prefix="$(realpath -m build/install)"
cmake --install build --prefix "$prefix" > build/install.log
exec "$prefix/bin/handshare-demo" "$out"
