#!/usr/bin/env bash
# Installs the Debian 12 packages msdeform needs. Idempotent: when everything is present it only checks
# (well under a second) and touches nothing. Needs root (or sudo) only when something is missing.
# Extra package names given as arguments are installed too (scripts/fuzz.sh adds clang and its runtime).
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libopenmesh-dev libembree-dev libcgal-dev libosd-dev
  libsuitesparse-dev libopenblas-dev libtbb-dev
  catch2 libcli11-dev libstb-dev
  pybind11-dev python3-dev python3-numpy python3-pytest
  libcgal-demo
  libglfw3-dev libimgui-dev libgl1-mesa-dri xvfb xauth
  "$@"
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

echo "setup: installing ${missing[*]}"
as_root=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
  as_root=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive
"${as_root[@]}" apt-get update -qq
"${as_root[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "setup: done"
