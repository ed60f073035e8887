#!/usr/bin/env bash
# The demo: installs what is missing, builds, and runs a shared session on loopback DDS:
# a world server, two simulated haptic users, a headless spectator writing PNG frames, and the
# audio guide writing one WAV per message-board text. Output goes to ./out/demo (or $1).
set -euo pipefail
cd "$(dirname "$0")/.."
./deploy/install_deps.sh
./deploy/build.sh

out="$(realpath -m "${1:-out/demo}")"
rm -rf "$out"
mkdir -p "$out"
domain="${HANDSHARE_DOMAIN:-17}"
session="demo"
bin=build
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  fastdds shm clean >/dev/null 2>&1 || true
}
trap cleanup EXIT

echo "demo: session '$session' on DDS domain $domain; logs, frames and speech in $out"
"$bin/world_server/world_server" --domain "$domain" --session "$session" --scene start_menu \
  --duration 14 > "$out/world_server.log" 2>&1 & pids+=($!)
"$bin/audio_guide/audio_guide" --domain "$domain" --session "$session" --out "$out/speech" \
  --duration 12 > "$out/audio_guide.log" 2>&1 & pids+=($!)
for user in alice bob; do
  "$bin/haptic_node/haptic_node" --domain "$domain" --session "$session" --user "$user" \
    --device sim --script "haptic_node/scripts/demo_$user.hand" --duration 10 \
    --trace "$out/$user.csv" > "$out/$user.log" 2>&1 & pids+=($!)
done
sleep 2
"$bin/graphics_node/graphics_node" --domain "$domain" --session "$session" --headless \
  --frames 60 --fps 10 --out "$out/frames" > "$out/graphics_node.log" 2>&1 & pids+=($!)

status=0
for p in "${pids[@]}"; do wait "$p" || status=1; done
pids=()
cat "$out/world_server.log" "$out/alice.log" "$out/bob.log" "$out/graphics_node.log" "$out/audio_guide.log"
if [ "$status" -ne 0 ]; then
  echo "demo: a node failed (see the logs in $out)" >&2
  exit 1
fi
echo
echo "demo done: $(ls "$out/frames"/frame_*.png | wc -l) frames in $out/frames," \
     "speech in $out/speech ($(ls "$out/speech"/*.wav | wc -l) WAV)"
