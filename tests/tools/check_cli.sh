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
#   check_cli.sh truncate SRC DST BYTES
#       writes the first BYTES bytes of SRC to DST (a truncated input).
#   check_cli.sh empty DST
#       writes a 0-byte file.
set -u

fail() {
  echo "FAIL: $*" >&2
  exit 1
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
