#!/usr/bin/env bash
# Issue 44 item 10 (b): the wheel for another CPython of Debian's minor version (pyenv's 3.11.7,
# a self-built 3.11), where no package index is reachable, by the commands of docs/python.md
# "Installing for another Python": a venv of that interpreter with Debian's numpy linked in,
# `pip wheel` of a clean copy with the venv's own setuptools (no `wheel` package: setup.py's
# bdist_wheel), `pip install --no-index` of that wheel *with* its dependencies (numpy, declared,
# satisfied by Debian's), then from another directory: qm3d imports from the venv and scores a
# bundled pair exactly as the build tree's package does under Debian's python3.
#
#   tests/python_package/test_other_python.sh [BUILD_DIR]      (default: build/)
#
# The other interpreter: $QM3D_OTHER_PYTHON, else the first CPython of Debian's minor version
# among pyenv's versions and python3.X on PATH that is not Debian's own. Exit 77 (skipped, with a
# message) when there is none, or it lacks venv/pip, or the build has no Python package.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD_DIR="$(cd "${1:-$ROOT/build}" && pwd)"  # absolute: the checks run from /
DEBIAN_PY=/usr/bin/python3
export PYTHONDONTWRITEBYTECODE=1 PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_CONFIG_FILE=/dev/null
unset PYTHONPATH PIP_INDEX_URL PIP_EXTRA_INDEX_URL PIP_FIND_LINKS
START=$SECONDS

log() { printf '[other-python] %s\n' "$*" >&2; }
skip() { log "skipped: $*"; exit 77; }
fail() { log "FAIL: $*"; exit 1; }

[ -x "$DEBIAN_PY" ] || skip "no $DEBIAN_PY"
MINOR="$("$DEBIAN_PY" -c 'import sys; print("%d.%d" % sys.version_info[:2])')"
NUMPY_DIR=$("$DEBIAN_PY" -c 'import numpy, os; print(os.path.dirname(numpy.__file__))' 2>/dev/null) ||
  skip "no numpy for $DEBIAN_PY (Debian package python3-numpy)"
NUMPY_META=$(ls -d "$NUMPY_DIR"-*.egg-info "$NUMPY_DIR"-*.dist-info 2>/dev/null | head -1) || true
[ -n "$NUMPY_META" ] || skip "Debian's numpy in $NUMPY_DIR has no metadata directory beside it"
ls "$BUILD_DIR"/python/qm3d/_qm3d*.so >/dev/null 2>&1 ||
  skip "$BUILD_DIR has no Python package (pybind11-dev / python3-dev missing?)"
TABLES="$(sed -n 's/^QM3D_DEFAULT_DATA_DIR:PATH=//p' "$BUILD_DIR/CMakeCache.txt")"
[ -f "$TABLES/L_data.txt" ] || fail "$BUILD_DIR: its tables directory '$TABLES' has no tables"

# CPython of Debian's minor version, not Debian's own interpreter.
is_other() {
  "$1" -c "import sys, platform
sys.exit(platform.python_implementation() != 'CPython' or '%d.%d' % sys.version_info[:2] != '$MINOR'
         or sys.base_prefix == '/usr')" 2>/dev/null
}
OTHER="${QM3D_OTHER_PYTHON:-}"
if [ -z "$OTHER" ]; then
  for candidate in "${PYENV_ROOT:-$HOME/.pyenv}"/versions/"$MINOR".*/bin/python"$MINOR" \
                   $(type -ap "python$MINOR" python3 2>/dev/null); do
    if [ -x "$candidate" ] && is_other "$candidate"; then OTHER="$candidate"; break; fi
  done
fi
[ -n "$OTHER" ] || skip "no CPython $MINOR besides $DEBIAN_PY (set QM3D_OTHER_PYTHON)"
is_other "$OTHER" || fail "$OTHER: not a CPython $MINOR other than Debian's"
"$OTHER" -c 'import ensurepip, venv' 2>/dev/null || skip "$OTHER has no venv/ensurepip"
log "the other interpreter: $OTHER ($("$OTHER" -c 'import sys; print(sys.version.split()[0])'))"

WORK="$(mktemp -d "${TMPDIR:-/tmp}/qm3d-other-python.XXXXXX")"
trap 'rm -rf "$WORK"' EXIT
SRC="$WORK/src" VENV="$WORK/venv" DIST="$WORK/dist"
quietly() {  # runs a command, showing its output only when it fails
  "$@" >"$WORK/log" 2>&1 || { tail -40 "$WORK/log" >&2; fail "$*"; }
}
mkdir -p "$SRC"
(cd "$ROOT" && git ls-files -z --cached --others --exclude-standard |
 while IFS= read -r -d '' f; do [ -e "$f" ] && printf '%s\0' "$f"; done |
 tar -c --null -T - -f -) | tar -x -C "$SRC"

# docs/python.md (b), command by command.
quietly "$OTHER" -m venv "$VENV"
VPY="$VENV/bin/python"
SITE=$("$VPY" -c 'import sysconfig; print(sysconfig.get_path("platlib"))')
ln -s "$NUMPY_DIR" "$NUMPY_META" "$SITE"/
"$VPY" -c 'import numpy' || fail "Debian's numpy does not import under $OTHER"
if "$VPY" -c 'import wheel' 2>/dev/null; then
  log "note: the venv has a wheel package: setup.py's own bdist_wheel is not exercised"
fi
log "pip wheel with $("$VPY" -c 'import setuptools; print("setuptools", setuptools.__version__)')"
(cd "$SRC" && quietly env CCACHE_BASEDIR="$WORK" CMAKE_BUILD_PARALLEL_LEVEL="${QM3D_JOBS:-$(nproc)}" \
   QM3D_DATA_DIR="$TABLES" \
   "$VPY" -m pip wheel . --no-build-isolation --no-deps --no-index --no-cache-dir -w "$DIST")
WHEEL="$(ls "$DIST"/qm3d-*.whl)"
TAG="$("$VPY" -c 'import sys; print("cp%d%d" % sys.version_info[:2])')"
[[ "$(basename "$WHEEL")" == qm3d-*-"$TAG"-"$TAG"-linux_*.whl ]] ||
  fail "$(basename "$WHEEL"): not a $TAG platform wheel"
"$VPY" - "$WHEEL" <<'PYEOF' || fail "the wheel's metadata (above)"
import sys, zipfile
z = zipfile.ZipFile(sys.argv[1])
meta = [n for n in z.namelist() if n.endswith(".dist-info/METADATA")]
text = z.read(meta[0]).decode()
if "Requires-Dist: numpy" not in text.splitlines():
    sys.exit(f"no 'Requires-Dist: numpy' in\n{text}")
record = [n for n in z.namelist() if n.endswith(".dist-info/RECORD")]
if not record or not any(n.startswith("qm3d/_qm3d.") for n in z.namelist()):
    sys.exit(f"no RECORD or no compiled module in {z.namelist()}")
PYEOF
# With its dependencies: numpy is declared and Debian's satisfies it, offline.
quietly "$VPY" -m pip install --no-index --no-cache-dir "$WHEEL"

SCORE='import qm3d, sys, warnings
warnings.simplefilter("ignore", qm3d.Qm3dWarning)  # stderr: the paths only
r = qm3d.pcqm(sys.argv[1], sys.argv[2])
print(qm3d.__file__, file=sys.stderr)
print(repr(r.score), sorted((k, repr(v)) for k, v in r.features.items()))'
REF="$ROOT/data/clouds/sphere_2k_ref.ply" DIST_CLOUD="$ROOT/data/clouds/sphere_2k_cnoise10.ply"
built=$(cd / && PYTHONPATH="$BUILD_DIR/python" QM3D_DATA_DIR="$TABLES" \
        "$DEBIAN_PY" -c "$SCORE" "$REF" "$DIST_CLOUD" 2>/dev/null) || fail "the build tree's package"
other=$(cd / && env -u QM3D_DATA_DIR "$VPY" -c "$SCORE" "$REF" "$DIST_CLOUD" 2>"$WORK/where") ||
  { cat "$WORK/where" >&2; fail "the wheel under $OTHER could not score the pair"; }
[ "$(cat "$WORK/where")" = "$SITE/qm3d/__init__.py" ] ||
  fail "import qm3d gave $(cat "$WORK/where"), not the venv's"
[ "$other" = "$built" ] || fail "$OTHER scored $other, the build tree $built"
log "ok   pcqm sphere_2k_ref sphere_2k_cnoise10 = ${other%% *} under $OTHER"
log "passed in $((SECONDS - START)) s"
