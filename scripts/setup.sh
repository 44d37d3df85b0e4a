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
  # headless OpenGL for `oitsim capture` (loaded at run time, only by capture):
  # GLVND's libEGL and libOpenGL, Mesa's EGL (surfaceless) and llvmpipe; headers to build
  libegl-dev libgl-dev libegl1 libopengl0 libegl-mesa0 libgl1-mesa-dri
  # `oitsim capture --apitrace`: apitrace's tracer and glretrace, Xvfb for GLX without
  # a display, Xlib headers for the tests' own small GL application
  apitrace apitrace-tracers xvfb libx11-dev libglx-dev
  # `oitsim report` (plots, PFM conversion), YAML sweep specs, the report's browser test
  python3 python3-matplotlib python3-yaml chromium
  # the sanitizer and fuzzing builds (scripts/sanitize.sh, scripts/fuzz.sh): clang,
  # its ASan/UBSan/libFuzzer runtimes, llvm-symbolizer for readable reports
  clang-14 libclang-rt-14-dev llvm-14
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

# Optional, never fatal: Debian's slurm-wlm and munge for the one-node Slurm
# test (tests/apps/test_slurm.cpp), which skips when they are absent. A
# temporary policy-rc.d keeps the packages' postinst from starting munged,
# slurmctld or slurmd (the test runs its own private daemons).
optional_packages() {
  local opt=(slurm-wlm munge) want=() p
  for p in "${opt[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || want+=("$p")
  done
  [ ${#want[@]} -eq 0 ] && return 0
  local su=()
  if [ "$(id -u)" -ne 0 ]; then
    if ! command -v sudo >/dev/null; then
      echo "setup: slurm unavailable (need root or sudo to install ${want[*]}), its test will skip"
      return 0
    fi
    su=(sudo)
  fi
  local policy=/usr/sbin/policy-rc.d made_policy=0
  if [ ! -e "$policy" ] && printf '#!/bin/sh\nexit 101\n' | "${su[@]}" tee "$policy" >/dev/null &&
     "${su[@]}" chmod 755 "$policy"; then
    made_policy=1
  fi
  echo "setup: optional: installing ${want[*]}"
  local ok=1
  export DEBIAN_FRONTEND=noninteractive
  "${su[@]}" timeout 600 apt-get update -qq || ok=0
  if [ $ok -eq 1 ]; then
    "${su[@]}" timeout 600 apt-get install -y -qq --no-install-recommends "${want[@]}" || ok=0
  fi
  [ $made_policy -eq 1 ] && "${su[@]}" rm -f "$policy"
  if [ $ok -eq 1 ]; then
    echo "setup: optional: slurm installed"
  else
    echo "setup: slurm unavailable (apt-get could not install ${want[*]}), its test will skip"
  fi
  return 0
}

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  meshes
  optional_packages || true
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
optional_packages || true
echo "setup: done"
