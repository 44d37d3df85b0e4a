#!/usr/bin/env bash
# Installs the real meshes that oitsim knows by name (see `oitsim scenes`) beyond
# glmark2-data's bunny (an ordinary package, which scripts/setup.sh installs):
# libcgal-demo's data/meshes/*.off (elephant, armadillo, ChineseDragon, ...).
# That package would pull in all of CGAL's demo programs and Qt, so instead its
# .deb is downloaded (apt-get download), unpacked with dpkg -x, and only the
# meshes are kept, in /var/cache/oitsim/meshes/cgal.
# Idempotent: does nothing when the meshes are already there.
set -euo pipefail

# Fixed: traces/gen/Mesh.cpp namedMeshes() looks here.
mesh_dir=/var/cache/oitsim/meshes
cgal_dir="$mesh_dir/cgal"

if [ -r "$cgal_dir/refined_elephant.off" ] && [ -r "$cgal_dir/armadillo.off" ]; then
  echo "install-meshes: CGAL meshes present in $cgal_dir"
  exit 0
fi

command -v apt-get >/dev/null || { echo "install-meshes: needs apt-get (Debian/Ubuntu)" >&2; exit 1; }
mkdir -p "$mesh_dir"
work="$(mktemp -d "$mesh_dir/.download.XXXXXX")"
# apt downloads as the unprivileged _apt user when that user may write the directory.
if [ "$(id -u)" -eq 0 ] && id _apt >/dev/null 2>&1; then chown _apt "$work"; fi
trap 'rm -rf "$work"' EXIT

echo "install-meshes: downloading libcgal-demo (about 24 MB)"
# apt-get download needs the package lists; update only when it cannot find the package.
if ! (cd "$work" && apt-get download -qq libcgal-demo); then
  sudo=()
  [ "$(id -u)" -ne 0 ] && sudo=(sudo)
  "${sudo[@]}" apt-get update -qq
  (cd "$work" && apt-get download -qq libcgal-demo)
fi
deb="$(ls "$work"/libcgal-demo_*.deb)"
dpkg -x "$deb" "$work/root"
data_tar="$work/root/usr/share/doc/libcgal-demo/data.tar.gz"
[ -r "$data_tar" ] || { echo "install-meshes: $deb has no data.tar.gz (package layout changed?)" >&2; exit 1; }
tar -xzf "$data_tar" -C "$work" --wildcards '*data/meshes/*.off'
src="$(find "$work" -type d -path '*data/meshes' | head -n1)"
[ -n "$src" ] || { echo "install-meshes: data.tar.gz has no data/meshes" >&2; exit 1; }
# Move into place only when complete, so an interrupted run leaves nothing half-made.
rm -rf "$cgal_dir.new"
mkdir -p "$cgal_dir.new"
cp "$src"/*.off "$cgal_dir.new/"
rm -rf "$cgal_dir"
mv "$cgal_dir.new" "$cgal_dir"
echo "install-meshes: $(ls "$cgal_dir" | wc -l) meshes in $cgal_dir"
