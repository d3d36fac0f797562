#!/usr/bin/env bash
# The rank table of pcl_dacpo_orient_mpi (issue 14): a generated building floor
# oriented by dacpo_orient() in one process (-whole) and by 1..R ranks; per run
# the wall time, each rank's phases, time in its own units and peak RSS, and
# whether the normals are byte-identical to the one-process run.
#
#   bench/mpi_scaling.sh [POINTS=10000000] [MAX_RANKS=4] [BUILD=build] [WORK=/tmp/dacpo_mpi_bench]
#
# Stages 0-1 on rank 0 use 2 threads (-threads 2), the units one core per rank.
# On a machine with fewer cores than ranks the ranks share them (oversubscribed).
set -euo pipefail
N=${1:-10000000} R=${2:-4} BUILD=${3:-build} W=${4:-/tmp/dacpo_mpi_bench}
T=$BUILD/wrappers
mkdir -p "$W"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none
IN=$W/building_$N.ply
[ -s "$IN" ] || "$T/dacpo_make_scene" "$IN" -scene building -n "$N" -seed 1 > /dev/null
run() { # label ranks args...
  local label=$1 np=$2; shift 2
  local t0 t1
  t0=$(date +%s.%N)
  mpirun -np "$np" --oversubscribe --bind-to none "$T/pcl_dacpo_orient_mpi" "$IN" \
    "$W/out_$label.ply" -estimate -seed 1 -threads 2 -q -report "$W/$label.json" "$@"
  t1=$(date +%s.%N)
  echo "$label $np $(echo "$t1 - $t0" | bc)" >> "$W/walls.txt"
}
: > "$W/walls.txt"
run whole 1 -whole
for np in $(seq 1 "$R"); do run "np$np" "$np"; done
echo "| run | ranks | wall s | rank: read+stages 0-1 / blocks / edges / solve+finish / write s, busy s, peak RSS MB | identical to one process |"
echo "|---|---:|---:|---|---|"
while read -r label np wall; do
  same=$(cmp -s "$W/out_whole.ply" "$W/out_$label.ply" && echo yes || echo NO)
  ranks=$(/usr/bin/python3 - "$W/$label.json" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
print("; ".join("%d: %.1f / %.1f / %.1f / %.1f / %.1f, busy %.1f, %.0f MB" % (
    r["rank"], r["read_stages01_s"], r["blocks_s"], r["edges_s"], r["solve_s"],
    r["write_s"], r["busy_s"], r["peak_rss_mb"]) for r in rows))
PY
)
  printf "| %s | %s | %.1f | %s | %s |\n" "$label" "$np" "$wall" "$ranks" "$same"
done < "$W/walls.txt"
