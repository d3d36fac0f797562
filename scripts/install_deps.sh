#!/usr/bin/env bash
# Installs the Debian packages pcl_dacpo needs to build, test and run.
# Idempotent: does nothing when everything is already installed.
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config
  libpcl-dev          # PCL 1.13 (pulls FLANN, Eigen, Boost, VTK)
  liblpsolve55-dev    # lp_solve headers
  lp-solve            # lp_solve shared library (/usr/lib/lp_solve/liblpsolve55.so, LGPL)
  libgtest-dev        # gtest
  pcl-tools           # pcl_viewer for looking at results
  clang               # libFuzzer targets (scripts/fuzz.sh, part of the test command)
  pybind11-dev python3-dev python3-numpy python3-pytest   # the Python package and its tests
  python3-venv python3-pip python3-setuptools   # pip install . (pyproject.toml, its test)
  openmpi-bin libopenmpi-dev   # pcl_dacpo_orient_mpi and its test (mpirun -np 2, 3)
)

"$(dirname "${BASH_SOURCE[0]}")/apt_install.sh" install_deps "${PACKAGES[@]}"
