#!/usr/bin/env bash
# Tiles (pcl_dacpo_orient -tiles / -memory, pcl_dacpo_orient_mpi -tiles): a
# generated building cut into tiles is oriented out of core to a bounded error;
# with MPI, 1, 2 and 3 ranks write the same bytes as one process while no rank
# holds every point; a cloud that fits gives the in-core answer; bad input and
# bad combinations fail with a message and leave no file.
#
#   check_tiles.sh MAKE_SCENE ORIENT EVAL [ORIENT_MPI MPIEXEC] WORKDIR
set -euo pipefail
MAKE=$1 ORIENT=$2 EVAL=$3
if [ $# -ge 6 ]; then MPI_TOOL=$4 MPIEXEC=$5 W=$6; else MPI_TOOL="" MPIEXEC="" W=$4; fi
mkdir -p "$W"
rm -f "$W"/.[!.]*  # stale files of an earlier run of this check
fail() { echo "FAIL: $*"; exit 1; }
wrong() { "$EVAL" "$1" "$2" -json | sed -n 's/.*"wrong_pct": *\([0-9.]*\).*/\1/p'; }

"$MAKE" "$W/b.ply" -scene building -n 40000 -seed 2 > /dev/null
out=$("$ORIENT" "$W/b.ply" "$W/tiled.ply" -tiles 12000 -seed 1 -threads 2 2>&1)
tiles=$(sed -n 's/.*tiles: points=40000 tiles=\([0-9]*\).*/\1/p' <<< "$out")
[ "${tiles:-0}" -ge 3 ] || fail "40K points in tiles of 12,000 made ${tiles:-?} tiles: $out"
largest=$(sed -n 's/.*largest_tile=\([0-9]*\).*/\1/p' <<< "$out")
[ "${largest:-99999}" -le 12000 ] || fail "the largest tile holds $largest points (> 12,000)"
w=$(wrong "$W/b.ply" "$W/tiled.ply")
echo "building 40K in $tiles tiles (largest $largest points): $w % wrong"
# measured 2026-12-03: 4.68 % (in one piece: see the closing note)
awk -v w="$w" 'BEGIN { exit !(w != "" && w <= 8) }' || fail "tiled: $w % wrong (bound 8 %)"
ls -a "$W" | grep -q '^\.dacpo' && fail "temporary tile files were left behind"

# a georeferenced room (double x y z, moved by (4e5, 5e6, 0)): tiles keep the
# coordinates bit for bit and orient it as the room at the origin (computing
# on floats of the coordinates, 39 % of its points came out right)
SAME_XYZ="$(dirname "$0")/same_xyz.py"
"$MAKE" "$W/r.ply" -scene room -n 20000 -seed 2 > /dev/null
"$MAKE" "$W/moved.ply" -scene room -n 20000 -seed 2 -offset 4e5,5e6,0 > /dev/null
same_as_at_origin() { # label, suffix: r_SUFFIX.ply and moved_SUFFIX.ply written
  python3 "$SAME_XYZ" "$W/moved.ply" "$W/moved_$2.ply" || fail "$1 changed double coordinates"
  python3 "$SAME_XYZ" "$W/r.ply" "$W/r_$2.ply" || fail "$1 changed float coordinates"
  local wr wm
  wr=$(wrong "$W/r.ply" "$W/r_$2.ply"); wm=$(wrong "$W/moved.ply" "$W/moved_$2.ply")
  awk -v a="$wr" -v b="$wm" 'BEGIN { d = a - b; exit !(d < 1 && d > -1) }' ||
    fail "$1: the moved room $wm % wrong, at the origin $wr %"
  echo "$1: coordinates kept bit for bit; moved room $wm % wrong, at the origin $wr %"
}
"$ORIENT" "$W/r.ply" "$W/r_t.ply" -tiles 2000 -seed 1 -q
"$ORIENT" "$W/moved.ply" "$W/moved_t.ply" -tiles 2000 -seed 1 -q
same_as_at_origin tiles t
ls -A "$W" | grep -q '^\.' && fail "temporary files left behind: $(ls -A "$W" | grep '^\.')"

# every point twice (a scan concatenated with itself): a halo from the spacing
# of distinct positions (it was 0: no tile related)
hl=$(grep -a -b -m1 "^end_header" "$W/r.ply" | cut -d: -f1); hl=$((hl + 11))
{ head -c "$hl" "$W/r.ply" | sed 's/^element vertex 20000$/element vertex 40000/'
  tail -c +"$((hl + 1))" "$W/r.ply"; tail -c +"$((hl + 1))" "$W/r.ply"; } > "$W/dup.ply"
out=$("$ORIENT" "$W/dup.ply" "$W/dup_t.ply" -tiles 5000 -seed 1 2>&1)
halo=$(sed -n 's/.* halo=\([0-9.e-]*\) .*/\1/p' <<< "$out")
largest=$(sed -n 's/.*largest_tile=\([0-9]*\).*/\1/p' <<< "$out")
awk -v h="$halo" 'BEGIN { exit !(h > 0) }' || fail "duplicates: halo ${halo:-?}: $out"
"$ORIENT" "$W/r.ply" "$W/r_t5.ply" -tiles 2500 -seed 1 -q  # the same cells
wt=$(wrong "$W/dup.ply" "$W/dup_t.ply"); wi=$(wrong "$W/r.ply" "$W/r_t5.ply")
# the doubled room in tiles as the room itself in tiles of half the points (measured 2026-12-04:
# 10.88 % both; the issue's report before the fix: 16.7 % against 5.0 % in core)
awk -v t="$wt" -v i="$wi" 'BEGIN { exit !(t <= i + 1) }' ||
  fail "duplicates: $wt % wrong in tiles, the room without copies $wi %"
echo "tiles: every point twice: halo $halo, largest tile $largest, $wt % wrong (without copies $wi %)"

# SIGTERM in the middle of a tiled run: no tile, halo or temporary output is
# left (SIGINT is the same handler; a background job of a script ignores it)
"$MAKE" "$W/big.ply" -scene room -n 100000 -seed 3 > /dev/null
mkdir -p "$W/sig"
"$ORIENT" "$W/big.ply" "$W/sig/o.ply" -tiles 10000 -q 2>/dev/null & pid=$!
for _ in $(seq 1 200); do ls -A "$W/sig" | grep -q 'tile' && break; sleep 0.05; done
ls -A "$W/sig" | grep -q 'tile' || fail "no tile file appeared in 10 s"
kill -TERM $pid; set +e; wait $pid; st=$?; set -e
[ $st -eq 143 ] || fail "SIGTERM: exit status $st, not 143"
[ -z "$(ls -A "$W/sig")" ] || fail "SIGTERM left: $(ls -A "$W/sig" | tr '\n' ' ')"
echo "tiles: SIGTERM during a tiled run leaves no file"

# a cloud within the budget runs in core: the answer of a run without -tiles
"$ORIENT" "$W/b.ply" "$W/fits.ply" -tiles 100000 -seed 1 -q
"$ORIENT" "$W/b.ply" "$W/incore.ply" -seed 1 -q
[ "$(wrong "$W/b.ply" "$W/fits.ply")" = "$(wrong "$W/b.ply" "$W/incore.ply")" ] ||
  fail "a cloud that fits the budget got another answer than in core"

# bad input and combinations: a message, a non-zero status, no output
set +e
hl=$(grep -a -b -m1 "^end_header" "$W/b.ply" | cut -d: -f1); hl=$((hl + 11))
{ head -c "$hl" "$W/b.ply"; printf '\x00\x00\xc0\x7f'; tail -c +"$((hl + 5))" "$W/b.ply"; } > "$W/nan.ply"
o=$("$ORIENT" "$W/nan.ply" "$W/x.ply" -tiles 12000 2>&1); st=$?
[ $st -ne 0 ] && grep -q "point 0 .* not finite" <<< "$o" || fail "NaN point: status $st: $o"
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n' > "$W/ascii.ply"
o=$("$ORIENT" "$W/ascii.ply" "$W/x.ply" -tiles 16 2>&1); st=$?
[ $st -ne 0 ] && grep -q "binary PLY" <<< "$o" || fail "ASCII PLY: status $st: $o"
o=$("$ORIENT" "$W/b.ply" "$W/x.pcd" -tiles 12000 2>&1); st=$?
[ $st -ne 0 ] && grep -q "write a .ply" <<< "$o" || fail ".pcd output with tiles: status $st: $o"
o=$("$ORIENT" "$W/b.ply" "$W/x.ply" -tiles 12000 -labels 2>&1); st=$?
[ $st -ne 0 ] && grep -q "without -labels" <<< "$o" || fail "-labels with tiles: status $st: $o"
o=$("$ORIENT" "$W/b.ply" "$W/x.ply" -memory 10M 2>&1); st=$?
[ $st -ne 0 ] && grep -q "needs at least" <<< "$o" || fail "-memory 10M: status $st: $o"
# an output name too long for a temporary sibling fails before any work, and
# an old file of that name is kept
long="$W/$(printf 'a%.0s' $(seq 1 250)).ply"
echo old > "$long"
o=$("$ORIENT" "$W/b.ply" "$long" -tiles 12000 2>&1); st=$?
[ $st -ne 0 ] && grep -q "name too long" <<< "$o" && [ "$(cat "$long")" = old ] ||
  fail "a name too long for a temp file: status $st: $o"
rm -f "$long"
set -e
[ ! -e "$W/x.ply" ] && [ ! -e "$W/x.pcd" ] || fail "a failed run left an output file"
echo "tiles: fits-in-core answer, NaN, ASCII, .pcd, -labels, too small a budget and too long a name checked"

[ -n "$MPI_TOOL" ] || exit 0
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none
run() { local np=$1; shift; timeout 300 "$MPIEXEC" -np "$np" --oversubscribe --bind-to none "$MPI_TOOL" "$@"; }
for np in 1 2 3; do
  run "$np" "$W/b.ply" "$W/mpi$np.ply" -tiles 12000 -seed 1 -q -report "$W/mpi$np.json"
  cmp "$W/tiled.ply" "$W/mpi$np.ply" || fail "$np ranks write other bytes than one process"
done
# double coordinates over MPI, tiles and in core: the input's bytes, the
# orientation of the room at the origin
run 2 "$W/moved.ply" "$W/moved_mt.ply" -tiles 2000 -seed 1 -q
cmp "$W/moved_t.ply" "$W/moved_mt.ply" || fail "mpi tiles of the moved room differ from one process"
run 2 "$W/moved.ply" "$W/moved_mi.ply" -seed 1 -q
run 2 "$W/r.ply" "$W/r_mi.ply" -seed 1 -q
same_as_at_origin "mpi in core" mi
# with 3 ranks no rank holds all 40,000 points; together they hold every one
held=$(sed -n 's/.*"held_points": \([0-9]*\).*/\1/p' "$W/mpi3.json")
[ "$(wc -l <<< "$held")" -eq 3 ] || fail "the 3-rank report has not 3 lines"
for h in $held; do [ "$h" -lt 40000 ] || fail "a rank held $h of 40,000 points"; done
[ "$(paste -sd+ <<< "$held" | bc)" -ge 40000 ] || fail "the ranks held fewer points than the cloud"
set +e
o=$(run 2 "$W/nan.ply" "$W/x.ply" -tiles 12000 2>&1); st=$?
[ $st -ne 0 ] && grep -q "not finite" <<< "$o" || fail "mpi NaN point: status $st: $o"
o=$(run 2 "$W/b.ply" "$W/x.pcd" -tiles 12000 2>&1); st=$?
[ $st -ne 0 ] && grep -q "write a .ply" <<< "$o" || fail "mpi .pcd output: status $st: $o"
set -e
[ ! -e "$W/x.ply" ] && [ ! -e "$W/x.pcd" ] || fail "a failed mpi run left an output file"
echo "tiles: 1, 2 and 3 ranks write the bytes of one process; held points per rank: $(echo $held)"

# a full disk: a 2 MB tmpfs with 1.7 MB of filler and an old output on it;
# every writer fails with a message, keeps the old output and leaves no
# temporary file (needs root for the mount; skipped with a note otherwise)
full_disk() { # label, command...
  local label=$1; shift
  mkdir -p "$W/full"
  mount -t tmpfs -o size=2m tmpfs "$W/full" 2>/dev/null || return 1
  head -c 1700000 /dev/zero > "$W/full/filler"; echo old > "$W/full/o.ply"
  set +e; o=$("$@" 2>&1); st=$?; set -e
  local left; left=$(ls -A "$W/full" | tr '\n' ' '); local kept; kept=$(cat "$W/full/o.ply")
  umount "$W/full"
  [ $st -ne 0 ] || fail "$label on a full disk: exit 0: $o"
  grep -q "disk full\|No space left" <<< "$o" || fail "$label on a full disk: no message: $o"
  [ "$kept" = old ] || fail "$label on a full disk: the old output was replaced"
  [ "$left" = "filler o.ply " ] || fail "$label on a full disk: left $left"
}
"$MAKE" "$W/r20.ply" -scene room -n 20000 -seed 4 > /dev/null
if full_disk "mpi -tiles" run 2 "$W/r20.ply" "$W/full/o.ply" -tiles 5000 -q; then
  full_disk "mpi in core" run 2 "$W/r20.ply" "$W/full/o.ply" -q
  full_disk "-tiles" "$ORIENT" "$W/r20.ply" "$W/full/o.ply" -tiles 5000 -q
  full_disk "in core" "$ORIENT" "$W/r20.ply" "$W/full/o.ply" -q
  echo "tiles: a full disk fails with a message and keeps the old output (mpi tiles and in core, tool tiles and in core)"
else
  echo "tiles: full-disk checks skipped (cannot mount a tmpfs here: not root?)"
fi
