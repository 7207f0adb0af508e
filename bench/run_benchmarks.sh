#!/usr/bin/env bash
# Speed and memory of the qm3d tool on the large benchmark pairs, printed as Markdown tables.
#
#   bench/run_benchmarks.sh [cmdm|pcqm|big|threads|batch|psnr|psnr_mesh|ibsm|graphsim|pointssim|geodesicpsim|krasula|icid|all|vs-reference]   (default: all)
#
#   cmdm     CMDM on the blob7 (164k vertices) and blob8 (655k) pairs
#   pcqm     PCQM on the 1M- and 2M-point sphere pairs
#   big      PCQM on a 4M-point sphere pair (memory)
#   threads  CMDM blob7 and PCQM 200k with --threads 1 and with 2 threads (runs alternating):
#            --threads 1 keeps one core busy (CPU <= 1.05 x wall) and is at least 0.55 x as fast
#            as 2 threads
#   batch    `batch --jobs 2` over 20 copies of the blob6 pair and 20 of the 200k-point pair: wall
#            <= 1.1 x (sum of the single pairs' --threads 1 CPU times) / 2
#   psnr     `psnr --threads 2` (MPEG pc_error's D1/D2/colour PSNR) on a 1M-point sphere pair (D1 +
#            colour: positions with Gaussian noise, colours with noise; no normals, so no D2) and on
#            the voxelised vox1 pair with the reference's normals (D1 + D2 + colour). When
#            QM3D_PC_ERROR names a pc_error 0.14.2 binary (built outside this repository), pc_error
#            runs in the same loop, interleaved with qm3d, with the CTC options and
#            --nbThreads=2; targets: qm3d's wall <= 1/3 of pc_error's, peak RSS <= 1.5 x
#            (reported, not enforced); qm3d's symmetric D1 PSNR must equal pc_error's
#            "mseF,PSNR (p2point)" (1e-8 relative, inf = inf).
#   psnr_mesh `psnr --threads 2` on two meshes (both sampled on mmetric's grid, G 1024, then
#            compared with mmetric's conventions): the monkey pair of mm_pcc_monkey_g1024 (1.9M
#            samples per mesh; every value checked against mm_pcc_reference.csv: the case the
#            test suite leaves out) and blob7's pair. When QM3D_MMETRIC names an mm 1.1.7 binary
#            (built outside this repository), mm samples both meshes on the same box and
#            compares them (it compares on one thread) in the same loop, interleaved; target:
#            qm3d's wall <= 1/4 of mm's, peak RSS <= mm's (reported, not enforced).
#   ibsm     `ibsm --threads 2` with its defaults (16 views of 2048², SSIM and MS-SSIM) on the
#            monkey pair, blob7's pair and the 1M-point sphere pair; when QM3D_MMETRIC is set,
#            mm's `compare --mode ibsm` runs on the two mesh pairs in the same loop, interleaved,
#            and qm3d's YUV PSNR must equal the one mm prints. mm 1.1.7 has no SSIM option and no
#            thread option for ibsm (it draws and compares one view at a time on one thread), so
#            it runs as it ships: qm3d does more work (SSIM and MS-SSIM of every view). Targets:
#            on meshes qm3d's wall <= 1/2 of mm's and its peak RSS <= 1.5 x mm's, the cloud pair
#            <= 10 s (reported, not enforced).
#   graphsim `graphsim` / `msgraphsim --threads 2` on the vox1 pair with the reference data's
#            keypoint file (vox1_ref / vox1_requant9, 56k points, 64 keypoints; the authors' code
#            under Octave: 2.2 s / 4.7 s CPU, ../shared/data/reference/graphsim), the keypoint draw
#            alone on vox1_ref (no keypoint file; theirs: 441 s of brute-force search) and both
#            metrics with their default keypoints on a 1.17M-point voxelised sphere
#            (bench/pointcloud/gen_voxel_sphere.py). Targets: CPU <= 1/20 of the reference's;
#            the 1M pair in seconds (reported, not enforced); every score the same on every run
#            and the vox1 scores equal to the table's (1e-10 relative).
#   pointssim PointSSIM on the gen_big_cloud.py sphere pairs (normals and curvature fitted on 12
#            neighbours): every value (7 estimators x 3 poolings x 4 attributes) on 5k points, where
#            the reference (mmspg/pointssim in Octave) takes ~36 s (target >= 100 x: <= 0.36 s),
#            and the default estimator on 100k and 1M points (linear in N; target: 1M in seconds);
#            the score must be the same in every run (reported, not enforced: the times)
#   geodesicpsim `geodesicpsim --threads 1` and `--threads 2` (keypoints 5000) on the basketball
#            frame against its qp8 / qp16 copies and on the non-square-texture blob pair of
#            ../shared/data/reference/geodesicpsim (inputs gunzipped into $QM3D_BENCH_DIR), beside
#            the reference's recorded numbers (geodesicpsim_reference.csv: its CPU time and peak
#            RSS with one thread); the score must equal the table's within 1e-9 relative. Targets:
#            the reference's CPU / qm3d's >= 5, qm3d's peak RSS <= 1/4 of the reference's
#            (reported, not enforced).
#   krasula  `eval --sd-column/--n-column` (Krasula's AUC_DS / AUC_BW / C0 with DeLong's
#            covariances) on 10,000 synthetic stimuli (49,995,000 J.149 pairs;
#            bench/evaluation/gen_krasula_stimuli.py) with one metric and with two (the second adds
#            the pass over the pairs for the covariance between metrics); the Krasula values must
#            be the same on every run. Targets: seconds, peak RSS well under 1 GB with one metric
#            (reported, not enforced).
#   icid     iCID of the 18 view pairs of blob4_geonoise at 256² (../shared/data/reference/icid/
#            views; the CMDM report's protocol) with the pairs in parallel on 2 threads, timed in
#            the process by bench/render/bench_icid (BM_Icid18ViewsInParallel/2, real time; the
#            LAB2000HL table loaded once; QM3D_BENCH_ICID names the program, default next to the
#            tool's build). When QM3D_ICID_REF names a command (made outside this repository) that
#            reads a file of image pairs, one `A;B` a line, scores them all in one process with the
#            reference iCID and prints one score a line, it runs in the same loop, interleaved,
#            timed as a whole process (its start-up included); its mean score must equal the mean
#            of `qm3d image A B --json` over the pairs (1e-10 relative). Target: the reference's
#            wall / qm3d's >= 50 (reported, not enforced). Not part of `all` without
#            QM3D_ICID_REF.
#   vs-reference
#            qm3d side by side with the reference implementations, built outside this repository
#            and named by QM3D_MEPP2_CMDM (MEPP-team/MEPP2's example_cmdm: CMDM blob7 and blob8)
#            and QM3D_PCQM_REF (MEPP-team/PCQM's PCQM: PCQM 1M); a case whose reference is not
#            named is left out, and one of the two must be. Each run of qm3d is followed by one of
#            its reference (interleaved). qm3d runs with --threads 2; MEPP2 as it ships (single
#            thread); PCQM with OMP_NUM_THREADS=2. The references run in a scratch directory
#            holding the LAB2000HL tables PCQM opens from its working directory ($QM3D_DATA_DIR,
#            else ../shared/data/lab2000hl) and taking the files they write there
#            (cmdm.output.obj, features_extracted.csv). Printed: both tools' wall, CPU and peak
#            RSS, the speed-up (reference wall / qm3d wall; targets >= 15 x, qm3d's peak RSS
#            <= 400 MB on blob8 and <= 250 MB on PCQM 1M: reported, not enforced) and the score
#            check: qm3d's score must round to what the reference prints ("Calculated CMDM = ",
#            "PCQM value is : ", 6 significant digits), and each tool's score must be the same on
#            every run. Not part of `all`.
#
# Each case runs QM3D_BENCH_RUNS times (default 5) and reports the median and the spread
# (min..max) of wall time, CPU time (user + system) and peak RSS, as /usr/bin/time measures them
# for the whole tool (reading included). The score must be the same on every run; where
# ../shared/data/reference/scale_reference.tsv has the pair, it is compared with that score.
# Environment: QM3D_BIN (the tool; default build/apps/qm3d), QM3D_BENCH_DIR (inputs, generated
# once with ../shared/tools/*.py, which need python3-numpy; default /tmp/qm3d-bench),
# QM3D_BENCH_THREADS (threads of the main cases; default all cores), QM3D_BENCH_RUNS,
# QM3D_PC_ERROR (psnr: the pc_error binary to compare with; unset = qm3d alone), QM3D_MMETRIC
# (psnr_mesh: the mm binary; unset = qm3d alone), QM3D_MEPP2_CMDM and QM3D_PCQM_REF (vs-reference),
# QM3D_ICID_REF and QM3D_BENCH_ICID (icid).
# The exit status is 1 when a score differs between runs or from its reference, a `threads` /
# `batch` check fails, psnr's D1 PSNR differs from pc_error's, or vs-reference's score check
# fails (speed and memory targets are reported, not enforced).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
QM3D="${QM3D_BIN:-$ROOT/build/apps/qm3d}"
TOOLS="$ROOT/../shared/tools"
DATA="${QM3D_BENCH_DIR:-/tmp/qm3d-bench}"
WHICH="${1:-all}"
THREADS="${QM3D_BENCH_THREADS:-$(nproc)}"
RUNS="${QM3D_BENCH_RUNS:-5}"
PY=/usr/bin/python3
STATUS=0

[ -x "$QM3D" ] || { echo "build qm3d first (scripts/setup.sh)" >&2; exit 1; }
[ -x /usr/bin/time ] || { echo "/usr/bin/time is needed (apt-get install time)" >&2; exit 1; }
[ "$RUNS" -ge 1 ] 2>/dev/null || { echo "QM3D_BENCH_RUNS must be a positive integer" >&2; exit 1; }
mkdir -p "$DATA"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

gen_mesh() { [ -f "$DATA/blob$1_ref.off" ] || $PY "$TOOLS/gen_blob_meshes.py" "$1" "$DATA" "blob$1" off >&2; }
gen_cloud() {
  local n=$1 tag=$2
  [ -f "$DATA/sphere_${tag}_ref_bin.ply" ] || $PY "$TOOLS/gen_big_cloud.py" "$n" "$DATA" >&2
}

ref_score() {  # metric reference distorted -> reference score from scale_reference.tsv
  awk -F'\t' -v m="$1" -v r="$2" -v d="$3" '$1==m && $2==r && $3==d {print $5}' \
    "$ROOT/../shared/data/reference/scale_reference.tsv"
}

# stats FILE COLUMN [scale] -> "median (min..max)" of a column of numbers
stats() {
  $PY - "$1" "$2" "${3:-1}" <<'EOF'
import statistics, sys
vals = [float(l.split()[int(sys.argv[2])]) / float(sys.argv[3]) for l in open(sys.argv[1]) if l.strip()]
fmt = (lambda v: '%.0f' % v) if float(sys.argv[3]) != 1 else (lambda v: '%.2f' % v)
med = statistics.median(vals)
print(fmt(med) if len(vals) == 1 else '%s (%s..%s)' % (fmt(med), fmt(min(vals)), fmt(max(vals))))
EOF
}
median() { $PY -c "import statistics,sys; print(statistics.median(float(l.split()[int(sys.argv[2])]) for l in open(sys.argv[1]) if l.strip()))" "$1" "$2"; }

# measure_once FILE cmd... : runs cmd once, appending "wall cpu rss_kb" to FILE (and the score
# to $SCORES when set); the command's stdout is left in $TMP/out
measure_once() {
  local file=$1; shift
  /usr/bin/time -f "%e %U %S %M" -o "$TMP/time" "$@" > "$TMP/out" 2> "$TMP/err" || {
    cat "$TMP/err" >&2; echo "FAIL: $*" >&2; STATUS=1; }
  awk '{printf "%s %.2f %s\n", $1, $2 + $3, $4}' "$TMP/time" >> "$file"
  [ "${SCORES:-}" = "" ] || awk -F, 'NR==2 {print $4}' "$TMP/out" >> "$SCORES"
}

# measure FILE cmd... : runs cmd RUNS times into a fresh FILE
measure() {
  local file=$1; shift
  : > "$file"
  for _ in $(seq "$RUNS"); do measure_once "$file" "$@"; done
}

# report_case label target metric ref dist threads times scores -> one table row from the runs
# in `times` (and their scores); LAST_WALL / LAST_CPU: medians
report_case() {
  local label=$1 target=$2 metric=$3 ref=$4 dist=$5 threads=$6 file=$7 scores=$8
  local distinct score expected rel="n/a"
  distinct=$(sort -u "$scores" | wc -l)
  score=$(head -1 "$scores")
  if [ "$distinct" != 1 ]; then
    echo "FAIL: $label: the score differs between runs: $(sort -u "$scores" | tr '\n' ' ')" >&2
    STATUS=1
  fi
  expected=$(ref_score "$metric" "$ref" "$dist")
  if [ -n "$expected" ]; then
    rel=$($PY -c "print('%.1e' % (abs($score-$expected)/abs($expected)))")
    if [ "$($PY -c "print(int(abs($score-$expected) > 1e-9*abs($expected)))")" = 1 ]; then
      echo "FAIL: $label: score $score, reference $expected" >&2; STATUS=1
    fi
  fi
  printf '| %s | %s | %s s | %s s | %s MB | %s | %s | %s | %s |\n' "$label" "$threads" \
    "$(stats "$file" 0)" "$(stats "$file" 1)" "$(stats "$file" 2 1024)" "$score" "${expected:-n/a}" \
    "$rel" "$target"
  LAST_WALL=$(median "$file" 0) LAST_CPU=$(median "$file" 1)
}

# run_case label target metric ref dist threads -> RUNS runs and their table row
run_case() {
  local label=$1 target=$2 metric=$3 ref=$4 dist=$5 threads=$6
  SCORES="$TMP/scores"; : > "$SCORES"
  measure "$TMP/case" "$QM3D" --threads "$threads" --quiet "$metric" "$DATA/$ref" "$DATA/$dist" --csv
  SCORES=""
  report_case "$label" "$target" "$metric" "$ref" "$dist" "$threads" "$TMP/case" "$TMP/scores"
}

check() {  # condition message: reports and records a failed check
  if $PY -c "import sys; sys.exit(0 if ($1) else 1)"; then echo "ok: $2"; else echo "FAIL: $2"; STATUS=1; fi
}

echo "qm3d $("$QM3D" --version | awk 'NR == 1 {print $2}')" \
  "(commit $("$QM3D" --version | sed -n '1s/.*(commit \([^)]*\)).*/\1/p')), $(date -u +%Y-%m-%d)," \
  "$THREADS threads, $(nproc) cores, $(uname -m)," \
  "$(awk -F: '/model name/ {print $2; exit}' /proc/cpuinfo | sed 's/^ *//')," \
  "load average $(cut -d' ' -f1 /proc/loadavg) at the start, $RUNS run(s) per case" \
  "(median (min..max))"
echo
header() {
  echo "| case | threads | wall | CPU | peak RSS | score | reference score | rel. diff | target |"
  echo "|---|---|---|---|---|---|---|---|---|"
}
if [ "$WHICH" = all ] || [ "$WHICH" = cmdm ] || [ "$WHICH" = pcqm ] || [ "$WHICH" = big ]; then
  header
fi
if [ "$WHICH" = all ] || [ "$WHICH" = cmdm ]; then
  gen_mesh 7; gen_mesh 8
  run_case "CMDM blob7 (164k vertices)" "<= 1.0 s" cmdm blob7_ref.off blob7_bothnoise.off "$THREADS"
  run_case "CMDM blob8 (655k vertices)" "<= 5.5 s, <= 300 MB" cmdm blob8_ref.off blob8_bothnoise.off "$THREADS"
fi
if [ "$WHICH" = all ] || [ "$WHICH" = pcqm ]; then
  gen_cloud 1000000 1000k; gen_cloud 2000000 2000k
  run_case "PCQM sphere 1M points" "<= 2.0 s, <= 250 MB" pcqm sphere_1000k_ref_bin.ply sphere_1000k_cnoise10_bin.ply "$THREADS"
  run_case "PCQM sphere 2M points" "<= 5 s" pcqm sphere_2000k_ref_bin.ply sphere_2000k_cnoise10_bin.ply "$THREADS"
fi
if [ "$WHICH" = all ] || [ "$WHICH" = big ]; then
  gen_cloud 4000000 4000k
  run_case "PCQM sphere 4M points" "<= 1.2 GB" pcqm sphere_4000k_ref_bin.ply sphere_4000k_cnoise10_bin.ply "$THREADS"
fi
if [ "$WHICH" = all ] || [ "$WHICH" = threads ]; then
  gen_mesh 7; gen_cloud 200000 200k
  echo
  header
  checks=()
  for c in "cmdm|CMDM blob7 (164k vertices)|blob7_ref.off|blob7_bothnoise.off" \
           "pcqm|PCQM sphere 200k points|sphere_200k_ref_bin.ply|sphere_200k_cnoise10_bin.ply"; do
    IFS='|' read -r metric label ref dist <<<"$c"
    # 1 and 2 threads alternate, so that a slow spell of the machine weighs on both alike.
    for f in t1 t2 s1 s2; do : > "$TMP/$f"; done
    for _ in $(seq "$RUNS"); do
      for t in 1 2; do
        SCORES="$TMP/s$t" measure_once "$TMP/t$t" "$QM3D" --threads "$t" --quiet "$metric" \
          "$DATA/$ref" "$DATA/$dist" --csv
      done
    done
    report_case "$label" "CPU <= 1.05 x wall" "$metric" "$ref" "$dist" 1 "$TMP/t1" "$TMP/s1"
    w1=$LAST_WALL c1=$LAST_CPU
    report_case "$label" ">= 0.55 x as fast with 1 thread" "$metric" "$ref" "$dist" 2 "$TMP/t2" "$TMP/s2"
    w2=$LAST_WALL
    checks+=("$c1 <= 1.05 * $w1|$label, --threads 1: CPU $c1 s in $w1 s (CPU/wall $($PY -c "print('%.2f' % ($c1/$w1))"), target <= 1.05)")
    checks+=("$w2 / $w1 >= 0.55|$label: 1 thread $w1 s, 2 threads $w2 s: 1 thread is $($PY -c "print('%.2f' % ($w2/$w1))") x as fast (target >= 0.55)")
  done
  echo
  for c in "${checks[@]}"; do check "${c%%|*}" "${c#*|}"; done
fi
if [ "$WHICH" = all ] || [ "$WHICH" = batch ]; then
  gen_mesh 6; gen_cloud 200000 200k
  # Single pairs with --threads 1: their CPU times bound what two jobs can do on two cores.
  SCORES=""
  measure "$TMP/one_mesh" "$QM3D" --threads 1 --quiet cmdm "$DATA/blob6_ref.off" "$DATA/blob6_bothnoise.off" --csv
  measure "$TMP/one_cloud" "$QM3D" --threads 1 --quiet pcqm "$DATA/sphere_200k_ref_bin.ply" "$DATA/sphere_200k_cnoise10_bin.ply" --csv
  cpu_mesh=$(median "$TMP/one_mesh" 1) cpu_cloud=$(median "$TMP/one_cloud" 1)
  list="$TMP/batch/list.csv"
  mkdir -p "$TMP/batch"
  echo "reference,distorted,metric" > "$list"
  for i in $(seq -w 1 20); do
    ln -s "$DATA/blob6_ref.off" "$TMP/batch/m${i}_ref.off"
    ln -s "$DATA/blob6_bothnoise.off" "$TMP/batch/m${i}_dist.off"
    ln -s "$DATA/sphere_200k_ref_bin.ply" "$TMP/batch/c${i}_ref.ply"
    ln -s "$DATA/sphere_200k_cnoise10_bin.ply" "$TMP/batch/c${i}_dist.ply"
    echo "m${i}_ref.off,m${i}_dist.off,cmdm" >> "$list"
    echo "c${i}_ref.ply,c${i}_dist.ply,pcqm" >> "$list"
  done
  measure "$TMP/batch_time" "$QM3D" --threads 2 --quiet batch "$list" -o "$TMP/batch/results.csv" --overwrite --jobs 2
  bound=$($PY -c "print('%.2f' % (1.1 * 20 * ($cpu_mesh + $cpu_cloud) / 2))")
  failed=$(awk -F, 'NR > 1 && $5 != "ok"' "$TMP/batch/results.csv" | wc -l)
  echo
  echo "| case | wall | CPU | peak RSS | single pairs' CPU (--threads 1) | target |"
  echo "|---|---|---|---|---|---|"
  printf '| batch --jobs 2: 20 x CMDM blob6 + 20 x PCQM 200k | %s s | %s s | %s MB | %s s + %s s per pair | wall <= %s s |\n' \
    "$(stats "$TMP/batch_time" 0)" "$(stats "$TMP/batch_time" 1)" "$(stats "$TMP/batch_time" 2 1024)" \
    "$cpu_mesh" "$cpu_cloud" "$bound"
  echo
  check "$failed == 0" "batch: $failed failed rows"
  check "$(median "$TMP/batch_time" 0) <= $bound" "batch wall $(median "$TMP/batch_time" 0) s <= 1.1 x 20 x ($cpu_mesh + $cpu_cloud) / 2 = $bound s"
fi
if [ "$WHICH" = all ] || [ "$WHICH" = psnr ]; then
  # Inputs: the 1M-point sphere of gen_big_cloud.py with its cnoise10 colours and Gaussian
  # position noise (sigma 0.002 = 0.001 x the bounding box, as gen_clouds.py's gnoise0.001), and
  # the shared vox1 pair whose reference carries add_pca_normals.py's normals.
  gen_cloud 1000000 1000k
  noisy="$DATA/sphere_1000k_gnoise0.001_cnoise10_bin.ply"
  [ -f "$noisy" ] || $PY - "$DATA/sphere_1000k_ref_bin.ply" "$DATA/sphere_1000k_cnoise10_bin.ply" "$noisy" <<'EOF'
import sys
import numpy as np
def read(path):
    data = open(path, 'rb').read()
    end = data.index(b'end_header\n') + len(b'end_header\n')
    dt = np.dtype([('x', '<f4'), ('y', '<f4'), ('z', '<f4'), ('red', 'u1'), ('green', 'u1'), ('blue', 'u1')])
    assert (len(data) - end) % dt.itemsize == 0 and b'property uchar blue\nend_header' in data[:end], path
    return data[:end], np.frombuffer(data[end:], dtype=dt).copy()
header, cloud = read(sys.argv[1])
_, coloured = read(sys.argv[2])
rng = np.random.default_rng(25)
for c in 'xyz':
    cloud[c] = (cloud[c].astype(np.float64) + rng.normal(scale=0.002, size=len(cloud))).astype(np.float32)
for c in ('red', 'green', 'blue'):
    cloud[c] = coloured[c]
open(sys.argv[3], 'wb').write(header + cloud.tobytes())
EOF
  PC_ERROR="${QM3D_PC_ERROR:-}"
  [ -z "$PC_ERROR" ] || [ -x "$PC_ERROR" ] || { echo "QM3D_PC_ERROR=$PC_ERROR is not executable" >&2; exit 1; }
  json_d1() {  # qm3d's --json on stdout -> its symmetric D1 PSNR (null = inf)
    $PY -c "import json,sys; v=json.load(open(sys.argv[1]))['features']['d1_psnr']; print('inf' if v is None else repr(v))" "$1" 2>/dev/null || echo error
  }
  pc_error_d1() {  # pc_error's stdout -> its "3. Final (symmetric)" D1 PSNR as printed
    awk '/mseF,PSNR \(p2point\):/ {v = $NF} END {print v == "" ? "error" : v}' "$1"
  }
  same_psnr() {  # a b -> exit 0 when equal within 1e-8 relative (pc_error prints 9 digits), inf = inf
    $PY -c "import sys,math; a,b=(float(x) for x in sys.argv[1:]); sys.exit(0 if a==b or (math.isfinite(a) and abs(a-b)<=1e-8*abs(b)) else 1)" "$1" "$2" 2>/dev/null
  }
  echo
  echo "| case | tool | threads | wall | CPU | peak RSS | D1 PSNR (symmetric, dB) | target |"
  echo "|---|---|---|---|---|---|---|---|"
  summary=() ratios=()
  REFDATA="$ROOT/../shared/data/reference"
  for c in "psnr sphere 1M points (D1 + colour)|1|$DATA/sphere_1000k_ref_bin.ply|$noisy" \
           "psnr vox1 56k points, normals (D1 + D2 + colour)|1023|$REFDATA/mpeg/vox1_ref_n.ply|$REFDATA/voxel/vox1_gnoise1.ply"; do
    IFS='|' read -r label peak ref dist <<<"$c"
    for f in tq tp dq dp; do : > "$TMP/$f"; done
    # qm3d and pc_error alternate, so that a slow spell of the machine weighs on both alike.
    for _ in $(seq "$RUNS"); do
      measure_once "$TMP/tq" "$QM3D" psnr "$ref" "$dist" --peak "$peak" --threads 2 --quiet --json
      json_d1 "$TMP/out" >> "$TMP/dq"
      if [ -n "$PC_ERROR" ]; then
        measure_once "$TMP/tp" "$PC_ERROR" -a "$ref" -b "$dist" -c 1 -d 1 --hausdorff=1 -r "$peak" \
          --dropdups=2 --neighborsProc=1 --nbThreads=2
        pc_error_d1 "$TMP/out" >> "$TMP/dp"
      fi
    done
    d1=$(head -1 "$TMP/dq")
    if [ "$(sort -u "$TMP/dq" | wc -l)" != 1 ] || [ "$d1" = error ]; then
      echo "FAIL: $label: qm3d's D1 PSNR differs between runs or is missing: $(sort -u "$TMP/dq" | tr '\n' ' ')" >&2
      STATUS=1
    fi
    target="wall <= 1/3 x pc_error's, peak RSS <= 1.5 x"
    [ -n "$PC_ERROR" ] || target="(QM3D_PC_ERROR unset: no pc_error to compare)"
    printf '| %s | qm3d | 2 | %s s | %s s | %s MB | %s | %s |\n' "$label" "$(stats "$TMP/tq" 0)" \
      "$(stats "$TMP/tq" 1)" "$(stats "$TMP/tq" 2 1024)" "$d1" "$target"
    [ -n "$PC_ERROR" ] || continue
    pd1=$(head -1 "$TMP/dp")
    printf '| %s | pc_error | 2 | %s s | %s s | %s MB | %s | |\n' "$label" "$(stats "$TMP/tp" 0)" \
      "$(stats "$TMP/tp" 1)" "$(stats "$TMP/tp" 2 1024)" "$pd1"
    wq=$(median "$TMP/tq" 0) wp=$(median "$TMP/tp" 0) mq=$(median "$TMP/tq" 2) mp=$(median "$TMP/tp" 2)
    cq=$(median "$TMP/tq" 1) cp=$(median "$TMP/tp" 1)
    ratio() { $PY -c "print('%.2f' % ($1 / max($2, 0.01)))"; }
    met() { $PY -c "import sys; print('met' if $1 else 'missed')"; }
    wall_ratio=$(ratio "$wq" "$wp") cpu_ratio=$(ratio "$cq" "$cp") rss_ratio=$(ratio "$mq" "$mp")
    ratios+=("| $label | $wq / $wp s = **$wall_ratio** ($(met "$wall_ratio <= 1/3")) | $cq / $cp s = $cpu_ratio | $(((${mq%.*} + 512) / 1024)) / $(((${mp%.*} + 512) / 1024)) MB = **$rss_ratio** ($(met "$rss_ratio <= 1.5")) |")
    if same_psnr "$d1" "$pd1" && [ "$(sort -u "$TMP/dp" | wc -l)" = 1 ]; then
      summary+=("ok: $label: D1 PSNR qm3d $d1 = pc_error $pd1")
    else
      summary+=("FAIL: $label: D1 PSNR qm3d $d1, pc_error $(sort -u "$TMP/dp" | tr '\n' ' ')")
      STATUS=1
    fi
  done
  if [ -n "$PC_ERROR" ]; then
    # The ratios of the medians (targets: wall <= 1/3, peak RSS <= 1.5 x; reported, not enforced).
    echo
    echo "| case | wall: qm3d / pc_error (target <= 1/3) | CPU: qm3d / pc_error | peak RSS: qm3d / pc_error (target <= 1.5) |"
    echo "|---|---|---|---|"
    for line in "${ratios[@]}"; do echo "$line"; done
  fi
  echo
  for line in "${summary[@]}"; do echo "$line"; done
fi

if [ "$WHICH" = all ] || [ "$WHICH" = psnr_mesh ]; then
  gen_mesh 7
  MM="${QM3D_MMETRIC:-}"
  [ -z "$MM" ] || [ -x "$MM" ] || { echo "QM3D_MMETRIC=$MM is not executable" >&2; exit 1; }
  REFDATA="$ROOT/../shared/data/reference"
  # ASCII PLY copies of blob7's OFF pair for mm, which reads no OFF (the same numbers).
  for m in blob7_ref blob7_bothnoise; do
    [ -f "$DATA/$m.ply" ] || $PY - "$DATA/$m.off" "$DATA/$m.ply" <<'EOF'
import sys
lines = [l.split() for l in open(sys.argv[1]) if l.strip() and not l.startswith('#')]
assert lines[0][0].endswith('OFF'), sys.argv[1]
nv, nf = int(lines[1][0]), int(lines[1][1])
v, f = lines[2:2 + nv], lines[2 + nv:2 + nv + nf]
with open(sys.argv[2], 'w') as out:
    out.write('ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n'
              'property uchar red\nproperty uchar green\nproperty uchar blue\nelement face %d\n'
              'property list uchar int vertex_indices\nend_header\n' % (nv, nf))
    for r in v:
        rgb = [float(c) for c in r[3:6]]
        scale = 255 if max(rgb) <= 1 else 1
        out.write('%s %s %s %d %d %d\n' % (r[0], r[1], r[2], *(round(c * scale) for c in rgb)))
    for r in f:
        out.write(' '.join(r[:int(r[0]) + 1]) + '\n')
EOF
  done
  box_of() {  # two meshes -> "minx miny minz|maxx maxy maxz" of qm3d's sampling box (9 digits)
    "$QM3D" psnr "$1" "$2" --grid-size 64 --no-color --no-hausdorff --json -q 2>/dev/null |
      $PY -c "import json,sys; b=json.load(sys.stdin)['sampling']['box']; print(' '.join('%.9g' % v for v in b['min']) + '|' + ' '.join('%.9g' % v for v in b['max']))"
  }
  mm_run() {  # ref dist box peak -> mm samples both on the box and compares them
    local lo=${3%|*} hi=${3#*|}
    "$MM" sample --mode grid --gridSize 1024 --useNormal --hideProgress --minPos "$lo" --maxPos "$hi" \
      --inputModel "$1" --outputModel "$TMP/a.ply" > /dev/null &&
    "$MM" sample --mode grid --gridSize 1024 --useNormal --hideProgress --minPos "$lo" --maxPos "$hi" \
      --inputModel "$2" --outputModel "$TMP/b.ply" > /dev/null &&
    "$MM" compare --mode pcc --inputModelA "$TMP/a.ply" --inputModelB "$TMP/b.ply" --hausdorff \
      --resolution "$4"
  }
  export -f mm_run; export MM TMP
  echo
  echo "| case | tool | threads | wall | CPU | peak RSS | D1 PSNR (symmetric, dB) | target |"
  echo "|---|---|---|---|---|---|---|---|"
  summary=()
  for c in "monkey2 / monkey_simplified, G 1024 (1.9M samples each)|137.829|$REFDATA/cmdm/monkey2.obj|$REFDATA/cmdm/monkey_simplified.obj" \
           "blob7 ref / bothnoise, G 1024|0|$DATA/blob7_ref.ply|$DATA/blob7_bothnoise.ply"; do
    IFS='|' read -r label peak ref dist <<<"$c"
    box=$(box_of "$ref" "$dist")
    peak_flag=(); [ "$peak" = 0 ] || peak_flag=(--peak "$peak")
    for f in tq tm dq dm; do : > "$TMP/$f"; done
    # qm3d and mm alternate, so that a slow spell of the machine weighs on both alike.
    for _ in $(seq "$RUNS"); do
      measure_once "$TMP/tq" "$QM3D" psnr "$ref" "$dist" --grid-size 1024 "${peak_flag[@]}" --threads 2 --quiet --json
      cp "$TMP/out" "$TMP/qm3d.json"
      $PY -c "import json,sys; v=json.load(open(sys.argv[1]))['features']['d1_psnr']; print('inf' if v is None else repr(v))" "$TMP/out" >> "$TMP/dq" 2>/dev/null || echo error >> "$TMP/dq"
      if [ -n "$MM" ]; then
        measure_once "$TMP/tm" bash -c 'mm_run "$@"' _ "$ref" "$dist" "$box" "$peak"
        awk '/mseF,PSNR \(p2point\):/ {v = $NF} END {print v == "" ? "error" : v}' "$TMP/out" >> "$TMP/dm"
      fi
    done
    d1=$(head -1 "$TMP/dq")
    if [ "$(sort -u "$TMP/dq" | wc -l)" != 1 ] || [ "$d1" = error ]; then
      echo "FAIL: $label: qm3d's D1 PSNR differs between runs or is missing" >&2
      STATUS=1
    fi
    target="wall <= 1/4 x mm's, peak RSS <= mm's"
    [ -n "$MM" ] || target="(QM3D_MMETRIC unset: no mm to compare)"
    printf '| %s | qm3d | 2 | %s s | %s s | %s MB | %s | %s |\n' "$label" "$(stats "$TMP/tq" 0)" \
      "$(stats "$TMP/tq" 1)" "$(stats "$TMP/tq" 2 1024)" "$d1" "$target"
    if [ "$peak" != 0 ]; then  # the table's G 1024 case, which the suite leaves out: every value
      if $PY - "$TMP/qm3d.json" "$REFDATA/mpeg/mm_pcc_reference.csv" <<'EOF'
import csv, json, math, sys
j = json.load(open(sys.argv[1]))
row = [r for r in csv.DictReader(open(sys.argv[2]), delimiter=';') if r['case'] == 'mm_pcc_monkey_g1024'][0]
bad = []
for prefix, feats in (('AB_', j['directions']['ref_to_dist']['features']),
                      ('BA_', j['directions']['dist_to_ref']['features']), ('sym_', j['features'])):
    for col, printed in row.items():
        if not col.startswith(prefix) or printed == '':
            continue
        name = col[len(prefix):].replace('haus', 'hausdorff')
        v = feats.get(name)
        v = math.inf if v is None else v
        e = math.inf if printed == 'inf' else float(printed)
        if not (v == e or abs(v - e) <= 1e-8 * abs(e)):
            bad.append('%s%s %r vs %s' % (prefix, name, v, printed))
if bad:
    print('; '.join(bad), file=sys.stderr)
sys.exit(1 if bad else 0)
EOF
      then summary+=("ok: $label: every value of mm_pcc_monkey_g1024 within 1e-8")
      else summary+=("FAIL: $label: values differ from mm_pcc_monkey_g1024"); STATUS=1
      fi
    fi
    [ -n "$MM" ] || continue
    printf '| %s | mm (sample x 2 + compare) | 1 | %s s | %s s | %s MB | %s | |\n' "$label" \
      "$(stats "$TMP/tm" 0)" "$(stats "$TMP/tm" 1)" "$(stats "$TMP/tm" 2 1024)" "$(head -1 "$TMP/dm")"
    wq=$(median "$TMP/tq" 0) wm=$(median "$TMP/tm" 0) mq=$(median "$TMP/tq" 2) mm=$(median "$TMP/tm" 2)
    summary+=("$label: qm3d / mm: wall $wq / $wm s = $($PY -c "print('%.2f' % ($wq / max($wm, 0.01)))") (target <= 0.25), peak RSS $(((${mq%.*} + 512) / 1024)) / $(((${mm%.*} + 512) / 1024)) MB = $($PY -c "print('%.2f' % ($mq / $mm))") (target <= 1)")
  done
  echo
  for line in "${summary[@]}"; do echo "$line"; done
fi

if [ "$WHICH" = all ] || [ "$WHICH" = ibsm ]; then
  gen_mesh 7; gen_cloud 1000000 1000k
  MM="${QM3D_MMETRIC:-}"
  [ -z "$MM" ] || [ -x "$MM" ] || { echo "QM3D_MMETRIC=$MM is not executable" >&2; exit 1; }
  REFDATA="$ROOT/../shared/data/reference"
  # mm reads no OFF: blob7's pair as the ASCII PLY copies the psnr_mesh mode writes.
  B7=off; [ -f "$DATA/blob7_ref.ply" ] && [ -f "$DATA/blob7_bothnoise.ply" ] && B7=ply
  [ -z "$MM" ] || [ "$B7" = ply ] || {
    echo "run 'bench/run_benchmarks.sh psnr_mesh' once first (it writes $DATA/blob7_*.ply for mm)" >&2; exit 1; }
  echo
  echo "| case | tool | threads | wall | CPU | peak RSS | YUV PSNR (dB) | target |"
  echo "|---|---|---|---|---|---|---|---|"
  summary=()
  for c in "monkey2 / monkey_simplified (mesh)|$REFDATA/cmdm/monkey2.obj|$REFDATA/cmdm/monkey_simplified.obj|mesh" \
           "blob7 ref / bothnoise (mesh, 164k vertices)|$DATA/blob7_ref.$B7|$DATA/blob7_bothnoise.$B7|mesh" \
           "sphere 1M points ref / cnoise10 (cloud)|$DATA/sphere_1000k_ref_bin.ply|$DATA/sphere_1000k_cnoise10_bin.ply|cloud"; do
    IFS='|' read -r label ref dist kind <<<"$c"
    for f in tq tm sq sm; do : > "$TMP/$f"; done
    # qm3d and mm alternate, so that a slow spell of the machine weighs on both alike.
    for _ in $(seq "$RUNS"); do
      measure_once "$TMP/tq" "$QM3D" ibsm "$ref" "$dist" --threads 2 --quiet --json
      $PY -c "import json,sys; print(repr(json.load(open(sys.argv[1]))['features']['yuv_psnr']))" "$TMP/out" >> "$TMP/sq" 2>/dev/null || echo error >> "$TMP/sq"
      if [ -n "$MM" ] && [ "$kind" = mesh ]; then
        measure_once "$TMP/tm" "$MM" compare --mode ibsm --inputModelA "$ref" --inputModelB "$dist"
        awk '/^YUV PSNR =/ {v = $NF} END {print v == "" ? "error" : v}' "$TMP/out" >> "$TMP/sm"
      fi
    done
    s=$(head -1 "$TMP/sq")
    if [ "$(sort -u "$TMP/sq" | wc -l)" != 1 ] || [ "$s" = error ]; then
      echo "FAIL: $label: qm3d's YUV PSNR differs between runs or is missing" >&2
      STATUS=1
    fi
    target="wall <= 1/2 mm's, RSS <= 1.5 x mm's"
    [ "$kind" = cloud ] && target="<= 10 s (mm draws no cloud)"
    [ "$kind" = mesh ] && [ -z "$MM" ] && target="(QM3D_MMETRIC unset: no mm to compare)"
    printf '| %s | qm3d (with SSIM, MS-SSIM) | 2 | %s s | %s s | %s MB | %s | %s |\n' "$label" \
      "$(stats "$TMP/tq" 0)" "$(stats "$TMP/tq" 1)" "$(stats "$TMP/tq" 2 1024)" "$s" "$target"
    if [ "$kind" = cloud ]; then
      wq=$(median "$TMP/tq" 0)
      summary+=("$label: qm3d wall $wq s (target <= 10 s)")
    fi
    [ -s "$TMP/tm" ] || continue
    sm=$(head -1 "$TMP/sm")
    printf '| %s | mm compare --mode ibsm | 1 | %s s | %s s | %s MB | %s | |\n' "$label" \
      "$(stats "$TMP/tm" 0)" "$(stats "$TMP/tm" 1)" "$(stats "$TMP/tm" 2 1024)" "$sm"
    wq=$(median "$TMP/tq" 0) wm=$(median "$TMP/tm" 0)
    rq=$(median "$TMP/tq" 2) rm=$(median "$TMP/tm" 2)
    summary+=("$label: mm / qm3d wall $wm / $wq s = $($PY -c "print('%.2f' % ($wm / max($wq, 0.01)))") x (target >= 2); qm3d / mm peak RSS $($PY -c "print('%.0f / %.0f MB = %.2f' % ($rq / 1024, $rm / 1024, $rq / $rm))") (target <= 1.5)")
    if $PY -c "import sys; a, b = float(sys.argv[1]), float(sys.argv[2]); sys.exit(0 if abs(a - b) <= 5e-7 * abs(b) + 5e-7 else 1)" "$s" "$sm"; then
      summary+=("ok: $label: qm3d's YUV PSNR $s rounds to mm's $sm")
    else
      summary+=("FAIL: $label: qm3d's YUV PSNR $s, mm printed $sm"); STATUS=1
    fi
  done
  echo
  for line in "${summary[@]}"; do echo "$line"; done
fi

if [ "$WHICH" = all ] || [ "$WHICH" = pointssim ]; then
  gen_cloud 5000 5k; gen_cloud 100000 100k; gen_cloud 1000000 1000k
  echo
  echo "| case | threads | wall | CPU | peak RSS | score | target |"
  echo "|---|---|---|---|---|---|---|"
  for spec in "5k|all|<= 0.36 s (100 x faster than the reference's ~36 s)" "100k|var|linear in N" \
              "1000k|var|<= 10 s"; do
    IFS='|' read -r tag estimators target <<< "$spec"
    SCORES="$TMP/scores"; : > "$SCORES"
    measure "$TMP/case" "$QM3D" --threads "$THREADS" --quiet pointssim \
      "$DATA/sphere_${tag}_ref_bin.ply" "$DATA/sphere_${tag}_cnoise10_bin.ply" --fit-knn 12 \
      --estimators "$estimators" --poolings all --attributes all --csv
    SCORES=""
    if [ "$(sort -u "$TMP/scores" | wc -l)" != 1 ]; then
      echo "FAIL: PointSSIM $tag: the score differs between runs" >&2; STATUS=1
    fi
    printf '| PointSSIM sphere %s, estimators %s | %s | %s s | %s s | %s MB | %s | %s |\n' "$tag" \
      "$estimators" "$THREADS" "$(stats "$TMP/case" 0)" "$(stats "$TMP/case" 1)" \
      "$(stats "$TMP/case" 2 1024)" "$(head -1 "$TMP/scores")" "$target"
  done
fi

if [ "$WHICH" = all ] || [ "$WHICH" = geodesicpsim ]; then
  GP="$ROOT/../shared/data/reference/geodesicpsim"
  GPD="$DATA/geodesicpsim"
  mkdir -p "$GPD"
  for f in "$GP"/inputs/*; do
    b=$(basename "$f")
    case "$b" in
      *.gz) [ -s "$GPD/${b%.gz}" ] || gunzip -c "$f" > "$GPD/${b%.gz}" ;;
      *) [ -e "$GPD/$b" ] || ln -s "$f" "$GPD/$b" ;;
    esac
  done
  echo
  echo "| case | tool | threads | wall | CPU | peak RSS | score | target |"
  echo "|---|---|---|---|---|---|---|---|"
  summary=()
  for c in bb1_qp16_default bb1_qp8_default tb5ns_texjpeg30_default; do
    # ref dis want_score ref_cpu ref_rss_mb (the reference's 1-thread run)
    read -r ref dis want rcpu rrss < <($PY - "$GP/geodesicpsim_reference.csv" "$c" <<'EOF2'
import csv, sys
r = next(r for r in csv.DictReader(open(sys.argv[1])) if r["case"] == sys.argv[2])
print(r["ref_obj"], r["dis_obj"], r["score"], r["cpu_s_1thread"], r["maxrss_MB_1thread"])
EOF2
)
    for t in 1 2; do
      : > "$TMP/tq"; : > "$TMP/sq"
      for _ in $(seq "$RUNS"); do
        measure_once "$TMP/tq" "$QM3D" geodesicpsim "$GPD/$ref" "$GPD/$dis" --threads "$t" --quiet --json
        $PY -c "import json,sys; print(repr(json.load(open(sys.argv[1]))['score']))" "$TMP/out" >> "$TMP/sq" 2>/dev/null || echo error >> "$TMP/sq"
      done
      s=$(head -1 "$TMP/sq")
      printf '| %s | qm3d | %s | %s s | %s s | %s MB | %s | CPU <= %s s, RSS <= %s MB |\n' "$c" "$t" \
        "$(stats "$TMP/tq" 0)" "$(stats "$TMP/tq" 1)" "$(stats "$TMP/tq" 2 1024)" "$s" \
        "$($PY -c "print('%.1f' % ($rcpu / 5))")" "$($PY -c "print('%.0f' % ($rrss / 4))")"
      if [ "$(sort -u "$TMP/sq" | wc -l)" != 1 ] || ! $PY -c "import sys; a, b = float(sys.argv[1]), float(sys.argv[2]); sys.exit(0 if abs(a - b) <= 1e-9 * abs(b) else 1)" "$s" "$want"; then
        summary+=("FAIL: $c --threads $t: qm3d's score $(sort -u "$TMP/sq" | tr '\n' ' ')vs the table's $want"); STATUS=1
      fi
      [ "$t" = 1 ] || continue
      cq=$(median "$TMP/tq" 1) mq=$(median "$TMP/tq" 2)
      summary+=("$c: reference CPU / qm3d CPU (1 thread) = $rcpu / $cq s = $($PY -c "print('%.1f' % ($rcpu / max($cq, 0.01)))") (target >= 5), qm3d peak RSS $((${mq%.*} / 1024)) MB vs the reference's $rrss MB (target <= 1/4)")
    done
    printf '| %s | GeodesicPSIM @ 3e06453 (recorded) | 1 | | %s s | %s MB | %s | |\n' "$c" "$rcpu" "$rrss" "$want"
  done
  echo
  for line in "${summary[@]}"; do echo "$line"; done
fi

if [ "$WHICH" = vs-reference ]; then
  MEPP2="${QM3D_MEPP2_CMDM:-}" PCQM_REF="${QM3D_PCQM_REF:-}"
  [ -n "$MEPP2$PCQM_REF" ] || {
    echo "vs-reference needs QM3D_MEPP2_CMDM (MEPP2's example_cmdm) and/or QM3D_PCQM_REF (MEPP-team/PCQM's binary)" >&2
    exit 1
  }
  for b in "$MEPP2" "$PCQM_REF"; do
    [ -z "$b" ] || [ -x "$b" ] || { echo "$b is not executable" >&2; exit 1; }
  done
  # The references read their tables and write their side files in the working directory.
  scratch="$TMP/reference-cwd"
  mkdir -p "$scratch"
  if [ -n "$PCQM_REF" ]; then
    tables="${QM3D_DATA_DIR:-$ROOT/../shared/data/lab2000hl}"
    for f in L_data.txt RegularGrid_0_0_1.txt RegularGrid_0_0_2.txt RegularGridInit_0_0_1.txt \
             RegularGridInit_0_0_2.txt; do
      # PCQM runs on with an all-zero lightness table when L_data.txt is missing.
      [ -s "$tables/$f" ] || { echo "$tables/$f is missing (set QM3D_DATA_DIR)" >&2; exit 1; }
      ln -sf "$(cd "$tables" && pwd)/$f" "$scratch/$f"
    done
  fi
  printed_score() {  # pattern stdout-file -> the last number printed after the pattern
    awk -v p="$1" 'index($0, p) {v = $NF} END {print v == "" ? "error" : v}' "$2"
  }
  rounds_to() {  # qm3d printed -> exit 0 when qm3d's score rounds to the 6 significant digits printed
    $PY -c "
import math, sys
q, p = (float(x) for x in sys.argv[1:])
half = 0.5 * 10 ** (math.floor(math.log10(abs(p))) - 5) if p != 0 else 1e-300
sys.exit(0 if abs(q - p) <= half * (1 + 1e-9) else 1)" "$1" "$2" 2>/dev/null
  }
  "$QM3D" --version | head -1
  [ -z "$MEPP2" ] || echo "reference CMDM: $MEPP2 ($("$QM3D" --version | awk '$1 == "cmdm:"' | sed 's/^ *cmdm: //'))"
  [ -z "$PCQM_REF" ] || echo "reference PCQM: $PCQM_REF ($("$QM3D" --version | awk '$1 == "pcqm:"' | sed 's/^ *pcqm: //'))"
  echo
  echo "| case | tool | threads | wall | CPU | peak RSS | score | target |"
  echo "|---|---|---|---|---|---|---|---|"
  cases=()
  [ -z "$MEPP2" ] || cases+=(
    "CMDM blob7 (164k vertices)|cmdm|blob7_ref.off|blob7_bothnoise.off|MEPP2 example_cmdm|>= 15 x MEPP2's speed|0"
    "CMDM blob8 (655k vertices)|cmdm|blob8_ref.off|blob8_bothnoise.off|MEPP2 example_cmdm|>= 15 x MEPP2's speed, <= 400 MB|400")
  [ -z "$PCQM_REF" ] || cases+=(
    "PCQM sphere 1M points|pcqm|sphere_1000k_ref_bin.ply|sphere_1000k_cnoise10_bin.ply|MEPP-team/PCQM|>= 15 x the reference's speed, <= 250 MB|250")
  summary=()
  for c in "${cases[@]}"; do
    IFS='|' read -r label metric ref dist tool target rss_mb <<<"$c"
    if [ "$metric" = cmdm ]; then
      gen_mesh "${ref:4:1}"
      ref_cmd=(env -C "$scratch" "$MEPP2" "$DATA/$ref" "$DATA/$dist") ref_threads=1
      pattern="Calculated CMDM = "
    else
      gen_cloud 1000000 1000k
      ref_cmd=(env -C "$scratch" OMP_NUM_THREADS=2 "$PCQM_REF" "$DATA/$ref" "$DATA/$dist" -fq) ref_threads=2
      pattern="PCQM value is : "
    fi
    for f in tq tr sq sr; do : > "$TMP/$f"; done
    # qm3d and its reference alternate, so that a slow spell of the machine weighs on both alike.
    for _ in $(seq "$RUNS"); do
      SCORES="$TMP/sq" measure_once "$TMP/tq" "$QM3D" --threads 2 --quiet "$metric" \
        "$DATA/$ref" "$DATA/$dist" --csv
      measure_once "$TMP/tr" "${ref_cmd[@]}"
      printed_score "$pattern" "$TMP/out" >> "$TMP/sr"
    done
    sq=$(head -1 "$TMP/sq") sr=$(head -1 "$TMP/sr")
    printf '| %s | qm3d | 2 | %s s | %s s | %s MB | %s | %s |\n' "$label" "$(stats "$TMP/tq" 0)" \
      "$(stats "$TMP/tq" 1)" "$(stats "$TMP/tq" 2 1024)" "$sq" "$target"
    printf '| %s | %s | %s | %s s | %s s | %s MB | %s | |\n' "$label" "$tool" "$ref_threads" \
      "$(stats "$TMP/tr" 0)" "$(stats "$TMP/tr" 1)" "$(stats "$TMP/tr" 2 1024)" "$sr"
    wq=$(median "$TMP/tq" 0) wr=$(median "$TMP/tr" 0) mq=$(median "$TMP/tq" 2)
    speedup=$($PY -c "print('%.1f' % ($wr / max($wq, 0.01)))")
    met() { $PY -c "print('met' if $1 else 'missed')"; }
    line="$label: $tool / qm3d wall $wr / $wq s = $speedup x (target >= 15: $(met "$speedup >= 15"))"
    [ "$rss_mb" = 0 ] || line+=", qm3d peak RSS $((${mq%.*} / 1024)) MB (target <= $rss_mb MB: $(met "${mq%.*} <= $rss_mb * 1024"))"
    summary+=("$line")
    if [ "$(sort -u "$TMP/sq" | wc -l)" != 1 ] || [ "$(sort -u "$TMP/sr" | wc -l)" != 1 ]; then
      summary+=("FAIL: $label: a score differs between runs: qm3d $(sort -u "$TMP/sq" | tr '\n' ' '), $tool $(sort -u "$TMP/sr" | tr '\n' ' ')")
      STATUS=1
    elif [ "$sr" != error ] && rounds_to "$sq" "$sr"; then
      summary+=("ok: $label: qm3d's score $sq rounds to $tool's printed $sr")
    else
      summary+=("FAIL: $label: qm3d's score $sq, $tool printed $sr")
      STATUS=1
    fi
  done
  echo
  for line in "${summary[@]}"; do echo "$line"; done
fi
if [ "$WHICH" = all ] || [ "$WHICH" = graphsim ]; then
  GS="$ROOT/../shared/data/reference/graphsim"
  VOX="$ROOT/../shared/data/reference/voxel"
  [ -f "$DATA/voxsphere_1m_ref.ply" ] || $PY "$ROOT/bench/pointcloud/gen_voxel_sphere.py" 290 "$DATA/voxsphere_1m" >&2
  echo
  echo "| case | threads | wall | CPU | peak RSS | score | reference score | target |"
  echo "|---|---|---|---|---|---|---|---|"
  want() { awk -F';' -v c="$1" -v k="$2" 'NR==1 {for (i = 1; i <= NF; i++) col[$i] = i} $1==c {print $col[k]}' "$GS/graphsim_reference.csv"; }
  for c in "GraphSIM vox1 requant9, 64 keypoints|graphsim|$VOX/vox1_ref.ply|$VOX/vox1_requant9.ply|--keypoint-file $GS/keys_vox1_ref.txt|$(want vox1_requant9 graphsim)|CPU <= 0.11 s (2.2 s / 20)" \
           "MS-GraphSIM vox1 requant9, 6 scales|msgraphsim|$VOX/vox1_ref.ply|$VOX/vox1_requant9.ply|--keypoint-file $GS/keys_vox1_ref.txt --scales 6|$(want vox1_requant9 msgraphsim_ns6)|CPU <= 0.24 s (4.7 s / 20)" \
           "GraphSIM vox1, keypoints drawn (56k points)|graphsim|$VOX/vox1_ref.ply|$VOX/vox1_requant9.ply||n/a|wall <= 22 s (441 s / 20)" \
           "GraphSIM sphere 1.17M points, keypoints drawn|graphsim|$DATA/voxsphere_1m_ref.ply|$DATA/voxsphere_1m_cnoise10.ply||n/a|seconds" \
           "MS-GraphSIM sphere 1.17M points, keypoints drawn|msgraphsim|$DATA/voxsphere_1m_ref.ply|$DATA/voxsphere_1m_cnoise10.ply||n/a|seconds"; do
    IFS='|' read -r label metric ref dist opts expected target <<<"$c"
    : > "$TMP/gs"
    : > "$TMP/gt"
    for _ in $(seq "$RUNS"); do
      # shellcheck disable=SC2086
      measure_once "$TMP/gt" "$QM3D" "$metric" "$ref" "$dist" $opts --threads 2 --quiet --json
      $PY -c "import json,sys; print(repr(json.load(open(sys.argv[1]))['score']))" "$TMP/out" >> "$TMP/gs" 2>/dev/null || echo error >> "$TMP/gs"
    done
    s=$(head -1 "$TMP/gs")
    if [ "$(sort -u "$TMP/gs" | wc -l)" != 1 ] || [ "$s" = error ]; then
      echo "FAIL: $label: the score differs between runs or is missing" >&2; STATUS=1
    fi
    if [ "$expected" != n/a ] && ! $PY -c "import sys; a, b = float(sys.argv[1]), float(sys.argv[2]); sys.exit(0 if abs(a - b) <= 1e-10 * abs(b) else 1)" "$s" "$expected"; then
      echo "FAIL: $label: score $s, reference $expected" >&2; STATUS=1
    fi
    printf '| %s | 2 | %s s | %s s | %s MB | %s | %s | %s |\n' "$label" "$(stats "$TMP/gt" 0)" \
      "$(stats "$TMP/gt" 1)" "$(stats "$TMP/gt" 2 1024)" "$s" "$expected" "$target"
  done
fi
if [ "$WHICH" = icid ] || { [ "$WHICH" = all ] && [ -n "${QM3D_ICID_REF:-}" ]; }; then
  VIEWS="$ROOT/../shared/data/reference/icid/views/blob4_geonoise"
  BENCH_ICID="${QM3D_BENCH_ICID:-$(dirname "$QM3D")/../bench/render/bench_icid}"
  [ -x "$BENCH_ICID" ] || { echo "icid: no $BENCH_ICID (set QM3D_BENCH_ICID)" >&2; exit 2; }
  : > "$TMP/icid_pairs"
  for v in $(seq 0 17); do
    printf '%s/view_%02d_reference.png;%s/view_%02d_distorted.png\n' "$VIEWS" "$v" "$VIEWS" "$v" \
      >> "$TMP/icid_pairs"
  done
  qm3d_mean=$(while IFS=';' read -r a b; do
    "$QM3D" --quiet image "$a" "$b" --json | $PY -c "import json,sys; print(repr(json.load(sys.stdin)['features']['icid']))"
  done < "$TMP/icid_pairs" | $PY -c "import sys; v=[float(l) for l in sys.stdin]; print(repr(sum(v) / len(v)))")
  : > "$TMP/icid_q"
  : > "$TMP/icid_r"
  : > "$TMP/icid_rs"
  for _ in $(seq "$RUNS"); do
    "$BENCH_ICID" --benchmark_filter='^BM_Icid18ViewsInParallel/2/' --benchmark_format=csv \
      2> /dev/null | awk -F, '/BM_Icid18ViewsInParallel\/2/ {printf "%.4f\n", $3 / 1000}' >> "$TMP/icid_q"
    if [ -n "${QM3D_ICID_REF:-}" ]; then
      /usr/bin/time -f "%e %U %S %M" -o "$TMP/time" $QM3D_ICID_REF "$TMP/icid_pairs" > "$TMP/out" \
        2> "$TMP/err" || { cat "$TMP/err" >&2; echo "FAIL: $QM3D_ICID_REF" >&2; STATUS=1; }
      awk '{printf "%s %.2f %s\n", $1, $2 + $3, $4}' "$TMP/time" >> "$TMP/icid_r"
      $PY -c "import sys; v=[float(l) for l in open(sys.argv[1]) if l.strip()]; print(repr(sum(v) / len(v)) if len(v) == 18 else 'error')" \
        "$TMP/out" >> "$TMP/icid_rs"
    fi
  done
  echo
  echo "| case | qm3d (2 threads, in process) | reference (whole process) | speed-up | mean iCID qm3d / reference | target |"
  echo "|---|---|---|---|---|---|"
  ref_wall=n/a ref_score=n/a ratio=n/a
  if [ -n "${QM3D_ICID_REF:-}" ]; then
    ref_wall="$(stats "$TMP/icid_r" 0) s wall, $(stats "$TMP/icid_r" 1) s CPU"
    ref_score=$(head -1 "$TMP/icid_rs")
    ratio=$($PY -c "print('%.1f' % ($(median "$TMP/icid_r" 0) / $(median "$TMP/icid_q" 0)))")
    if [ "$(sort -u "$TMP/icid_rs" | wc -l)" != 1 ] || [ "$ref_score" = error ] || \
       ! $PY -c "import sys; a, b = float(sys.argv[1]), float(sys.argv[2]); sys.exit(0 if abs(a - b) <= 1e-10 * abs(b) else 1)" "$qm3d_mean" "$ref_score"; then
      echo "FAIL: icid: the reference's mean $ref_score, qm3d's $qm3d_mean" >&2; STATUS=1
    fi
  fi
  printf '| iCID, 18 view pairs at 256² (blob4_geonoise) | %s s | %s | %s | %s / %s | >= 50 x |\n' \
    "$(stats "$TMP/icid_q" 0)" "$ref_wall" "$ratio" "$qm3d_mean" "$ref_score"
fi
if [ "$WHICH" = all ] || [ "$WHICH" = krasula ]; then
  KS="$DATA/krasula_10000.csv"
  [ -f "$KS" ] || $PY "$ROOT/bench/evaluation/gen_krasula_stimuli.py" 10000 "$KS" >&2
  echo
  echo "| case | threads | wall | CPU | peak RSS | AUC_BW of m1 | target |"
  echo "|---|---|---|---|---|---|---|"
  for cols in m1 m1,m2; do
    : > "$TMP/kt"
    : > "$TMP/ks"
    for _ in $(seq "$RUNS"); do
      measure_once "$TMP/kt" "$QM3D" --threads "$THREADS" --quiet eval "$KS" "$KS" \
        --scores-key stimulus --scores-column "$cols" --mos-column MOS --sd-column SD \
        --n-column n --bootstrap 0 --json
      $PY -c "import json,sys; j=json.load(open(sys.argv[1])); print(repr([j['metrics'][m]['krasula'] for m in sorted(j['metrics'])] + [c for c in j['comparisons'] if c['test'].startswith(('delong', 'c0'))]))" "$TMP/out" >> "$TMP/ks" 2>/dev/null || echo error >> "$TMP/ks"
    done
    if [ "$(sort -u "$TMP/ks" | wc -l)" != 1 ] || [ "$(head -1 "$TMP/ks")" = error ]; then
      echo "FAIL: Krasula $cols: the values differ between runs or are missing" >&2; STATUS=1
    fi
    auc=$($PY -c "import json,sys; print(json.load(open(sys.argv[1]))['metrics']['m1']['krasula']['auc_bw'])" "$TMP/out" 2>/dev/null || echo n/a)
    printf '| Krasula 10,000 stimuli (50 M pairs), metrics %s | %s | %s s | %s s | %s MB | %s | seconds, < 1 GB |\n' \
      "$cols" "$THREADS" "$(stats "$TMP/kt" 0)" "$(stats "$TMP/kt" 1)" "$(stats "$TMP/kt" 2 1024)" "$auc"
  done
fi
exit $STATUS
