#!/usr/bin/env bash
# Scores a qm3d batch list on a Slurm cluster: submits a job array of N shards
# (qm3d-array.sbatch) and a merge job (qm3d-merge.sbatch) that starts when every shard has ended.
#
#   scripts/slurm/submit.sh [OPTIONS] LIST OUT_DIR [-- BATCH OPTIONS...]
#
#   -n, --shards N          array tasks = shards (default $QM3D_SHARDS, else 8)
#   -c, --cpus-per-task C   cores per task, passed to qm3d as --threads (default $QM3D_CPUS, else 4)
#   --max-running M         at most M tasks at a time (--array=0-(N-1)%M)
#   --qm3d PATH             the qm3d binary, visible from the compute nodes (default $QM3D_BIN,
#                           else build/apps/qm3d of this checkout, else qm3d on PATH)
#   --results FILE          merged results (default OUT_DIR/RESULTS.csv)
#   --sbatch "OPTIONS"      more sbatch options for both jobs, e.g. "--partition=cpu --time=4:00:00"
#                           (default $QM3D_SBATCH_OPTIONS)
#   --wait                  wait for the merge job and exit with its exit code
#
# Shard K writes OUT_DIR/OUT_K.csv and OUT_DIR/logs/batch-<job>_K.log. A task can be resubmitted
# alone (`sbatch --array=K ... qm3d-array.sbatch LIST OUT_DIR N`): it resumes its results file.
# Prints the two job ids.
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
die() { echo "submit.sh: $*" >&2; exit 1; }
usage() { sed -n '2,21p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; }

SHARDS="${QM3D_SHARDS:-8}"
CPUS="${QM3D_CPUS:-4}"
MAX_RUNNING=""
RESULTS=""
SBATCH_OPTIONS="${QM3D_SBATCH_OPTIONS:-}"
WAIT=""
if [ -z "${QM3D_BIN:-}" ]; then
  if [ -x "$ROOT/build/apps/qm3d" ]; then QM3D_BIN="$ROOT/build/apps/qm3d"; else QM3D_BIN="$(command -v qm3d || true)"; fi
fi
POSITIONAL=()
while [ $# -gt 0 ]; do
  case "$1" in
    -n|--shards) SHARDS="${2:?$1 needs a value}"; shift 2 ;;
    -c|--cpus-per-task) CPUS="${2:?$1 needs a value}"; shift 2 ;;
    --max-running) MAX_RUNNING="${2:?$1 needs a value}"; shift 2 ;;
    --qm3d) QM3D_BIN="${2:?$1 needs a value}"; shift 2 ;;
    --results) RESULTS="${2:?$1 needs a value}"; shift 2 ;;
    --sbatch) SBATCH_OPTIONS="${2?$1 needs a value}"; shift 2 ;;
    --wait) WAIT=1; shift ;;
    -h|--help) usage; exit 0 ;;
    --) shift; break ;;
    -*) die "unknown option $1 (see --help)" ;;
    *) POSITIONAL+=("$1"); shift ;;
  esac
done
[ ${#POSITIONAL[@]} -eq 2 ] || die "expected LIST OUT_DIR (see --help)"
LIST="$(realpath -m "${POSITIONAL[0]}")"
OUT_DIR="$(realpath -m "${POSITIONAL[1]}")"
RESULTS="$(realpath -m "${RESULTS:-$OUT_DIR/RESULTS.csv}")"
[ -f "$LIST" ] || die "$LIST: no such file"
[[ "$SHARDS" =~ ^[1-9][0-9]*$ ]] || die "--shards $SHARDS: expected a whole number >= 1"
[[ "$CPUS" =~ ^[1-9][0-9]*$ ]] || die "--cpus-per-task $CPUS: expected a whole number >= 1"
[ -z "$MAX_RUNNING" ] || [[ "$MAX_RUNNING" =~ ^[1-9][0-9]*$ ]] || die "--max-running $MAX_RUNNING: expected a whole number >= 1"
[ -n "$QM3D_BIN" ] && [ -x "$QM3D_BIN" ] || die "no qm3d binary: build it or give --qm3d PATH"
QM3D_BIN="$(realpath "$QM3D_BIN")"
command -v sbatch >/dev/null || die "sbatch: not found (not on a Slurm cluster?)"

mkdir -p "$OUT_DIR/logs"
read -r -a EXTRA_SBATCH <<< "$SBATCH_OPTIONS"
ARRAY="0-$((SHARDS - 1))${MAX_RUNNING:+%$MAX_RUNNING}"
array_job=$(sbatch --parsable "${EXTRA_SBATCH[@]}" --array="$ARRAY" --cpus-per-task="$CPUS" \
  --export="ALL,QM3D_BIN=$QM3D_BIN" --output="$OUT_DIR/logs/batch-%A_%a.log" \
  "$HERE/qm3d-array.sbatch" "$LIST" "$OUT_DIR" "$SHARDS" "$@")
array_job="${array_job%%;*}"
echo "submit.sh: array job $array_job: $SHARDS shards of $LIST -> $OUT_DIR/OUT_*.csv" >&2
merge_args=(--parsable "${EXTRA_SBATCH[@]}" --dependency="afterany:$array_job"
  --export="ALL,QM3D_BIN=$QM3D_BIN" --output="$OUT_DIR/logs/merge-%j.log")
if [ -n "$WAIT" ]; then
  echo "submit.sh: waiting for the merge job (after every shard) -> $RESULTS" >&2
  set +e
  sbatch --wait "${merge_args[@]}" "$HERE/qm3d-merge.sbatch" "$LIST" "$OUT_DIR" "$SHARDS" "$RESULTS"
  code=$?
  set -e
  echo "submit.sh: merge job ended with exit code $code (log: $OUT_DIR/logs/merge-*.log)" >&2
  exit $code
fi
merge_job=$(sbatch "${merge_args[@]}" "$HERE/qm3d-merge.sbatch" "$LIST" "$OUT_DIR" "$SHARDS" "$RESULTS")
merge_job="${merge_job%%;*}"
echo "submit.sh: merge job $merge_job (afterany:$array_job) -> $RESULTS" >&2
echo "$array_job $merge_job"
