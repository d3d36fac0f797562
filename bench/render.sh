#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Headless picture for the README: a generated room oriented by pcl_dacpo next
# to the same room oriented by a peer, correct normals blue, wrong ones red
# (pcl_dacpo_eval -colored), each rendered by pcl_viewer under Xvfb and put
# side by side with ImageMagick.
#
#   bench/render.sh [-b BUILD] [-w WORK] [-o OUT.png] [-n POINTS] [-seed S]
#                   [-peer cgal|pcl_viewpoint|open3d] [-sign] [-- extra pcl_dacpo_orient args]
#
# -sign: colour by normal direction instead, RGB = (n + 1) / 2 (pcl_dacpo_eval
# -normals_colored), titled with the share right as returned (no flip forgiven):
# what a user sees of the global sign (a room turned inside out shows a dark
# floor).
#
# Needs pcl_viewer (pcl-tools), xvfb-run (xvfb, xauth) and ImageMagick
# (scripts/install_deps.sh + scripts/install_bench_deps.sh). Peers are built
# from bench/peers like bench/run_benchmark.sh does.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$root/build"
work=""
out="$root/bench/results/room_dacpo_vs_peer.png"
points=100000
seed=1
peer=cgal
sign=0
while [ $# -gt 0 ]; do
  case "$1" in
    -b) build="$(cd "$2" && pwd)"; shift 2 ;;
    -w) work="$2"; shift 2 ;;
    -o) out="$2"; shift 2 ;;
    -n) points="$2"; shift 2 ;;
    -seed) seed="$2"; shift 2 ;;
    -peer) peer="$2"; shift 2 ;;
    -sign) sign=1; shift ;;
    -h|--help) sed -n '2,15p' "$0"; exit 0 ;;
    --) shift; break ;;
    *) echo "render: unknown option $1" >&2; exit 2 ;;
  esac
done
extra=("$@")
work="${work:-$build/bench}"
tools="$build/wrappers"
for t in pcl_viewer xvfb-run convert; do
  command -v "$t" >/dev/null 2>&1 || { echo "render: $t not found (scripts/install_bench_deps.sh)" >&2; exit 1; }
done
for t in dacpo_make_scene pcl_dacpo_orient pcl_dacpo_eval; do
  [ -x "$tools/$t" ] || { echo "render: $tools/$t not built (cmake --build $build)" >&2; exit 1; }
done
dir="$work/render"
mkdir -p "$dir" "$(dirname "$out")"

# --- the peer's orientation
peer_out="$dir/peer_$peer.ply"
case "$peer" in
  cgal|pcl_viewpoint)
    bin="$work/peers-build/$([ "$peer" = cgal ] && echo cgal_orient || echo pcl_viewpoint)"
    if [ ! -x "$bin" ]; then
      cmake -S "$root/bench/peers" -B "$work/peers-build" -DCMAKE_BUILD_TYPE=Release >/dev/null
      cmake --build "$work/peers-build" -j 2 >/dev/null
    fi
    [ -x "$bin" ] || { echo "render: peer $peer could not be built (libcgal-dev / libpcl-dev?)" >&2; exit 1; }
    peer_cmd=("$bin")
    peer_title=$([ "$peer" = cgal ] && echo "CGAL mst_orient_normals" || echo "PCL flip to centroid")
    ;;
  open3d)
    peer_cmd=(/usr/bin/python3 "$root/bench/peers/open3d_orient.py")
    peer_title="Open3D tangent-plane MST"
    ;;
  *) echo "render: unknown peer $peer" >&2; exit 2 ;;
esac

room="$dir/room_${points}_s$seed.ply"
[ -f "$room" ] || "$tools/dacpo_make_scene" "$room" -scene room -n "$points" -seed "$seed" >/dev/null
"$tools/pcl_dacpo_orient" "$room" "$dir/dacpo.pcd" -estimate -q "${extra[@]}" 2>/dev/null
"${peer_cmd[@]}" "$room" "$peer_out" 2>/dev/null
pct() { # gt pred colored.pcd -> wrong % (-sign: % right as returned, normal colours)
  if [ "$sign" = 1 ]; then
    "$tools/pcl_dacpo_eval" "$1" "$2" -normals_colored "$3" -json |
      sed -n 's/.*"right_sign_pct":\([0-9.]*\).*/\1/p' | tail -1 | awk '{printf "%.2f", $1}'
  else
    "$tools/pcl_dacpo_eval" "$1" "$2" -colored "$3" -json |
      sed -n 's/.*"wrong_pct":\([0-9.]*\).*/\1/p' | tail -1 | awk '{printf "%.2f", $1}'
  fi
}
w_dacpo=$(pct "$room" "$dir/dacpo.pcd" "$dir/dacpo_colored.pcd")
w_peer=$(pct "$room" "$peer_out" "$dir/peer_colored.pcd")

# --- headless screenshots: one Xvfb session, pcl_viewer per cloud, grab the root window
# Camera: pcl_viewer -cam "near,far/focal/position/view up/fovy/window size/window pos",
# looking down into the open 6 x 5 m room over its front wall.
W=900; H=700
cam="0.1,60/3,2.9,0.5/3,-2.4,11.5/0,0,1/0.8575/$W,$H/0,0"
cat > "$dir/shoot.sh" <<EOF
set -u
shoot() { # cloud png
  pcl_viewer "\$1" -bc 1,1,1 -ps 2 -cam "$cam" > "\$2.log" 2>&1 &
  pid=\$!
  # pcl_viewer's stdout is block-buffered into the log: wait for the window, then a fixed settle time
  for i in \$(seq 1 60); do grep -q "Loading" "\$2.log" 2>/dev/null && break; sleep 0.5; done
  sleep 5
  import -window root -crop ${W}x${H}+0+0 "\$2"
  kill \$pid 2>/dev/null; wait \$pid 2>/dev/null
  return 0
}
rm -f "$dir/dacpo.png" "$dir/peer.png"
shoot "$dir/dacpo_colored.pcd" "$dir/dacpo.png"
shoot "$dir/peer_colored.pcd" "$dir/peer.png"
exit 0
EOF
xvfb-run -a -s "-screen 0 ${W}x${H}x24" bash "$dir/shoot.sh"
for f in "$dir/dacpo.png" "$dir/peer.png"; do
  [ -s "$f" ] || { echo "render: screenshot $f failed (see $f.log)" >&2; exit 1; }
done

label() { # png text: trim the white margin, title on top
  convert "$1" -fuzz 4% -trim +repage -bordercolor white -border 30 -gravity north -background white \
    -splice 0x40 -font DejaVu-Sans -pointsize 24 -fill black -annotate +0+14 "$2" "$1"
}
if [ "$sign" = 1 ]; then
  what="right"
  legend="signs as returned, colour = normal direction, RGB = (n + 1) / 2: up is blue, down olive"
else
  what="wrong"
  legend="blue = correct, red = wrong"
fi
label "$dir/dacpo.png" "pcl_dacpo: ${w_dacpo}% $what"
label "$dir/peer.png" "$peer_title: ${w_peer}% $what"
convert "$dir/dacpo.png" "$dir/peer.png" -background white -gravity center +append \
  \( -size $((2 * W))x36 xc:white -gravity center -font DejaVu-Sans -pointsize 18 -fill '#333333' \
     -annotate +0+0 "generated room, $points points (seed $seed), PCA normals (k=16) oriented; $legend" \) \
  -append "$out"
echo "render: wrote $out (pcl_dacpo ${w_dacpo}% $what, $peer_title ${w_peer}% $what)"
