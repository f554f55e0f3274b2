#!/usr/bin/env bash
# Installs what mcg needs from Debian 12's packages, if anything is missing. Run as root.
# python3-scipy is the LSODA peer of scripts/bench.d/sim_scipy.sh.
# --fuzz: also clang 14 and its libFuzzer runtime, for the MCG_FUZZ build (scripts/fuzz.sh).
set -euo pipefail
packages=(
  build-essential cmake pkg-config
  libcli11-dev libfmt-dev libeigen3-dev libserialport-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  sdcc sdcc-ucsim
  gnuplot-x11 mandoc groff-base socat parallel
  libncurses-dev tmux xvfb x11-apps netpbm
  python3-scipy
)
if [ "${1:-}" = --fuzz ]; then
  packages+=(clang-14 libclang-rt-14-dev)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "install-deps: installing ${missing[*]}" >&2
  sudo_cmd=()
  [ "$(id -u)" = 0 ] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
