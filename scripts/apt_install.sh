#!/usr/bin/env bash
# Shared by scripts/install_deps.sh and scripts/install_bench_deps.sh: installs
# the given Debian packages that are missing (apt-get update once, then
# install; as root or through sudo). Idempotent: does nothing when all are there.
#   apt_install.sh NAME [--no-install-recommends] PACKAGE...
set -euo pipefail
name="$1"
shift
opts=()
if [ "${1:-}" = "--no-install-recommends" ]; then
  opts+=(--no-install-recommends)
  shift
fi
missing=()
for p in "$@"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "$name: all packages present"
  exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "$name: installing ${missing[*]}"
$SUDO env DEBIAN_FRONTEND=noninteractive apt-get update -q
$SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -q "${opts[@]}" "${missing[@]}"
