#!/usr/bin/env bash
# Installs qm3d from a build directory into a scratch prefix, builds tests/downstream against it
# (find_package(qm3d), qm3d::mesh, qm3d::pointcloud), and checks that the downstream program and
# the installed tool give the same scores on bundled pairs. Run by scripts/test.sh.
#
#   scripts/test_downstream.sh [BUILD_DIR]      (default: build/)
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${1:-$ROOT/build}"
SCRATCH="$(mktemp -d "${TMPDIR:-/tmp}/qm3d-downstream.XXXXXX")"
trap 'rm -rf "$SCRATCH"' EXIT
PREFIX="$SCRATCH/prefix"

log() { printf '[downstream] %s\n' "$*" >&2; }

quietly() {  # runs a command, showing its output only when it fails
  "$@" >"$SCRATCH/log" 2>&1 || { cat "$SCRATCH/log" >&2; log "FAIL: $*"; exit 1; }
}
log "installing $BUILD_DIR into $PREFIX"
quietly cmake --install "$BUILD_DIR" --prefix "$PREFIX"
log "building tests/downstream against it"
quietly cmake -S "$ROOT/tests/downstream" -B "$SCRATCH/build" -DCMAKE_BUILD_TYPE=Release \
        -DCMAKE_PREFIX_PATH="$PREFIX"
quietly cmake --build "$SCRATCH/build" -j "${QM3D_JOBS:-$(nproc)}"
rm -f "$SCRATCH/log"

# Neither the environment nor the working directory may point at tables: the installed tool must
# find PREFIX/share/qm3d/lab2000hl by itself; the downstream program gets the package's
# qm3d_DATA_DIR (tests/downstream/CMakeLists.txt).
unset QM3D_DATA_DIR
TABLES="$PREFIX/share/qm3d/lab2000hl"
[ -f "$TABLES/L_data.txt" ] || { log "FAIL: no tables installed in $TABLES"; exit 1; }
cd "$SCRATCH"

fail=0
check() {  # metric ref dist
  local tool lib
  tool=$("$PREFIX/bin/qm3d" --quiet "$1" "$ROOT/data/$2" "$ROOT/data/$3" --json |
         python3 -c 'import json, sys; print(repr(json.load(sys.stdin)["score"]))')
  lib=$("$SCRATCH/build/score_pair" "$1" "$ROOT/data/$2" "$ROOT/data/$3" |
        python3 -c 'import sys; print(repr(float(sys.stdin.read())))')
  if [ "$tool" = "$lib" ]; then
    log "ok   $1 $2 $3: $lib"
  else
    log "FAIL $1 $2 $3: installed tool $tool, downstream program $lib"
    fail=1
  fi
}
used=$("$PREFIX/bin/qm3d" --quiet pcqm "$ROOT/data/clouds/sphere_2k_ref.ply" \
       "$ROOT/data/clouds/sphere_2k_cnoise10.ply" --json |
       python3 -c 'import json, sys; print(json.load(sys.stdin)["options"]["data_dir"])')
if [ "$used" = "$TABLES" ]; then
  log "ok   the installed tool reads its own tables ($used)"
else
  log "FAIL: the installed tool read the tables in $used, not $TABLES"
  fail=1
fi
check cmdm meshes/blob3_ref.off meshes/blob3_bothnoise.off
# The evaluation toolkit through its deprecated header path and the default registry.
spearman=$("$SCRATCH/build/score_pair" spearman)
if [ "$spearman" = "-1 1" ]; then
  log "ok   evaluation through qm3d/common/evaluation.h (deprecated path): $spearman"
else
  log "FAIL evaluation through the deprecated path: '$spearman', expected '-1 1'"
  fail=1
fi
check pcqm clouds/sphere_2k_ref.ply clouds/sphere_2k_cnoise10.ply
"$PREFIX/bin/qm3d" demo >/dev/null || { log "FAIL: the installed tool's demo"; fail=1; }
[ -z "$(ls -A "$SCRATCH" | grep -v -e '^prefix$' -e '^build$')" ] ||
  { log "FAIL: files written in the working directory"; fail=1; }
exit "$fail"
