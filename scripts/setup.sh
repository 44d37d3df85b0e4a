#!/usr/bin/env bash
# Installs what oitsim needs from Debian's packages. Idempotent: installs only
# what is missing, and does nothing (not even apt-get update) when all is there.
set -euo pipefail

packages=(
  # build
  g++ cmake ninja-build pkg-config
  # libraries (the design card's three, then the well-kept helpers)
  libsystemc-dev libfmt-dev libgtest-dev
  libcli11-dev nlohmann-json3-dev libpng-dev zlib1g-dev
  # real meshes: the Stanford bunny
  glmark2-data
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

sudo=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo=(sudo)
fi
echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${sudo[@]}" apt-get update -qq
"${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "setup: done"
