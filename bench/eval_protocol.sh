#!/usr/bin/env bash
# The paper's evaluation protocol (§6) on this project's data: every real scan in
# $DACPO_REAL_DATA (a folder of PLYs with ground-truth normals, when set) and
# generated rooms in the paper's variants
# (clean, noise sigma 0.004 / 0.008, random downsampling to 100K / 10K).
# For each input: orient from PCA normals (signs unknown), then score with
# pcl_dacpo_eval. Prints one JSON line per run (eval result + wall seconds +
# peak RSS) and a Markdown summary at the end.
#
# usage: bench/eval_protocol.sh [-b BUILD_DIR] [-o OUT_DIR] [-n ROOM_POINTS] [-- extra orient args]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$root/build"
out="$root/build/eval"
room_points=200000
while [ $# -gt 0 ]; do
  case "$1" in
    -b) build="$2"; shift 2 ;;
    -o) out="$2"; shift 2 ;;
    -n) room_points="$2"; shift 2 ;;
    --) shift; break ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
extra=("$@")
tools="$build/wrappers"
mkdir -p "$out/in" "$out/res"
data="${DACPO_REAL_DATA:-}"

inputs=()
if [ -n "$data" ] && [ -d "$data" ]; then
  for f in "$data"/*.ply; do inputs+=("real:$f"); done
else
  echo "# DACPO_REAL_DATA not set or not a folder: real scans skipped" >&2
fi
gen() { # name args...
  local name="$1"; shift
  [ -f "$out/in/$name.ply" ] || "$tools/dacpo_make_scene" "$out/in/$name.ply" "$@" >/dev/null
  inputs+=("gen:$out/in/$name.ply")
}
gen room_clean -scene room -n "$room_points" -seed 1
gen room_noise004 -scene room -n "$room_points" -noise 0.004 -seed 1
gen room_noise008 -scene room -n "$room_points" -noise 0.008 -seed 1
gen room_100k -scene room -n "$room_points" -downsample 100000 -seed 1
gen room_10k -scene room -n "$room_points" -downsample 10000 -seed 1

results="$out/results.jsonl"
: > "$results"
for item in "${inputs[@]}"; do
  kind="${item%%:*}"; f="${item#*:}"; name="$(basename "$f" .ply)"
  pred="$out/res/$name.pcd"
  start=$(date +%s.%N)
  if "$tools/pcl_dacpo_orient" "$f" "$pred" -estimate -q "${extra[@]}" 2> "$out/res/$name.log"; then
    end=$(date +%s.%N)
    secs=$(awk -v a="$start" -v b="$end" 'BEGIN{printf "%.2f", b-a}')
    rss=$(grep -o 'peak_rss_mb=[0-9.]*' "$out/res/$name.log" | tail -1 | cut -d= -f2 || true)
    line=$("$tools/pcl_dacpo_eval" "$f" "$pred" -json)
    echo "${line%\}}, \"kind\": \"$kind\", \"seconds\": $secs, \"peak_rss_mb\": ${rss:-null}}" | tee -a "$results"
  else
    echo "{\"file\": \"$name\", \"kind\": \"$kind\", \"error\": \"orient failed, see $out/res/$name.log\"}" | tee -a "$results"
  fi
done

echo
echo "| file | points | % wrong (all) | % wrong (largest comp.) | components | seconds |"
echo "|---|---:|---:|---:|---:|---:|"
python3 - "$results" <<'PY' 2>/dev/null || awk '{print}' "$results"
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
for kind in ("real", "gen"):
    sel = [r for r in rows if r.get("kind") == kind and "wrong_pct" in r]
    for r in sel:
        print(f"| {r['file']} | {r['points']} | {r['wrong_pct']:.2f} | {r['largest_component_wrong_pct']:.2f} | {r['components']} | {r['seconds']:.2f} |")
    if sel:
        m = sum(r['wrong_pct'] for r in sel) / len(sel)
        ml = sum(r['largest_component_wrong_pct'] for r in sel) / len(sel)
        t = sum(r['seconds'] for r in sel) / len(sel)
        print(f"| **mean ({kind}, {len(sel)})** | | **{m:.2f}** | **{ml:.2f}** | | {t:.2f} |")
PY
