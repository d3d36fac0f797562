#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The README's results from today's code, headless: error per suite against the
# peers, time and memory against points, the plots and the pictures
# (bench/report.py says what and how). Installs the bench's Debian packages
# first (peers, xvfb, ImageMagick, matplotlib).
#   bench/report.sh [--suite NAME=DIR ...] [--seeds 1,2,3,4,5] [--sizes N,N,...]
#                   [--no-render] [--no-readme] [-b BUILD] [-w WORK] [-o RESULTS]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/install_deps.sh"
"$root/scripts/install_bench_deps.sh"
exec /usr/bin/python3 "$root/bench/report.py" "$@"
