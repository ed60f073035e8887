#!/usr/bin/env bash
# The demo: installs what is missing, builds, and runs a shared session on loopback DDS: the
# encyclopedia tour of a world server, two simulated haptic users, a headless spectator writing
# PNG frames, and the audio guide writing one WAV per message-board text; then prints the
# session report. Output goes to ./out/demo (or $1).
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

echo "demo: session '$session' on DDS domain $domain; logs, frames, speech and session log in $out"
# The deformable worlds' FEM models, computed once and cached (seconds when already cached).
"$bin/core/world/world_prepare" > "$out/world_prepare.log" 2>&1
# The encyclopedia tour with two users: start menu -> solar system (lift the ball on the Moon,
# the lever to Mars, lift it again) -> dinosaur (both press the triceratops' tail) ->
# microscopic -> back to the start menu. A spectator draws it; the guide speaks the board.
"$bin/world_server/world_server" --domain "$domain" --session "$session" --scene start_menu \
  --duration 54 --log "$out/session.db" > "$out/world_server.log" 2>&1 & pids+=($!)
"$bin/audio_guide/audio_guide" --domain "$domain" --session "$session" --out "$out/speech" \
  --duration 52 > "$out/audio_guide.log" 2>&1 & pids+=($!)
"$bin/graphics_node/graphics_node" --domain "$domain" --session "$session" --headless \
  --frames 96 --fps 2 --out "$out/frames" > "$out/graphics_node.log" 2>&1 & pids+=($!)
sleep 1
for user in alice bob; do
  "$bin/haptic_node/haptic_node" --domain "$domain" --session "$session" --user "$user" \
    --device sim --script "haptic_node/scripts/tour_$user.hand" --duration 50 \
    --trace "$out/$user.csv" > "$out/$user.log" 2>&1 & pids+=($!)
done

status=0
for p in "${pids[@]}"; do wait "$p" || status=1; done
pids=()
cat "$out/world_server.log" "$out/alice.log" "$out/bob.log" "$out/graphics_node.log" "$out/audio_guide.log"
echo
"$bin/world_server/session_report" "$out/session.db" || status=1
if [ "$status" -ne 0 ]; then
  echo "demo: a node failed (see the logs in $out)" >&2
  exit 1
fi
echo
echo "demo done: $(ls "$out/frames"/frame_*.png | wc -l) frames in $out/frames," \
     "speech in $out/speech ($(ls "$out/speech"/*.wav | wc -l) WAV)"
