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
  # headless OpenGL for `oitsim capture`: Mesa's EGL (surfaceless) and llvmpipe
  libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri
  # `oitsim report` (plots, PFM conversion), YAML sweep specs, the report's browser test
  python3 python3-matplotlib python3-yaml chromium
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

# More real meshes (libcgal-demo's elephant, armadillo, dragon, ...), unpacked
# from the .deb by their own idempotent script, after the packages are in place.
meshes() { "$(dirname "$0")/install-meshes.sh"; }

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  meshes
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
meshes
echo "setup: done"
