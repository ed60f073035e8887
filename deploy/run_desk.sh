#!/usr/bin/env bash
# A person at this desk joins a session with the mouse and keyboard: installs what is missing,
# builds only the programs it runs (world_server, haptic_node, graphics_node, world_prepare),
# and runs deploy/handshare-desk USER [SESSION] from the build tree (see that script: without
# SESSION it starts a world server of its own). Needs a display.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 1 ] || [ $# -gt 2 ]; then
  echo "usage: ./deploy/run_desk.sh USER [SESSION]" >&2
  exit 2
fi
./deploy/install_deps.sh
HANDSHARE_TARGETS="${HANDSHARE_TARGETS:-world_server haptic_node graphics_node world_prepare}" ./deploy/build.sh
exec ./deploy/handshare-desk "$@"
