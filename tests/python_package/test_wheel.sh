#!/usr/bin/env bash
# The Python wheel as a user gets it: `pip wheel` on a clean copy of the source (tracked and
# untracked files, no build directories) run by a fresh `python3 -m venv --system-site-packages`
# (numpy from Debian), `pip install` of that wheel into the venv, then, from another directory
# with no PYTHONPATH: qm3d imports from the venv, finds the tables shipped in the wheel, scores a
# bundled pair exactly as the build tree's package does, and a missing table directory or table
# file is the same one-line InputError. Then a wheel built where no tables are found: it has
# none, looks in the configured directory (the same error when absent) and scores the pair with
# $QM3D_DATA_DIR. Nothing is downloaded (--no-index, --no-build-isolation).
# Run by scripts/test.sh.
#
#   tests/python_package/test_wheel.sh [BUILD_DIR]      (default: build/)
#
# Exit 77 (skipped, with a message) when pip, venv or setuptools is missing for
# /usr/bin/python3, or the build tree has no Python package (no pybind11-dev).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD_DIR="${1:-$ROOT/build}"
PY=/usr/bin/python3  # Debian's interpreter: its numpy is what the venv sees
export PYTHONDONTWRITEBYTECODE=1 PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_CONFIG_FILE=/dev/null
unset PYTHONPATH PIP_INDEX_URL PIP_EXTRA_INDEX_URL PIP_FIND_LINKS
START=$SECONDS

log() { printf '[wheel] %s\n' "$*" >&2; }
skip() { log "skipped: $*"; exit 77; }
fail() { log "FAIL: $*"; exit 1; }

"$PY" -m pip --version >/dev/null 2>&1 || skip "no pip for $PY (Debian package python3-pip)"
"$PY" -c 'import ensurepip, venv' 2>/dev/null ||
  skip "no venv for $PY (Debian package python3-venv)"
"$PY" -c 'import setuptools' 2>/dev/null ||
  skip "no setuptools for $PY (Debian package python3-setuptools; no \`wheel\` needed)"
[ -f "$BUILD_DIR/CMakeCache.txt" ] || fail "$BUILD_DIR: not a configured build directory"
ls "$BUILD_DIR"/python/qm3d/_qm3d*.so >/dev/null 2>&1 ||
  skip "$BUILD_DIR has no Python package (pybind11-dev / python3-dev missing?)"
TABLES="$(sed -n 's/^QM3D_DEFAULT_DATA_DIR:PATH=//p' "$BUILD_DIR/CMakeCache.txt")"
[ -f "$TABLES/L_data.txt" ] || fail "$BUILD_DIR: its tables directory '$TABLES' has no tables"

WORK="$(mktemp -d "${TMPDIR:-/tmp}/qm3d-wheel.XXXXXX")"
trap 'rm -rf "$WORK"' EXIT
SRC="$WORK/src" VENV="$WORK/venv" DIST="$WORK/dist"
quietly() {  # runs a command, showing its output only when it fails
  "$@" >"$WORK/log" 2>&1 || { tail -40 "$WORK/log" >&2; fail "$*"; }
}

# A clean copy: what a fresh clone holds (plus uncommitted work), without build directories.
mkdir -p "$SRC"
if git -C "$ROOT" rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  (cd "$ROOT" && git ls-files -z --cached --others --exclude-standard |
   while IFS= read -r -d '' f; do [ -e "$f" ] && printf '%s\0' "$f"; done |
   tar -c --null -T - -f -) | tar -x -C "$SRC"
else
  tar -c -C "$ROOT" --exclude=./build --exclude='./build-*' -f - . | tar -x -C "$SRC"
fi

log "venv: $PY -m venv --system-site-packages"
quietly "$PY" -m venv --system-site-packages "$VENV"
VPY="$VENV/bin/python"
# The venv's interpreter builds (sys.executable differs from $PY; same version and ABI).
# ccache keys on paths relative to $WORK, so a rerun of this test reuses the compiled objects.
build_wheel() {  # OUT_DIR [VAR=VALUE...]: pip wheel in $SRC with those variables set
  local out="$1"; shift
  (cd "$SRC" && quietly env "$@" CCACHE_BASEDIR="$WORK" \
     CMAKE_BUILD_PARALLEL_LEVEL="${QM3D_JOBS:-$(nproc)}" \
     "$VPY" -m pip wheel . --no-build-isolation --no-deps --no-index --no-cache-dir -w "$out")
}
log "pip wheel (a full build of the libraries and the module; minutes without ccache)"
build_wheel "$DIST" QM3D_DATA_DIR="$TABLES"
WHEEL="$(ls "$DIST"/qm3d-*.whl)"
TAG="$("$VPY" -c 'import sys; print("cp%d%d" % sys.version_info[:2])')"
[[ "$(basename "$WHEEL")" == qm3d-*-"$TAG"-"$TAG"-linux_*.whl ]] ||
  fail "$(basename "$WHEEL"): not a $TAG platform wheel"
grep -qx "PYTHON_EXECUTABLE:FILEPATH=$VPY" "$SRC"/build-wheel/temp.*/cmake/CMakeCache.txt ||
  fail "CMake did not build for the interpreter running pip ($VPY)"
[ ! -e "$SRC/python/qm3d.egg-info" ] || fail "the build wrote python/qm3d.egg-info into the source"
"$VPY" - "$WHEEL" <<'EOF' || fail "the wheel's contents (above)"
import sys, zipfile
names = set(zipfile.ZipFile(sys.argv[1]).namelist())
want = {"qm3d/__init__.py", "qm3d/dask.py", "qm3d/lab2000hl/LICENSE-MPL2.txt"} | {
    f"qm3d/lab2000hl/{t}.txt" for t in ("L_data", "RegularGrid_0_0_1", "RegularGrid_0_0_2",
                                        "RegularGridInit_0_0_1", "RegularGridInit_0_0_2")}
missing = sorted(want - names)
if missing or not any(n.startswith("qm3d/_qm3d.") and n.endswith(".so") for n in names):
    sys.exit(f"missing {missing or 'qm3d/_qm3d*.so'} in {sorted(names)}")
EOF
log "pip install $(basename "$WHEEL")"
quietly "$VPY" -m pip install --no-index --no-deps --no-cache-dir "$WHEEL"

# The pair's score and features (17 digits) from a package; the tables it read on stderr.
SCORE='import qm3d, sys, warnings
warnings.simplefilter("ignore", qm3d.Qm3dWarning)  # stderr: the paths only
r = qm3d.pcqm(sys.argv[1], sys.argv[2])
print(qm3d.__file__, qm3d._qm3d.__file__, r.to_dict()["options"]["data_dir"], sep="\n",
      file=sys.stderr)
print(repr(r.score), sorted((k, repr(v)) for k, v in r.features.items()))'
REF="$ROOT/data/clouds/sphere_2k_ref.ply" DIST_CLOUD="$ROOT/data/clouds/sphere_2k_cnoise10.ply"
built=$(cd / && PYTHONPATH="$BUILD_DIR/python" QM3D_DATA_DIR="$TABLES" \
        "$PY" -c "$SCORE" "$REF" "$DIST_CLOUD" 2>/dev/null) || fail "the build tree's package"
wheel=$(cd / && env -u QM3D_DATA_DIR "$VPY" -c "$SCORE" "$REF" "$DIST_CLOUD" 2>"$WORK/where") ||
  { cat "$WORK/where" >&2; fail "the installed wheel could not score the pair"; }
{ read -r module; read -r extension; read -r used; } <"$WORK/where"
SITE="$("$VPY" -c 'import sysconfig; print(sysconfig.get_path("platlib"))')"
[ "$module" = "$SITE/qm3d/__init__.py" ] || fail "import qm3d gave $module, not the venv's"
[[ "$extension" == "$SITE/qm3d/_qm3d."*.so ]] || fail "qm3d._qm3d is $extension, not the venv's"
[ "$used" = "$SITE/qm3d/lab2000hl" ] || fail "the wheel read the tables in $used, not its own"
[ "$wheel" = "$built" ] || fail "the wheel scored $wheel, the build tree $built"
log "ok   pcqm sphere_2k_ref sphere_2k_cnoise10 = ${wheel%% *} from $module"

# A missing table directory ($QM3D_DATA_DIR) and a missing table file (data_dir=): the one-line
# InputError naming the path, as from a build tree.
mkdir "$WORK/four_tables"
cp "$TABLES"/L_data.txt "$TABLES"/RegularGrid_0_0_1.txt "$TABLES"/RegularGridInit_0_0_*.txt \
   "$WORK/four_tables"
ERROR='import qm3d, sys
try:
    qm3d.pcqm(sys.argv[1], sys.argv[2], **({"data_dir": sys.argv[3]} if sys.argv[3:] else {}))
except qm3d.InputError as e:
    print(e)
else:
    sys.exit("no InputError")'
check_error() {  # command... (the message expected: $EXPECT, a pattern)
  local got
  got=$(cd / && "$@" 2>&1) || fail "$got"
  [[ "$got" == $EXPECT ]] || fail "expected '$EXPECT', got '$got'"
  log "ok   $got"
}
EXPECT="LAB2000HL table directory $WORK/absent: not found (set --data-dir or QM3D_DATA_DIR)"
check_error env QM3D_DATA_DIR="$WORK/absent" "$VPY" -c "$ERROR" "$REF" "$DIST_CLOUD"
EXPECT="LAB2000HL table $WORK/four_tables/RegularGrid_0_0_2.txt: cannot open (set --data-dir"*
check_error "$VPY" -c "$ERROR" "$REF" "$DIST_CLOUD" "$WORK/four_tables"

# A wheel built where no tables are found: none inside (none left from the first build either),
# the configured directory is where it looks, and a missing one is the same error.
log "pip wheel without tables (the same build directory: one source file rebuilt)"
build_wheel "$WORK/dist-no-tables" QM3D_CMAKE_ARGS="-DQM3D_DEFAULT_DATA_DIR=$WORK/absent"
"$VPY" -c 'import sys, zipfile
names = zipfile.ZipFile(sys.argv[1]).namelist()
tables = [n for n in names if "lab2000hl" in n]
sys.exit(f"{tables}" if tables else 0)' "$WORK"/dist-no-tables/qm3d-*.whl ||
  fail "the wheel built without tables has the files above"
quietly "$VPY" -m pip install --no-index --no-deps --no-cache-dir --force-reinstall \
  "$WORK"/dist-no-tables/qm3d-*.whl
EXPECT="LAB2000HL table directory $WORK/absent: not found (set --data-dir or QM3D_DATA_DIR)"
check_error env -u QM3D_DATA_DIR "$VPY" -c "$ERROR" "$REF" "$DIST_CLOUD"
again=$(cd / && QM3D_DATA_DIR="$TABLES" "$VPY" -c "$SCORE" "$REF" "$DIST_CLOUD" 2>/dev/null) ||
  fail "the wheel without tables could not score the pair with \$QM3D_DATA_DIR"
[ "$again" = "$built" ] || fail "the wheel without tables scored $again, the build tree $built"
log "ok   with \$QM3D_DATA_DIR: ${again%% *}"
log "passed in $((SECONDS - START)) s"
