#!/usr/bin/env bash
# Tiles on a generated building (issue 14): one process out of core
# (pcl_dacpo_orient -memory) and 1..R MPI ranks with the same tiles
# (pcl_dacpo_orient_mpi -memory: every rank reads its own byte range, no rank
# holds the whole cloud). Per run: wall time, peak RSS (per rank), the error
# against the scene's ground truth, and whether the normals are byte-identical
# to the one-process tiled run.
#
#   bench/tiles_scaling.sh [POINTS=10000000] [MAX_RANKS=4] [MEMORY=1G] [BUILD=build] [WORK=/tmp/dacpo_tiles_bench]
#
# The one-process run uses 2 threads; each rank 1 thread (a rank per core; on a
# machine with fewer cores than ranks they share them).
set -euo pipefail
N=${1:-10000000} R=${2:-4} MEM=${3:-1G} BUILD=${4:-build} W=${5:-/tmp/dacpo_tiles_bench}
T=$BUILD/wrappers
mkdir -p "$W"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none
IN=$W/building_$N.ply
[ -s "$IN" ] || "$T/dacpo_make_scene" "$IN" -scene building -n "$N" -seed 1 > /dev/null
wrong() { "$T/pcl_dacpo_eval" "$IN" "$1" -json | sed -n 's/.*"wrong_pct": *\([0-9.]*\).*/\1/p'; }
echo "| run | ranks | wall s | tiles | per rank: read+plan / route / tiles / join / write s, busy s, held points, peak RSS MB | wrong % | identical to one process |"
echo "|---|---:|---:|---:|---|---:|---|"
t0=$(date +%s.%N)
/usr/bin/time -f "%M" -o "$W/one.rss" "$T/pcl_dacpo_orient" "$IN" "$W/one.ply" -memory "$MEM" \
  -seed 1 -threads 2 2> "$W/one.log"
t1=$(date +%s.%N)
line=$(grep '^tiles:' "$W/one.log")
tiles=$(sed -n 's/^tiles: points=[0-9]* tiles=\([0-9]*\).*/\1/p' <<< "$line")
printf "| one process, -memory %s | 1 | %.1f | %s | %s; peak RSS %.0f MB | %s | — |\n" "$MEM" \
  "$(echo "$t1 - $t0" | bc)" "$tiles" "$(sed 's/^tiles: //' <<< "$line")" \
  "$(echo "$(cat "$W/one.rss") / 1024" | bc -l)" "$(wrong "$W/one.ply")"
for np in $(seq 1 "$R"); do
  t0=$(date +%s.%N)
  mpirun -np "$np" --oversubscribe --bind-to none "$T/pcl_dacpo_orient_mpi" "$IN" \
    "$W/np$np.ply" -memory "$MEM" -seed 1 -threads 1 -q -report "$W/np$np.json"
  t1=$(date +%s.%N)
  same=$(cmp -s "$W/one.ply" "$W/np$np.ply" && echo yes || echo NO)
  ranks=$(/usr/bin/python3 - "$W/np$np.json" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
print("; ".join("%d: %.1f / %.1f / %.1f / %.1f / %.1f, busy %.1f, %.0f pts, %.0f MB" % (
    r["rank"], r["read_plan_s"], r["route_s"], r["tiles_s"], r["join_s"], r["write_s"],
    r["busy_s"], r["held_points"], r["peak_rss_mb"]) for r in rows))
print(int(rows[0]["num_tiles"]))
PY
)
  printf "| mpi -memory %s | %s | %.1f | %s | %s | %s | %s |\n" "$MEM" "$np" \
    "$(echo "$t1 - $t0" | bc)" "$(tail -1 <<< "$ranks")" "$(head -1 <<< "$ranks")" \
    "$(wrong "$W/np$np.ply")" "$same"
done
