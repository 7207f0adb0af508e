#!/usr/bin/env bash
# Runs the whole qm3d test suite with ctest (building first if needed).
#
#   scripts/test.sh              # normal Release build in build/, then the installed package
#                                # used by tests/downstream (scripts/test_downstream.sh),
#                                # the Slurm scripts (tests/slurm/test_slurm.sh, as root),
#                                # HTML reports in headless Chromium (tests/report/test_report.sh)
#                                # the Debian package (tests/package/test_deb.sh)
#                                # and the Python wheel in a fresh venv (tests/python_package/)
#   scripts/test.sh --sanitize   # AddressSanitizer + UBSan build in build-sanitize/
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
JOBS="${QM3D_JOBS:-$(nproc)}"
BUILD_DIR="${QM3D_BUILD_DIR:-$ROOT/build}"
EXTRA=()
CTEST_ARGS=()
if [ "${1:-}" = "--sanitize" ]; then
  BUILD_DIR="$ROOT/build-sanitize"
  EXTRA=(-DQM3D_SANITIZE=ON -DQM3D_BUILD_BENCH=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo)
  export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
  # The voxel PCQM rows at -r 0.02 (2000-point curvature fits, 10000-point statistics
  # neighbourhoods) take minutes under the sanitizers and run no code the default-radius voxel
  # rows do not: the normal build runs them.
  CTEST_ARGS=(-E 'r02_vox1')
fi

if [ ! -f "$BUILD_DIR/CMakeCache.txt" ] || [ ${#EXTRA[@]} -gt 0 ]; then
  cmake -S "$ROOT" -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release "${EXTRA[@]}" >/dev/null
fi
cmake --build "$BUILD_DIR" -j "$JOBS"
cd "$BUILD_DIR"
ctest --output-on-failure -j "$JOBS" "${CTEST_ARGS[@]}"
# The installed package, used by another project (tests/downstream); not under the sanitizers
# (the downstream program would need their runtime too).
if [ ${#EXTRA[@]} -eq 0 ]; then
  bash "$ROOT/scripts/test_downstream.sh" "$BUILD_DIR"
  # scripts/slurm/ on a private one-node Slurm cluster (exit 77: skipped, no Slurm/munge or root).
  slurm_rc=0
  bash "$ROOT/tests/slurm/test_slurm.sh" "$BUILD_DIR/apps/qm3d" || slurm_rc=$?
  [ "$slurm_rc" -eq 0 ] || [ "$slurm_rc" -eq 77 ] || exit "$slurm_rc"
  # HTML reports opened in headless Chromium (exit 77: skipped, no chromium or libjs-three).
  report_rc=0
  bash "$ROOT/tests/report/test_report.sh" "$BUILD_DIR/apps/qm3d" || report_rc=$?
  [ "$report_rc" -eq 0 ] || [ "$report_rc" -eq 77 ] || exit "$report_rc"
  # The Debian package (cpack -G DEB) installed into a scratch root (exit 77: skipped, no dpkg-dev).
  deb_rc=0
  bash "$ROOT/tests/package/test_deb.sh" "$BUILD_DIR" || deb_rc=$?
  [ "$deb_rc" -eq 0 ] || [ "$deb_rc" -eq 77 ] || exit "$deb_rc"
  # `pip wheel` of a clean copy installed into a fresh venv (exit 77: skipped, no pip/venv or
  # no Python package in the build).
  wheel_rc=0
  bash "$ROOT/tests/python_package/test_wheel.sh" "$BUILD_DIR" || wheel_rc=$?
  [ "$wheel_rc" -eq 0 ] || [ "$wheel_rc" -eq 77 ] || exit "$wheel_rc"
  # The wheel for another CPython of the same minor version (pyenv's), offline, with Debian's
  # numpy (exit 77: skipped, no such interpreter).
  other_rc=0
  bash "$ROOT/tests/python_package/test_other_python.sh" "$BUILD_DIR" || other_rc=$?
  [ "$other_rc" -eq 0 ] || [ "$other_rc" -eq 77 ] || exit "$other_rc"
fi
