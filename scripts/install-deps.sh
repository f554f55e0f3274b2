#!/usr/bin/env bash
# Installs what mcg needs from Debian 12's packages, if anything is missing. Run as root.
set -euo pipefail
packages=(
  build-essential cmake pkg-config
  libcli11-dev libfmt-dev libeigen3-dev libserialport-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  sdcc sdcc-ucsim
  gnuplot-nox mandoc groff-base socat parallel
)
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
