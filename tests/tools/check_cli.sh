#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Checks for the CLI smoke tests (tests/tools/CMakeLists.txt). One case per call:
#
#   check_cli.sh eval EVAL gt.ply predicted.{pcd,ply} MAX_WRONG_PCT colored.pcd
#       pcl_dacpo_eval -json must succeed, print the JSON line with all fields,
#       wrong_pct must be below MAX_WRONG_PCT and the colored file must exist.
#   check_cli.sh fields FILE.pcd FIELD...
#       the PCD header must list every FIELD.
#   check_cli.sh must_fail PATTERN COMMAND...
#       COMMAND must exit with status 1 (a clean failure, not a crash) and its
#       stderr must contain PATTERN.
#   check_cli.sh orient_diagnostics ORIENT in.ply labels.pcd edges.csv blocks.pcd STATS
#       pcl_dacpo_orient -labels -edges -blocks_colored -q must succeed and print
#       exactly one stderr line, "stats: ... peak_rss_mb=<number>", kept in STATS.
#   check_cli.sh eval_blocks EVAL gt.ply labelled.pcd
#       the JSON of pcl_dacpo_eval must have the block keys with sane values:
#       intra_block_wrong_pct <= component_wrong_pct <= wrong_pct, and
#       flip_wrong_blocks <= blocks.
#   check_cli.sh edges_csv edges.csv STATS
#       the CSV has the header and as many rows as "edges=" in STATS, each with 7
#       columns and a confidence in [0, 1].
#   check_cli.sh blocks_colored ORIENT blocks.pcd POINTS
#       the PCD has x y z rgb and POINTS points, and pcl_dacpo_orient reads it.
#   check_cli.sh known_blocks EVAL DIR
#       known answer: 3 blocks of 100 points, one right, one flipped, one with 10
#       points flipped: wrong 36.67 %, in-block 3.33 %, 1 flip-wrong block.
#   check_cli.sh sign_colors ORIENT EVAL box.ply colored.pcd
#       orienting the open box towards a viewpoint inside it with -vp and
#       -normals_colored must give a PCD with x y z rgb and normals that face
#       into the box as returned (right_sign_pct > 99); the default sign
#       (no -vp) must do the same.
#   check_cli.sh bad_files DIR
#       writes files that are not what their name says: text, zeros and an ELF
#       binary named .pcd, a PLY renamed to .pcd, ASCII PCD and PLY with a word
#       among the numbers (PCL 1.13 crashes on the first kind and reads words
#       as NaN).
#   check_cli.sh full_disk ORIENT EVAL box.ply DIR
#       with the file size limited (ulimit -f 10 / 100, SIGXFSZ ignored: writes fail
#       as on a full disk), pcl_dacpo_orient writing over its own input (.ply),
#       over an existing .pcd, and with -edges / -mesh side outputs, and
#       pcl_dacpo_eval -colored must exit 1 with "cannot write", leave every
#       existing file byte for byte as it was and leave no temporary file.
#   check_cli.sh same_normals MAKE ORIENT EVAL DIR
#       a generated room, and the same room moved by (4.5e5, 5.4e6, 120) in a
#       double-precision PLY (a georeferenced scan), oriented with the same
#       seed, must get the same normals (pcl_dacpo_eval of one against the
#       other: <= 0.5 % differ, as the rounding of the move allows) and the output must keep the
#       double coordinates; a sphere scaled by 1e22 and by 1e-23 must come out
#       < 1 % wrong with outward normals.
#   check_cli.sh batch ORIENT EVAL box.ply DIR
#       -input_dir/-output_dir over a folder with two good files (.ply, .pcd) and
#       one that is not a PCD: exit 1 naming the bad one, both good ones oriented
#       (< 3 % wrong) under their own names; then the good ones alone: exit 0.
#   check_cli.sh truncate SRC DST BYTES
#       writes the first BYTES bytes of SRC to DST (a truncated input).
#   check_cli.sh empty DST
#       writes a 0-byte file.
set -u

fail() {
  echo "FAIL: $*" >&2
  exit 1
}

# Numeric value of the first "key": in a JSON line.
json_number() {
  echo "$1" | grep -o "\"$2\":[0-9.eE+-]*" | head -1 | cut -d: -f2
}

# Succeeds if the awk expression over a and b holds.
holds() {
  awk -v a="$1" -v b="$2" "BEGIN { exit !($3) }"
}

# ASCII PLY of 300 points on the plane z = 0 (a 30 x 10 grid, spacing 0.01):
# ground truth normal +z; predicted normals per block of 100 points: block 0
# right, block 1 flipped, block 2 with its first 10 points flipped.
write_known_blocks() {
  local dir=$1
  for kind in gt pred; do
    {
      echo "ply"
      echo "format ascii 1.0"
      echo "element vertex 300"
      for p in x y z nx ny nz; do echo "property float $p"; done
      [ "$kind" = pred ] && echo "property int block" && echo "property int component"
      echo "end_header"
      awk -v kind="$kind" 'BEGIN {
        for (i = 0; i < 300; ++i) {
          b = int(i / 100); nz = 1;
          if (kind == "pred" && (b == 1 || (b == 2 && i % 100 < 10))) nz = -1;
          line = sprintf("%g %g 0 0 0 %d", (i % 30) * 0.01, int(i / 30) * 0.01, nz);
          if (kind == "pred") line = line " " b " 0";
          print line;
        }
      }'
    } >"$dir/known_$kind.ply" || fail "cannot write $dir/known_$kind.ply"
  done
}

case "${1:-}" in
eval)
  [ $# -eq 6 ] || fail "eval needs EVAL GT PRED MAX COLORED"
  evaltool=$2 gt=$3 pred=$4 max=$5 colored=$6
  rm -f "$colored"
  json=$("$evaltool" "$gt" "$pred" -json -colored "$colored") || fail "pcl_dacpo_eval exited with $?"
  echo "$json"
  for key in file points wrong_pct largest_component_points largest_component_wrong_pct components; do
    echo "$json" | grep -q "\"$key\":" || fail "key $key missing in: $json"
  done
  pct=$(echo "$json" | sed -n 's/.*"wrong_pct":\([0-9.eE+-]*\).*/\1/p')
  [ -n "$pct" ] || fail "cannot parse wrong_pct from: $json"
  awk -v p="$pct" -v m="$max" 'BEGIN { exit !(p < m) }' || fail "wrong_pct $pct is not below $max"
  [ -s "$colored" ] || fail "colored output $colored was not written"
  head -c 400 "$colored" | grep -a -q '^FIELDS.*rgb' || fail "colored output has no rgb field"
  ;;
fields)
  [ $# -ge 3 ] || fail "fields needs FILE FIELD..."
  file=$2
  shift 2
  [ -s "$file" ] || fail "$file missing or empty"
  header=$(head -c 1000 "$file" | grep -a '^FIELDS') || fail "$file has no FIELDS line"
  for f in "$@"; do
    echo " $header " | grep -q " $f " || fail "field $f missing in '$header'"
  done
  echo "$header"
  ;;
must_fail)
  [ $# -ge 3 ] || fail "must_fail needs PATTERN COMMAND..."
  pattern=$2
  shift 2
  err=$("$@" 2>&1 >/dev/null)
  rc=$?
  echo "$err"
  [ $rc -eq 1 ] || fail "expected exit status 1, got $rc"
  echo "$err" | grep -q -- "$pattern" || fail "stderr does not mention '$pattern'"
  ;;
orient_diagnostics)
  [ $# -eq 7 ] || fail "orient_diagnostics needs ORIENT IN LABELS EDGES BLOCKS STATS"
  rm -f "$4" "$5" "$6" "$7"
  "$2" "$3" "$4" -labels -edges "$5" -blocks_colored "$6" -q 2>"$7" ||
    fail "pcl_dacpo_orient exited with $?: $(cat "$7")"
  cat "$7"
  [ "$(wc -l <"$7")" -eq 1 ] || fail "with -q stderr must be the stats line only"
  grep -q '^stats: points=[0-9]* blocks=[0-9]* edges=[0-9]* .*peak_rss_mb=[0-9][0-9.]*$' "$7" ||
    fail "no stats line with peak_rss_mb"
  ;;
eval_blocks)
  [ $# -eq 4 ] || fail "eval_blocks needs EVAL GT PRED"
  json=$("$2" "$3" "$4" -json) || fail "pcl_dacpo_eval exited with $?"
  echo "$json"
  for key in blocks component_wrong_pct intra_block_wrong_pct flip_wrong_blocks \
    flip_wrong_points_pct largest_block_wrong; do
    echo "$json" | grep -q "\"$key\":" || fail "key $key missing"
  done
  wrong=$(json_number "$json" wrong_pct)
  comp=$(json_number "$json" component_wrong_pct)
  intra=$(json_number "$json" intra_block_wrong_pct)
  fwb=$(json_number "$json" flip_wrong_blocks)
  fwp=$(json_number "$json" flip_wrong_points_pct)
  blocks=$(json_number "$json" blocks)
  holds "$intra" "$comp" 'a >= 0 && a <= b + 1e-9' || fail "intra_block_wrong_pct $intra > component_wrong_pct $comp"
  holds "$comp" "$wrong" 'a <= b + 1e-9' || fail "component_wrong_pct $comp > wrong_pct $wrong"
  holds "$fwb" "$blocks" 'a <= b && b >= 1' || fail "flip_wrong_blocks $fwb vs blocks $blocks"
  holds "$fwp" 100 'a >= 0 && a <= b' || fail "flip_wrong_points_pct $fwp out of range"
  [ "$(echo "$json" | grep -o '"wrong_pct":' | wc -l)" -eq $((1 + (blocks < 5 ? blocks : 5))) ] ||
    fail "largest_block_wrong should list min(5, blocks) blocks"
  ;;
edges_csv)
  [ $# -eq 3 ] || fail "edges_csv needs EDGES STATS"
  [ -s "$2" ] || fail "$2 missing or empty"
  head -1 "$2"
  [ "$(head -1 "$2")" = "block_a,block_b,alpha,alpha_bar,confidence,flipped_a,flipped_b" ] ||
    fail "bad CSV header"
  edges=$(sed -n 's/.* edges=\([0-9]*\) .*/\1/p' "$3")
  [ -n "$edges" ] || fail "no edges= in $(cat "$3")"
  rows=$(($(wc -l <"$2") - 1))
  [ "$rows" -eq "$edges" ] || fail "$rows CSV rows, stats say $edges edges"
  [ "$edges" -ge 1 ] || fail "expected block edges on the room scene"
  awk -F, 'NR > 1 && (NF != 7 || $5 < 0 || $5 > 1 || $1 >= $2 || ($6 != 0 && $6 != 1)) {
    print "bad row " NR ": " $0; bad = 1 } END { exit bad }' "$2" || fail "bad CSV rows"
  ;;
blocks_colored)
  [ $# -eq 4 ] || fail "blocks_colored needs ORIENT BLOCKS POINTS"
  header=$(head -c 400 "$3" | grep -a -E '^(FIELDS|POINTS)') || fail "$3 is not a PCD"
  echo "$header"
  echo "$header" | grep -q '^FIELDS x y z rgb' || fail "fields are not x y z rgb"
  echo "$header" | grep -q "^POINTS $4\$" || fail "expected $4 points"
  stats=$("$2" "$3" "$3.reoriented.pcd" -estimate -no_ipsr -q 2>&1) ||
    fail "pcl_dacpo_orient cannot read $3: $stats"
  echo "$stats" | grep -q "points=$4 " || fail "read back: $stats"
  rm -f "$3.reoriented.pcd"
  ;;
known_blocks)
  [ $# -eq 3 ] || fail "known_blocks needs EVAL DIR"
  write_known_blocks "$3"
  json=$("$2" "$3/known_gt.ply" "$3/known_pred.ply" -json) || fail "pcl_dacpo_eval exited with $?"
  echo "$json"
  for kv in '"wrong_pct":36.6667' '"component_wrong_pct":36.6667' \
    '"intra_block_wrong_pct":3.3333' '"blocks":3' '"flip_wrong_blocks":1' \
    '"flip_wrong_points_pct":33.3333' \
    '"largest_block_wrong":\[{"id":1, "component":0, "points":100, "wrong_pct":100.00}, {"id":2, "component":0, "points":100, "wrong_pct":10.00}, {"id":0, "component":0, "points":100, "wrong_pct":0.00}\]'; do
    echo "$json" | grep -q "$kv" || fail "expected $kv"
  done
  ;;
sign_colors)
  [ $# -eq 5 ] || fail "sign_colors needs ORIENT EVAL box.ply colored.pcd"
  for vp in "-vp 2,1.5,1.2" ""; do
    # shellcheck disable=SC2086
    "$2" "$4" "$(dirname "$5")/sign_out.pcd" -q -normals_colored "$5" $vp 2>/dev/null ||
      fail "pcl_dacpo_orient -normals_colored $vp exited with $?"
    head -c 400 "$5" | grep -q "^FIELDS x y z rgb normal_x normal_y normal_z" ||
      fail "$5 lacks x y z rgb normal_x normal_y normal_z"
    json=$("$3" "$4" "$5" -json) || fail "pcl_dacpo_eval exited with $?"
    right=$(json_number "$json" right_sign_pct)
    holds "$right" 99 "a > b" || fail "right_sign_pct $right <= 99 with '$vp'"
  done
  ;;
bad_files)
  [ $# -eq 2 ] || fail "bad_files needs DIR"
  d="$2"
  echo "hello world" >"$d/not_pcd_text.pcd" || fail "cannot write $d"
  head -c 1000 /dev/zero >"$d/not_pcd_zeros.pcd"
  head -c 4000 /bin/sh >"$d/not_pcd_binary.pcd"
  ply_header='ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n'
  printf "${ply_header}0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n" >"$d/renamed_ply.pcd"
  cp "$d/renamed_ply.pcd" "$d/renamed_ply.ply"
  printf "${ply_header}0 0 0 0 0 1\n1 five 0 0 0 1\n0 1 0 0 0 1\n" >"$d/word.ply"
  printf '# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n0 0 0\n1 five 0\n0 1 0\n' >"$d/word.pcd"
  # binary data whose first bytes spell COLUMNS: PCL 1.13 aborts (found by fuzzing)
  { printf '# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA binary\nCOLUMNS'
    head -c 29 /dev/zero; } >"$d/columns.pcd"
  ;;
full_disk)
  [ $# -eq 5 ] || fail "full_disk needs ORIENT EVAL box.ply DIR"
  d="$5/full_disk"
  rm -rf "$d" && mkdir -p "$d" || fail "cannot make $d"
  cp "$4" "$d/scan.ply" && cp "$4" "$d/keep.ply" || fail "cannot copy $4"
  "$2" "$d/scan.ply" "$d/old.pcd" -q -no_ipsr 2>/dev/null || fail "cannot make old.pcd"
  cp "$d/old.pcd" "$d/keep.pcd"
  printf 'old edges\n' >"$d/old.csv"
  printf 'old mesh\n' >"$d/old_mesh.ply"
  # limited KB COMMAND...: run with files limited to KB kilobytes
  limited() { bash -c 'trap "" XFSZ; ulimit -f "$0"; exec "$@"' "$@"; }
  expect_write_error() {
    err=$(limited "$@" 2>&1 >/dev/null)
    rc=$?
    [ $rc -eq 1 ] || fail "exit $rc, expected 1: $*"
    echo "$err" | grep -q "cannot write" || fail "no 'cannot write' message: $* -> $err"
  }
  expect_write_error 100 "$2" "$d/scan.ply" "$d/scan.ply" -no_ipsr
  cmp -s "$d/scan.ply" "$d/keep.ply" || fail "the input was changed by a failed write over it"
  expect_write_error 10 "$2" "$d/scan.ply" "$d/old.pcd" -no_ipsr
  cmp -s "$d/old.pcd" "$d/keep.pcd" || fail "old.pcd was changed by a failed write"
  limited 100 "$2" "$d/scan.ply" "$d/small.pcd" -no_ipsr -edges "$d/old.csv" >/dev/null 2>&1
  grep -qx "old edges" "$d/old.csv" || [ "$(head -1 "$d/old.csv")" = "block_a,block_b,alpha,alpha_bar,confidence,flipped_a,flipped_b" ] ||
    fail "old.csv is neither the old file nor a complete new one"
  expect_write_error 100 "$2" "$d/scan.ply" "$d/scan2.pcd" -mesh "$d/old_mesh.ply"
  grep -qx "old mesh" "$d/old_mesh.ply" || fail "old_mesh.ply was changed by a failed write"
  expect_write_error 10 "$3" "$d/scan.ply" "$d/keep.pcd" -colored "$d/old.pcd"
  cmp -s "$d/old.pcd" "$d/keep.pcd" || fail "old.pcd was changed by a failed -colored write"
  left=$(find "$d" -name '.*tmp*' | head -1)
  [ -z "$left" ] || fail "temporary file left behind: $left"
  ;;
same_normals)
  [ $# -eq 5 ] || fail "same_normals needs MAKE ORIENT EVAL DIR"
  d="$5/frames"
  mkdir -p "$d" || fail "cannot make $d"
  "$2" "$d/room.ply" -scene room -n 20000 -seed 2 >/dev/null || fail "make_scene failed"
  "$2" "$d/moved.ply" -scene room -n 20000 -seed 2 -offset 4.5e5,5.4e6,120 >/dev/null ||
    fail "make_scene -offset failed"
  "$3" "$d/room.ply" "$d/room_out.ply" -estimate -q -seed 3 2>/dev/null || fail "orient room failed"
  "$3" "$d/moved.ply" "$d/moved_out.ply" -estimate -q -seed 3 2>/dev/null ||
    fail "orient moved room failed"
  head -c 3000 "$d/moved_out.ply" | grep -aq "property double x" ||
    fail "the output lost the double coordinates"
  json=$("$4" "$d/room_out.ply" "$d/moved_out.ply" -json 2>/dev/null) || fail "eval failed"
  # the move itself is not exact in double (a float coordinate of 0.1 m plus
  # 5.4e6 m is rounded to 1e-9 m), and such perturbations change near-tie
  # decisions: 0.18 % of the normals with 4 restarts kept by energy, 0.59 %
  # (117 points in 79 clusters of at most 14, error vs ground truth 7.88 and
  # 7.85 %) with 16 restarts voted (measured, seeds 2/3); in float the moved
  # room fell apart into 11 components and came out 59 % different
  holds "$(json_number "$json" wrong_pct)" 1.0 "a <= b" || fail "moved room differs: $json"
  holds "$(json_number "$json" right_sign_pct)" 99.0 "a >= b" ||
    fail "moved room sign differs: $json"
  for s in 1e22 1e-23; do
    "$2" "$d/sphere.ply" -scene sphere -n 3000 -scale $s >/dev/null || fail "make_scene -scale failed"
    "$3" "$d/sphere.ply" "$d/sphere_out.ply" -estimate -q 2>/dev/null || fail "orient sphere x $s failed"
    json=$("$4" "$d/sphere.ply" "$d/sphere_out.ply" -json 2>/dev/null) || fail "eval failed"
    holds "$(json_number "$json" right_sign_pct)" 99 "a > b" || fail "sphere x $s: $json"
  done
  ;;
batch)
  [ $# -eq 5 ] || fail "batch needs ORIENT EVAL box.ply DIR"
  d="$5/batch"
  rm -rf "$d" && mkdir -p "$d/in" || fail "cannot make $d"
  cp "$4" "$d/in/a.ply" && "$2" "$4" "$d/in/b.pcd" -q 2>/dev/null || fail "cannot make inputs"
  echo "not a cloud" >"$d/in/c.pcd"
  err=$("$2" -input_dir "$d/in" -output_dir "$d/out" -q -no_ipsr 2>&1 >/dev/null)
  [ $? -eq 1 ] || fail "a failed file must give exit 1"
  echo "$err" | grep -q "c.pcd' failed" || fail "the bad file is not named: $err"
  for f in a.ply b.pcd; do
    [ -f "$d/out/$f" ] || fail "$f was not written"
    json=$("$3" "$4" "$d/out/$f" -json 2>/dev/null) || fail "eval of $f failed"
    holds "$(json_number "$json" wrong_pct)" 3 "a < b" || fail "$f: $json"
  done
  rm "$d/in/c.pcd"
  "$2" -input_dir "$d/in" -output_dir "$d/out2" -q -no_ipsr >/dev/null 2>&1 || fail "good batch failed"
  [ -f "$d/out2/a.ply" ] && [ -f "$d/out2/b.pcd" ] || fail "good batch lost a file"
  ;;
truncate)
  [ $# -eq 4 ] || fail "truncate needs SRC DST BYTES"
  head -c "$4" "$2" >"$3" || fail "cannot write $3"
  ;;
empty)
  [ $# -eq 2 ] || fail "empty needs DST"
  : >"$2" || fail "cannot write $2"
  ;;
*)
  fail "unknown case '${1:-}'"
  ;;
esac
exit 0
