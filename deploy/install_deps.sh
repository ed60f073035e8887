#!/usr/bin/env bash
# Installs every Debian 12 package handshare needs to build, run and test.
# Idempotent: packages already present are skipped without touching the network.
set -euo pipefail

PACKAGES=(
  # toolchain
  build-essential cmake ninja-build pkg-config git lld
  # middleware: Fast DDS 2.9 and its IDL generator
  libfastrtps-dev libfastcdr-dev fastddsgen fastdds-tools
  # numerics: Eigen, CHOLMOD (SuiteSparse), an optimized BLAS
  libeigen3-dev libsuitesparse-dev libopenblas-dev
  # geometry: collision and mesh import
  libfcl-dev libassimp-dev
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev
  # presentation: software OpenGL (offscreen), a window where a display exists, PNG, speech
  libosmesa6-dev libgl-dev libglfw3-dev libsdl2-dev libpng-dev espeak-ng libespeak-ng-dev
  # presentation: the board's caption in a real font, Latin and Japanese (FreeType, IPA Gothic)
  libfreetype-dev fonts-ipafont-gothic
  # presentation: audio playback (ALSA) and a virtual X display for window tests
  libasound2-dev xvfb
  # a person at the desk, tested as one: real X input events to the window (tests/desk_test.py)
  xdotool
  # session log, config parsing
  libsqlite3-dev sqlite3 nlohmann-json3-dev
  # asset preparation and independent FEM oracle (called as external programs)
  tetgen calculix-ccx
  # network tests (tests/net): namespaces, nft loss/partition, the NFQUEUE delayer; iptables
  # (iptables-nft) reaches the xt NFQUEUE target where the kernel lacks nft's queue expression
  iproute2 nftables iptables libnetfilter-queue-dev
  # DDS-Security keystores (deploy/security/make_keystore.sh); the security tests set a
  # station's clock back with faketime (tests/security_test.py)
  openssl faketime
  # the web console (web_console): HTTP, WebSocket and TLS through Boost.Beast and OpenSSL;
  # three.js for the browser's view, served from the install; its browser tests run Debian's
  # chromium headless through selenium and chromium-driver (tests/web_console_test.py)
  libboost-dev libssl-dev libjs-three chromium chromium-driver python3-selenium
  # plots for bench/ and WAV checks
  python3 python3-matplotlib python3-numpy python3-pil sox
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

echo "install_deps: installing ${#missing[@]} packages: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
