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
#   python3-matplotlib  the plots of bench/report.sh
set -euo pipefail

PACKAGES=(python3-open3d libcgal-dev xvfb xauth imagemagick time python3-matplotlib)

"$(dirname "${BASH_SOURCE[0]}")/apt_install.sh" install_bench_deps --no-install-recommends \
  "${PACKAGES[@]}"
