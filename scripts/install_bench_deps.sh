#!/usr/bin/env bash
# Installs the Debian packages the benchmark suite (bench/) uses on top of
# scripts/install_deps.sh: the peer methods it compares against and the tools
# for the headless picture. The library and its test suite do not need these.
# Idempotent: does nothing when everything is already installed.
#   python3-open3d  Open3D's orient_normals_consistent_tangent_plane (peer)
#   libcgal-dev     CGAL's mst_orient_normals (peer, header-only)
#   xvfb            virtual X server for pcl_viewer screenshots (bench/render.sh)
#   imagemagick     montage of the two renders side by side
#   time            /usr/bin/time -v for wall time and peak RSS of every run
set -euo pipefail

PACKAGES=(python3-open3d libcgal-dev xvfb xauth imagemagick time)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_bench_deps: all packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install_bench_deps: installing ${missing[*]}"
$SUDO env DEBIAN_FRONTEND=noninteractive apt-get update -q
$SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
