#!/usr/bin/env bash
# Speed and memory of the qm3d tool on the large benchmark pairs, printed as a Markdown table.
#
#   bench/run_benchmarks.sh [cmdm|pcqm|threads|all]      (default: all)
#
# `threads` runs a 164k-vertex CMDM pair and a 200k-point PCQM pair with --threads 1 and checks
# that they keep one core busy: CPU time (user + system) at most 1.1 x wall.
#
# Inputs are generated once (with ../shared/tools/*.py, which need python3-numpy) into
# $QM3D_BENCH_DIR (default /tmp/qm3d-bench). Each case runs the built tool end to end (reading
# included) under /usr/bin/time; "wall" and "peak RSS" are what it reports. The reference scores
# come from ../shared/data/reference/scale_reference.tsv.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
QM3D="${QM3D_BIN:-$ROOT/build/apps/qm3d}"
TOOLS="$ROOT/../shared/tools"
DATA="${QM3D_BENCH_DIR:-/tmp/qm3d-bench}"
WHICH="${1:-all}"
THREADS="${QM3D_BENCH_THREADS:-$(nproc)}"
PY=/usr/bin/python3

[ -x "$QM3D" ] || { echo "build qm3d first (scripts/setup.sh)" >&2; exit 1; }
[ -x /usr/bin/time ] || { echo "/usr/bin/time is needed (apt-get install time)" >&2; exit 1; }
mkdir -p "$DATA"

gen_mesh() { [ -f "$DATA/blob$1_ref.off" ] || $PY "$TOOLS/gen_blob_meshes.py" "$1" "$DATA" "blob$1" off >&2; }
gen_cloud() {
  local n=$1 tag=$2
  [ -f "$DATA/sphere_${tag}_ref_bin.ply" ] || $PY "$TOOLS/gen_big_cloud.py" "$n" "$DATA" >&2
}

ref_score() {  # metric reference distorted -> reference score from scale_reference.tsv
  awk -F'\t' -v m="$1" -v r="$2" -v d="$3" '$1==m && $2==r && $3==d {print $5}' \
    "$ROOT/../shared/data/reference/scale_reference.tsv"
}

run_case() {  # label target metric ref dist [args...]
  local label=$1 target=$2 metric=$3 ref=$4 dist=$5; shift 5
  local out
  out=$( { /usr/bin/time -f "TIME %e %M %U %S" "$QM3D" --threads "$THREADS" --quiet "$metric" \
           "$DATA/$ref" "$DATA/$dist" --csv "$@" ; } 2>&1 )
  local wall rss cpu score expected
  wall=$(echo "$out" | awk '/^TIME/ {print $2}')
  rss=$(echo "$out" | awk '/^TIME/ {printf "%.0f", $3/1024}')
  cpu=$(echo "$out" | awk '/^TIME/ {printf "%.2f", $4 + $5}')
  score=$(echo "$out" | awk -F, 'NR==2 {print $4}')
  expected=$(ref_score "$metric" "$ref" "$dist")
  local rel="n/a"
  if [ -n "$expected" ]; then
    rel=$($PY -c "print('%.1e' % (abs($score-$expected)/abs($expected)))")
  fi
  printf '| %s | %s s | %s s | %s MB | %s | %s | %s | %s |\n' "$label" "$wall" "$cpu" "$rss" \
    "$score" "${expected:-?}" "$rel" "$target"
  LAST_WALL=$wall LAST_CPU=$cpu
}

echo "qm3d $("$QM3D" --version | awk '{print $2}'), $THREADS threads, $(nproc) cores, $(uname -m)"
echo
echo "| case | wall | CPU | peak RSS | score | reference score | rel. diff | target |"
echo "|---|---|---|---|---|---|---|---|"
if [ "$WHICH" = all ] || [ "$WHICH" = cmdm ]; then
  gen_mesh 7; gen_mesh 8
  run_case "CMDM blob7 (164k vertices)" "<= 2 s" cmdm blob7_ref.off blob7_bothnoise.off
  run_case "CMDM blob8 (655k vertices)" "<= 14 s, <= 500 MB" cmdm blob8_ref.off blob8_bothnoise.off
fi
if [ "$WHICH" = all ] || [ "$WHICH" = pcqm ]; then
  gen_cloud 1000000 1000k; gen_cloud 2000000 2000k
  run_case "PCQM sphere 1M points" "<= 4 s, <= 400 MB" pcqm sphere_1000k_ref_bin.ply sphere_1000k_cnoise10_bin.ply
  run_case "PCQM sphere 2M points" "<= 10 s" pcqm sphere_2000k_ref_bin.ply sphere_2000k_cnoise10_bin.ply
fi
if [ "$WHICH" = all ] || [ "$WHICH" = threads ]; then
  gen_mesh 7; gen_cloud 200000 200k
  status=0
  for c in "cmdm|CMDM blob7 (164k vertices), --threads 1|blob7_ref.off|blob7_bothnoise.off" \
           "pcqm|PCQM sphere 200k points, --threads 1|sphere_200k_ref_bin.ply|sphere_200k_cnoise10_bin.ply"; do
    IFS='|' read -r metric label ref dist <<<"$c"
    THREADS=1 run_case "$label" "CPU <= 1.1 x wall" "$metric" "$ref" "$dist"
    if ! $PY -c "import sys; sys.exit(0 if $LAST_CPU <= 1.1 * $LAST_WALL else 1)"; then
      echo "FAIL: $label used $LAST_CPU s of CPU in $LAST_WALL s" >&2
      status=1
    fi
  done
  exit $status
fi
