#!/usr/bin/env bash
# The MPI tool gives the normals of dacpo_orient() in one process, byte for
# byte, for 1, 2 and 3 ranks (oversubscribed: more ranks than cores is fine),
# with stage 0's neighbour search on rank 0 or spread over the ranks, reads and
# writes PCD as well as PLY, and fails cleanly (a message and exit status 1 or 2 on every rank, no hang).
#
#   check_mpi.sh MAKE_SCENE ORIENT_MPI EVAL MPIEXEC WORKDIR
set -euo pipefail
MAKE=$1 TOOL=$2 EVAL=$3 MPIEXEC=$4 W=$5
mkdir -p "$W"
# root in a container: Open MPI refuses without these; no shared-memory
# single-copy (ptrace is often not allowed there)
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none
run() { # ranks, then the tool's arguments
  local np=$1; shift
  timeout 300 "$MPIEXEC" -np "$np" --oversubscribe --bind-to none "$TOOL" "$@"
}
fail() { echo "FAIL: $*"; exit 1; }

check_scene() { # name, make_scene args..., -- tool args...
  local name=$1; shift
  local make=() tool=()
  while [ "$1" != "--" ]; do make+=("$1"); shift; done; shift
  tool=("$@")
  "$MAKE" "$W/$name.ply" "${make[@]}" > /dev/null
  run 1 "$W/$name.ply" "$W/${name}_whole.ply" -whole -q "${tool[@]}"
  for np in 1 2 3; do
    run "$np" "$W/$name.ply" "$W/${name}_np$np.ply" -q -report "$W/${name}_np$np.json" \
        "${tool[@]}"
    cmp "$W/${name}_whole.ply" "$W/${name}_np$np.ply" ||
      fail "$name: $np ranks differ from dacpo_orient() in one process"
    [ "$(wc -l < "$W/${name}_np$np.json")" -eq "$np" ] ||
      fail "$name: the report of $np ranks has not one line per rank"
  done
  # every rank ran units: the work was spread
  grep -q '"rank": 2.*"blocks": [1-9]' "$W/${name}_np3.json" ||
    fail "$name: rank 2 of 3 ran no block"
  local wrong
  wrong=$("$EVAL" "$W/$name.ply" "$W/${name}_np3.ply" -json |
          sed -n 's/.*"wrong_pct": *\([0-9.]*\).*/\1/p')
  echo "$name: identical for 1-3 ranks, $wrong % wrong"
  awk -v w="$wrong" -v m="$MAX" 'BEGIN { exit !(w != "" && w <= m) }' ||
    fail "$name: $wrong % wrong (bound $MAX %)"
}

# a room with estimated normals, seed 3, 11 blocks over 3 ranks
MAX=10 check_scene room -scene room -n 20000 -seed 4 -- -estimate -seed 3 -blocks 11
# the method's options come from the parameter table (as pcl_dacpo_orient's):
# the same bytes for 1-3 ranks, and they do change the answer
MAX=10 check_scene room_opts -scene room -n 20000 -seed 4 -- -estimate -seed 3 -blocks 11 \
  -c 2 -restarts 4 -seam_dipole 0
! cmp -s "$W/room_whole.ply" "$W/room_opts_whole.ply" ||
  fail "room: -c 2 -restarts 4 -seam_dipole 0 gave the default's bytes"
# the spread neighbour search (-spread_knn): 2 and 3 ranks, a first halo far
# too thin, widened round by round (every rank's rows checked), and a cloud of
# six copies of every point (more duplicates than the gathered rows hold: rank
# 0 searches alone, with a note) all give the bytes of one process
args=(-q -estimate -seed 3 -blocks 11 -spread_knn)
for np in 2 3; do
  run "$np" "$W/room.ply" "$W/room_spread$np.ply" "${args[@]}"
  cmp "$W/room_whole.ply" "$W/room_spread$np.ply" ||
    fail "room: -spread_knn on $np ranks changes the normals"
done
run 3 "$W/room.ply" "$W/room_halo.ply" "${args[@]}" -knn_halo 0.0001 -report "$W/halo.json"
cmp "$W/room_whole.ply" "$W/room_halo.ply" || fail "room: a thin first halo changes the normals"
rounds=$(sed -n 's/.*"knn_rounds": \([0-9]*\).*/\1/p' "$W/halo.json" | head -1)
[ "${rounds:-0}" -ge 3 ] || fail "room: a thin first halo took ${rounds:-?} rounds, not >= 3"
hl=$(grep -a -b -m1 "^end_header" "$W/room.ply" | cut -d: -f1)
hl=$((hl + 11))
{ head -c "$hl" "$W/room.ply" | sed 's/^element vertex 20000$/element vertex 120000/'
  for copy in 1 2 3 4 5 6; do tail -c +"$((hl + 1))" "$W/room.ply"; done; } > "$W/dup.ply"
run 1 "$W/dup.ply" "$W/dup_whole.ply" "${args[@]}" -whole
out=$(run 2 "$W/dup.ply" "$W/dup_np2.ply" "${args[@]}" 2>&1)
cmp "$W/dup_whole.ply" "$W/dup_np2.ply" || fail "duplicates: 2 ranks differ from one process"
grep -q "rank 0 searches alone" <<< "$out" || fail "duplicates: no note of the fallback: $out"
echo "room: -spread_knn on 2 and 3 ranks, a halo widened over $rounds rounds and a 6-fold duplicated cloud: same bytes"
# PCD out and in: PCL (the evaluator) reads the PCD written by 2 ranks to the
# same score, and that PCD as input (normals re-estimated) gives the same bytes
run 2 "$W/room.ply" "$W/room_np2.pcd" -q -estimate -seed 3 -blocks 11
[ "$("$EVAL" "$W/room.ply" "$W/room_np2.pcd" -json | sed 's/"file":[^,]*,//')" = \
  "$("$EVAL" "$W/room.ply" "$W/room_np2.ply" -json | sed 's/"file":[^,]*,//')" ] ||
  fail "room: the PCD output scores differently from the PLY output"
run 3 "$W/room_np2.pcd" "$W/room_from_pcd.ply" -q -estimate -seed 3 -blocks 11
cmp "$W/room_np2.ply" "$W/room_from_pcd.ply" ||
  fail "room: PCD input gives other normals than PLY input"
echo "room: PCD output read by PCL to the same score, PCD input gives the same bytes"
# two rooms (two components) with the file's normals as axes
MAX=5 check_scene two_rooms -scene two_rooms -n 12000 -seed 2 -- -seed 5

# bad input: a message and a non-zero status on every rank, no hang
set +e
out=$(run 2 "$W/missing.ply" "$W/x.ply" 2>&1); st=$?
set -e
[ "$st" -ne 0 ] && grep -q "cannot open" <<< "$out" || fail "missing input: status $st: $out"
head -c 700 "$W/room.ply" > "$W/truncated.ply"
set +e
out=$(run 3 "$W/truncated.ply" "$W/x.ply" 2>&1); st=$?
set -e
[ "$st" -ne 0 ] && grep -q "truncated" <<< "$out" || fail "truncated input: status $st: $out"
set +e
out=$(run 2 "$W/room.ply" "$W/x.ply" -blocks many 2>&1); st=$?
set -e
[ "$st" -ne 0 ] && grep -q "\-blocks many (num_blocks: 'many' is not a value it takes)" <<< "$out" ||
  fail "bad option: status $st: $out"
set +e
out=$(run 2 "$W/room.ply" "$W/x.ply" -no_such_option 3 2>&1); st=$?
set -e
[ "$st" -ne 0 ] && grep -q "unknown option or missing number: -no_such_option" <<< "$out" ||
  fail "unknown option: status $st: $out"
[ ! -e "$W/x.ply" ] || fail "a failed run left an output file"
set +e
out=$(run 2 "$W/room.ply" "$W/no_such_dir/x.ply" -q 2>&1); st=$?
set -e
[ "$st" -ne 0 ] && grep -q "does not exist" <<< "$out" || fail "unwritable output: status $st: $out"
set +e
out=$(run 2 "$W/room.ply" "$W/x.ply" -q -report "$W/no_such_dir/r.json" 2>&1); st=$?
set -e
[ "$st" -ne 0 ] && grep -q "does not exist" <<< "$out" || fail "-report into a missing folder: status $st: $out"
set +e
out=$(run 2 "$W/room.ply" "$W/x.txt" -q 2>&1); st=$?
set -e
[ "$st" -ne 0 ] && grep -q ".ply or .pcd" <<< "$out" || fail "output o.txt: status $st: $out"
[ ! -e "$W/x.txt" ] || fail "a .txt output was written"
# an ASCII row with one value too many: refused, not every later point shifted
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 0 0 7\n0 1 0\n' > "$W/extra.ply"
set +e
out=$(run 2 "$W/extra.ply" "$W/x.ply" -q 2>&1); st=$?
set -e
[ "$st" -ne 0 ] && grep -q "more or fewer values" <<< "$out" || fail "ASCII row with an extra value: status $st: $out"
# help: every option named, status 0
out=$(run 2 -h)
for opt in -estimate -seed -blocks -k -normal_k -threads -whole -spread_knn -knn_halo \
    -report -q; do
  grep -q -- " $opt " <<< "$out" || fail "help does not name $opt"
done
echo "mpi: all checks passed"
