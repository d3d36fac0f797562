#!/bin/sh
# SPDX-License-Identifier: BSD-3-Clause
# Eight generated rooms no parameter was tuned on (the `room` scene of
# dacpo_make_scene, scene seeds 11-14, 100K points at sigma 4 mm and 60K at
# sigma 8 mm), each oriented with run seeds 1-5 by bench/robustness.py:
# median, worst seed, spread and the in-block / flip / component split.
#
# ROOMS=fused instead: the same four scenes (100K points, sigma 2 mm) fused
# from 3 views 8 mm and 0.2 degrees apart (dacpo_make_scene -fused), so every
# surface comes as offset copies (misregistered multi-view fusion).
#
# ROOMS=cameras instead: scenes 5-8 seen by 3, 5 and 8 depth cameras
# (dacpo_make_scene -views: each camera keeps what it sees, density falling
# with range) with 5 mm / 0.1 degrees and 20 mm / 0.5 degrees of pose error
# per view, 100K points, no range noise: 24 scans like a few registered RGB-D
# frames concatenated, where close copies and thin solids seen from both
# sides meet (docs/DESIGN.md, known limits). Add `--peer
# <peers-build>/cgal_orient` to score CGAL's MST on the same files.
#
# usage: [ROOMS=noisy|fused|cameras] bench/generated_rooms.sh [BUILD] [WORK] [-- robustness.py options]
#   BUILD  build folder with wrappers/ (default: build)
#   WORK   where the rooms and runs go (default: BUILD/generated_rooms,
#          BUILD/fused_rooms or BUILD/camera_rooms)
set -eu
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-$ROOT/build}
ROOMS=${ROOMS:-noisy}
case "$ROOMS" in
  noisy) WORK=${2:-$BUILD/generated_rooms} ;;
  fused) WORK=${2:-$BUILD/fused_rooms} ;;
  cameras) WORK=${2:-$BUILD/camera_rooms} ;;
  *) echo "ROOMS must be noisy, fused or cameras, got $ROOMS" >&2; exit 2 ;;
esac
[ $# -ge 1 ] && shift
[ $# -ge 1 ] && [ "$1" != "--" ] && shift
[ $# -ge 1 ] && [ "$1" = "--" ] && shift
mkdir -p "$WORK/rooms"
if [ "$ROOMS" = cameras ]; then
  for s in 5 6 7 8; do
    for v in 3 5 8; do
      for err in 0.005,0.1 0.02,0.5; do
        f="$WORK/rooms/cams_s${s}_v${v}_$(echo "$err" | tr , _).ply"
        [ -f "$f" ] ||
          "$BUILD/wrappers/dacpo_make_scene" "$f" -scene room -n 100000 \
            -views "$v,$err" -seed $s > /dev/null
      done
    done
  done
  exec python3 "$ROOT/bench/robustness.py" -b "$BUILD" -w "$WORK" "$@" "$WORK/rooms"
fi
for s in 11 12 13 14; do
  if [ "$ROOMS" = fused ]; then
    [ -f "$WORK/rooms/fused_s${s}_v3.ply" ] ||
      "$BUILD/wrappers/dacpo_make_scene" "$WORK/rooms/fused_s${s}_v3.ply" -scene room \
        -n 100000 -noise 0.002 -fused 3,0.008,0.2 -seed $s > /dev/null
    continue
  fi
  [ -f "$WORK/rooms/room_s${s}_n4.ply" ] ||
    "$BUILD/wrappers/dacpo_make_scene" "$WORK/rooms/room_s${s}_n4.ply" -scene room \
      -n 100000 -noise 0.004 -seed $s > /dev/null
  [ -f "$WORK/rooms/room_s${s}_n8.ply" ] ||
    "$BUILD/wrappers/dacpo_make_scene" "$WORK/rooms/room_s${s}_n8.ply" -scene room \
      -n 60000 -noise 0.008 -seed $s > /dev/null
done
exec python3 "$ROOT/bench/robustness.py" -b "$BUILD" -w "$WORK" "$@" "$WORK/rooms"
