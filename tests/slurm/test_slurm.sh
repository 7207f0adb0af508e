#!/usr/bin/env bash
# End-to-end test of scripts/slurm/ on a real, private, one-node Slurm cluster started here:
# munged, slurmctld and slurmd with their own key copy, sockets, ports, state and logs in a
# temporary folder (nothing in /etc is changed, except creating /etc/munge/munge.key when the
# munge package left none).
#
#   tests/slurm/test_slurm.sh [QM3D_BINARY]     # default: build/apps/qm3d; must run as root
#
# 1. submit.sh --wait: 3 array tasks over the bundled stimuli, then the dependent merge job; the
#    merged CSV must equal a single-process `qm3d batch` of the same list (every column but
#    `seconds`, same order).
# 2. A slower list in 2 shards: one task is cancelled (scancel) after its first rows, resubmitted
#    alone (`sbatch --array=1`) and resumes; after `qm3d merge` every pair is there exactly once.
# Exit code 0 pass, 1 fail, 77 skipped (Slurm or munge not installed, or not root). Every daemon
# started here is stopped, by its pid, on exit.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
QM3D="$(realpath -m "${1:-${QM3D_BIN:-$ROOT/build/apps/qm3d}}")"

skip() { echo "SKIP: test_slurm: $*"; exit 77; }
for tool in munged slurmctld slurmd sbatch scontrol scancel squeue sinfo; do
  command -v "$tool" >/dev/null || skip "$tool is not installed (apt-get install slurm-wlm munge)"
done
[ "$(id -u)" -eq 0 ] || skip "must run as root (slurmd and munged are started here)"
[ -x "$QM3D" ] || { echo "FAIL: test_slurm: $QM3D: no qm3d binary (build it first)"; exit 1; }

T="$(mktemp -d /tmp/qm3d-slurm-test.XXXXXX)"
chmod 755 "$T"
JOBS=()
ok=""
log() { printf '[test_slurm %(%T)T] %s\n' -1 "$*"; }
fail() { echo "FAIL: test_slurm: $*"; exit 1; }

stop_pidfile() {  # stops the daemon whose pid file is $1, waiting up to 10 s
  local pid
  [ -s "$1" ] || return 0
  pid="$(cat "$1")"
  kill "$pid" 2>/dev/null || return 0
  for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || return 0; sleep 0.2; done
  kill -9 "$pid" 2>/dev/null || true
}
cleanup() {
  local code=$?
  set +e
  if [ -s "$T/slurmctld.pid" ] && [ ${#JOBS[@]} -gt 0 ]; then
    scancel "${JOBS[@]}" 2>/dev/null
    for _ in $(seq 50); do [ -z "$(squeue -h 2>/dev/null)" ] && break; sleep 0.2; done
  fi
  stop_pidfile "$T/slurmd.pid"
  stop_pidfile "$T/slurmctld.pid"
  stop_pidfile "$T/munged.pid"
  if [ -n "$ok" ]; then
    rm -rf "$T"
  else
    for f in "$T"/slurmctld.log "$T"/slurmd.log "$T"/out*/logs/*.log; do
      [ -f "$f" ] && { echo "--- $f (last lines)"; tail -n 15 "$f"; }
    done
    echo "test_slurm: files kept in $T"
  fi
  exit $code
}
trap cleanup EXIT
trap 'exit 1' INT TERM

# ---- munge ---------------------------------------------------------------------------------
KEY=/etc/munge/munge.key
if [ ! -s "$KEY" ]; then
  log "creating $KEY"
  mkdir -p /etc/munge
  mungekey --create --keyfile="$KEY" 2>/dev/null || dd if=/dev/urandom of="$KEY" bs=1024 count=1 2>/dev/null
  chmod 400 "$KEY"
fi
install -m 400 "$KEY" "$T/munge.key"  # a root-owned copy: munged running as root accepts it
munged --force --socket="$T/munge.sock" --pid-file="$T/munged.pid" --log-file="$T/munged.log" \
  --seed-file="$T/munged.seed" --key-file="$T/munge.key" || fail "munged did not start ($T/munged.log)"
for _ in $(seq 50); do [ -S "$T/munge.sock" ] && break; sleep 0.1; done
[ -S "$T/munge.sock" ] || fail "munged made no socket"

# ---- slurmctld + slurmd ------------------------------------------------------------------------
port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
CTLD_PORT=16817
while ! port_free "$CTLD_PORT" || ! port_free $((CTLD_PORT + 1)); do
  CTLD_PORT=$((CTLD_PORT + 2))
  [ "$CTLD_PORT" -lt 16900 ] || fail "no free port pair in 16817..16900"
done
MEM_MB=$(awk '/MemTotal/ { print int($2 / 1024 * 0.8) }' /proc/meminfo)
mkdir -p "$T/state" "$T/spool"
cat > "$T/slurm.conf" <<EOF
ClusterName=qm3dtest
SlurmctldHost=localhost
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$T/munge.sock
SlurmctldPort=$CTLD_PORT
SlurmdPort=$((CTLD_PORT + 1))
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/slurmctld.log
SlurmdLogFile=$T/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=1
MpiDefault=none
ReturnToService=2
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
InactiveLimit=0
MinJobAge=300
KillWait=5
Waittime=0
NodeName=localhost CPUs=2 RealMemory=$MEM_MB State=UNKNOWN
PartitionName=test Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$T/slurm.conf"
slurmctld -f "$SLURM_CONF" || fail "slurmctld did not start"
slurmd -f "$SLURM_CONF" -N localhost || fail "slurmd did not start"
for _ in $(seq 150); do
  [ "$(sinfo -h -o %t 2>/dev/null)" = "idle" ] && break
  sleep 0.2
done
[ "$(sinfo -h -o %t 2>/dev/null)" = "idle" ] || fail "the node did not become idle: $(sinfo 2>&1)"
log "cluster up (ports $CTLD_PORT/$((CTLD_PORT + 1)))"

# ---- 1: submit.sh over the bundled stimuli == one qm3d batch -----------------------------------
cp -r "$ROOT/data/meshes" "$ROOT/data/clouds" "$T/"
cat > "$T/list.csv" <<'EOF'
reference,distorted,metric
meshes/blob3_ref.off,meshes/blob3_ref.off
meshes/blob3_ref.off,meshes/blob3_geonoise.off
meshes/blob3_ref.off,meshes/blob3_colnoise.off
meshes/blob3_ref.off,meshes/blob3_bothnoise.off,compare
meshes/blob3_ref.off,meshes/blob3_geonoise.off,msdm2
clouds/sphere_2k_ref.ply,clouds/sphere_2k_cnoise10.ply
clouds/sphere_2k_ref.ply,clouds/sphere_2k_gnoise0.005.ply
clouds/sphere_2k_ref.ply,clouds/sphere_2k_down0.5.ply,compare
clouds/sphere_2k_ref.ply,clouds/sphere_2k_missing.ply
EOF
log "1: submit.sh -n 3 --wait"
set +e
submit_out="$("$ROOT/scripts/slurm/submit.sh" -n 3 -c 1 --qm3d "$QM3D" --wait "$T/list.csv" "$T/out1" 2>&1)"
merge_code=$?
set -e
echo "$submit_out"
JOBS+=($(sed -n 's/.*array job \([0-9]*\):.*/\1/p' <<< "$submit_out"))
# The list has one missing file: its row records the error and merge exits 2, like batch.
[ "$merge_code" -eq 2 ] || fail "merge job exit code $merge_code, expected 2 (one failed pair)"
for k in 0 1 2; do [ -f "$T/out1/OUT_$k.csv" ] || fail "shard $k wrote no $T/out1/OUT_$k.csv"; done
grep -q "0 missing" "$T"/out1/logs/merge-*.log || fail "merge did not find every row: $(cat "$T"/out1/logs/merge-*.log)"
set +e
"$QM3D" batch "$T/list.csv" -o "$T/single.csv" --threads 1 --quiet
single_code=$?
set -e
[ "$single_code" -eq 2 ] || fail "single batch exit code $single_code, expected 2"
without_seconds() {  # every column but the 7th (seconds), read as CSV (warnings quote commas)
  python3 -c 'import csv, sys
for row in csv.reader(open(sys.argv[1], newline="")): print(repr(row[:6] + row[7:]))' "$1"
}
if ! diff <(without_seconds "$T/single.csv") <(without_seconds "$T/out1/RESULTS.csv") >"$T/diff1.txt"; then
  cat "$T/diff1.txt"
  fail "merged results differ from a single qm3d batch"
fi
rows=$(($(wc -l < "$T/single.csv") - 1))
# meshes: 3 cmdm + 5 (compare: cmdm, msdm2, pcqm, pcqm_sampled, dlab) + 1 msdm2; clouds: 2 pcqm
# + 3 (compare: pcqm, psnr, dlab) + 1 missing file
[ "$rows" -eq 15 ] || fail "expected 15 result rows, got $rows"
log "1: PASS ($rows rows from 3 shards equal one batch)"

# ---- 2: a task cancelled mid-run and resubmitted resumes its results ----------------------------
: > "$T/slow.csv"
for r in ref geonoise colnoise bothnoise; do
  for d in ref geonoise colnoise bothnoise; do
    echo "meshes/blob3_$r.off,meshes/blob3_$d.off,pcqm_sampled" >> "$T/slow.csv"
  done
done
mkdir -p "$T/out2/logs"
ARRAY_SCRIPT="$ROOT/scripts/slurm/qm3d-array.sbatch"
SLOW_ARGS=("$T/slow.csv" "$T/out2" 2 --points 100000)  # about 1 s per pair
job=$(sbatch --parsable --array=0-1 --cpus-per-task=1 --export="ALL,QM3D_BIN=$QM3D" \
  --output="$T/out2/logs/batch-%A_%a.log" "$ARRAY_SCRIPT" "${SLOW_ARGS[@]}")
job="${job%%;*}"
JOBS+=("$job")
log "2: array job $job (2 shards of 16 pairs); cancelling task 1 after its first rows"
lines() { if [ -f "$1" ]; then wc -l < "$1"; else echo 0; fi; }
for _ in $(seq 600); do [ "$(lines "$T/out2/OUT_1.csv")" -ge 3 ] && break; sleep 0.1; done
[ "$(lines "$T/out2/OUT_1.csv")" -ge 3 ] || fail "task 1 wrote no rows within 60 s"
scancel "${job}_1"
for _ in $(seq 150); do [ -z "$(squeue -h -j "$job" 2>/dev/null)" ] && break; sleep 0.2; done
[ -z "$(squeue -h -j "$job" 2>/dev/null)" ] || fail "array job $job did not end"
done_rows=$(($(lines "$T/out2/OUT_1.csv") - 1))
[ "$done_rows" -lt 8 ] || fail "task 1 finished its 8 pairs before it was cancelled: cannot test resuming"
log "2: task 1 cancelled after $done_rows of its 8 pairs; resubmitting it alone"
set +e
resumed=$(sbatch --parsable --wait --array=1 --cpus-per-task=1 --export="ALL,QM3D_BIN=$QM3D" \
  --output="$T/out2/logs/resumed-%A_%a.log" "$ARRAY_SCRIPT" "${SLOW_ARGS[@]}")
resumed_code=$?
set -e
JOBS+=("${resumed%%;*}")
[ "$resumed_code" -eq 0 ] || fail "the resubmitted task failed (exit code $resumed_code)"
grep -q "pairs already done" "$T"/out2/logs/resumed-*.log || fail "the resubmitted task did not resume"
"$QM3D" merge "$T/out2/OUT_0.csv" "$T/out2/OUT_1.csv" -o "$T/out2/RESULTS.csv" --list "$T/slow.csv" \
  2> "$T/merge2.err" || { cat "$T/merge2.err"; fail "merge after resuming failed"; }
cat "$T/merge2.err"
grep -q "duplicated\|missing:" "$T/merge2.err" && fail "merge reported duplicated or missing pairs"
shard_rows=$(( $(lines "$T/out2/OUT_0.csv") + $(lines "$T/out2/OUT_1.csv") - 2 ))
[ "$shard_rows" -eq 16 ] || fail "the shards wrote $shard_rows rows for 16 pairs (a pair scored twice?)"
if ! diff <(cut -d, -f1-2 "$T/slow.csv") <(tail -n +2 "$T/out2/RESULTS.csv" | cut -d, -f1-2) >"$T/diff2.txt"; then
  cat "$T/diff2.txt"
  fail "merged pairs are not the list's pairs in its order"
fi
log "2: PASS (16 pairs, each once, after cancel + resume)"
ok=1
echo "PASS: test_slurm"
