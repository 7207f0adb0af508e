#!/usr/bin/env bash
# The Debian package (cmake/Packaging.cmake): `cpack -G DEB` in a build directory, then checks
#   - the file name qm3d_VERSION_ARCH.deb and the control fields (dpkg-deb -f);
#   - Depends computed by dpkg-shlibdeps: every shared library the packaged ELF files need
#     directly (readelf NEEDED, resolved by ldd) belongs to a Debian package named in Depends;
#   - the contents: exactly what `cmake --install` installs, the Python package moved from
#     lib/python3.X/dist-packages to Debian's lib/python3/dist-packages;
#   - installed into a scratch root: as root with `dpkg --root=SCRATCH -i` against a copy of this
#     system's dpkg status, so that dpkg itself checks that Depends is satisfied here (no
#     --force-depends); otherwise unpacked with `dpkg-deb -x`. No chroot: the packaged binaries
#     run in place and load this system's libraries from /usr/lib (every one found: ldd), the
#     package's own libraries being static;
#   - the unpacked tool runs `qm3d demo` and scores a bundled pair with the package's tables
#     (SCRATCH/usr/share/qm3d/lab2000hl, found beside SCRATCH/usr/bin/qm3d, with no QM3D_DATA_DIR),
#     and Debian's python3 imports the package's module and scores the same pair with them;
#   - the manual page qm3d(1) is in the package (usr/share/man/man1/qm3d.1.gz, gzip -9n) and, once
#     installed, `man -l` and `man qm3d` (MANPATH=SCRATCH/usr/share/man) render it with every
#     command and every metric of the packaged tool (skipped when man-db is not installed);
#   - `dpkg --root=SCRATCH -r qm3d` removes every file it installed.
#
#   tests/package/test_deb.sh [BUILD_DIR]      (default: build/, already built: cpack only
#                                               re-runs its install step)
# Exit 77 (skipped, with a message) when cpack, dpkg-deb or dpkg-shlibdeps (dpkg-dev) is missing.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD_DIR="$(cd "${1:-$ROOT/build}" && pwd)"
PY=/usr/bin/python3
export PYTHONDONTWRITEBYTECODE=1

log() { printf '[deb] %s\n' "$*" >&2; }
fail() { log "FAIL: $*"; exit 1; }

[ -f "$BUILD_DIR/CPackConfig.cmake" ] ||
  fail "$BUILD_DIR/CPackConfig.cmake: not a configured qm3d build directory"
CMAKE="$(sed -n 's/^CMAKE_COMMAND:INTERNAL=//p' "$BUILD_DIR/CMakeCache.txt")"
CPACK="$(dirname "$CMAKE")/cpack"
for tool in "$CPACK" dpkg-deb dpkg-shlibdeps dpkg file readelf ldd; do
  command -v "$tool" >/dev/null ||
    { echo "test_deb: skipped: $tool not found (Debian packages cmake, dpkg-dev, file, binutils)"; exit 77; }
done

SCRATCH="$(mktemp -d "${TMPDIR:-/tmp}/qm3d-deb.XXXXXX")"
trap 'rm -rf "$SCRATCH"' EXIT
START=$SECONDS
quietly() {  # runs a command, showing its output only when it fails
  "$@" >"$SCRATCH/log" 2>&1 || { cat "$SCRATCH/log" >&2; fail "$*"; }
}

# ---- build the package (into the scratch folder: nothing is left in the build directory) ----
VERSION="$(sed -n 's/^project(qm3d VERSION \([0-9.]*\).*/\1/p' "$ROOT/CMakeLists.txt")"
ARCH="$(dpkg --print-architecture)"
[ -n "$VERSION" ] || fail "no version in $ROOT/CMakeLists.txt's project()"
quietly "$CPACK" -G DEB --config "$BUILD_DIR/CPackConfig.cmake" -B "$SCRATCH/pkg"
DEB="$SCRATCH/pkg/qm3d_${VERSION}_${ARCH}.deb"
[ -f "$DEB" ] || fail "cpack wrote $(ls "$SCRATCH/pkg"/*.deb 2>/dev/null || echo nothing), not $DEB"
log "built $(basename "$DEB") ($(( $(stat -c %s "$DEB") / 1024 )) KiB)"

# ---- control fields ----
field() { dpkg-deb -f "$DEB" "$1"; }
expect_field() {  # name value
  [ "$(field "$1")" = "$2" ] || fail "$1: '$(field "$1")', expected '$2'"
}
expect_field Package qm3d
expect_field Version "$VERSION"
expect_field Architecture "$ARCH"
expect_field Section science
for f in Maintainer Description Depends; do [ -n "$(field "$f")" ] || fail "no $f field"; done
DEPENDS="$(field Depends)"
depended() { tr ',|' '\n' <<<"$DEPENDS" | sed 's/^ *//; s/ .*//'; }  # package names
depends_on() { depended | grep -Fqx "$1"; }
for p in libc6 libstdc++6 libgomp1 python3 python3-numpy; do
  depends_on "$p" || fail "Depends does not name $p: $DEPENDS"
done
depends_on liblzf1 || fail "Depends does not name liblzf1 (binary_compressed PCD): $DEPENDS"
# PCD is read without PCL: its I/O library (VTK, OpenNI, MPI ...) is no dependency of the package.
if depended | grep -q '^libpcl-\|^libvtk'; then fail "Depends names PCL or VTK: $DEPENDS"; fi

# ---- contents: what `cmake --install` installs, the Python package in Debian's place ----
quietly "$CMAKE" --install "$BUILD_DIR" --prefix "$SCRATCH/install/usr"
(cd "$SCRATCH/install" && find . -type f -o -type l) |
  sed 's|^\./||; s|^usr/lib/python3\.[0-9]*/dist-packages/|usr/lib/python3/dist-packages/|' |
  sort >"$SCRATCH/installed.txt"
dpkg-deb -c "$DEB" | awk '$1 !~ /^d/ {print $6}' | sed 's|^\./||' | sort >"$SCRATCH/packaged.txt"
diff -u "$SCRATCH/installed.txt" "$SCRATCH/packaged.txt" >&2 ||
  fail "the package's files differ from cmake --install's (- installed only, + packaged only)"
for f in usr/bin/qm3d usr/lib/cmake/qm3d/qm3dConfig.cmake usr/include/qm3d/common/version.h \
         usr/lib/libqm3d_common.a usr/share/qm3d/data/meshes/blob3_ref.off \
         usr/lib/python3/dist-packages/qm3d/__init__.py usr/share/man/man1/qm3d.1.gz; do
  grep -qx "$f" "$SCRATCH/packaged.txt" || fail "$f is not in the package"
done
TABLES_DIR="$(sed -n 's/^QM3D_DEFAULT_DATA_DIR:PATH=//p' "$BUILD_DIR/CMakeCache.txt")"
if [ -f "$TABLES_DIR/L_data.txt" ]; then
  grep -qx usr/share/qm3d/lab2000hl/L_data.txt "$SCRATCH/packaged.txt" ||
    fail "the build's tables ($TABLES_DIR) are not in the package"
  HAVE_TABLES=1
else
  log "the build found no LAB2000HL tables: the package has none, scoring is not checked"
  HAVE_TABLES=0
fi
rm -rf "$SCRATCH/install"

# ---- install into a scratch root ----
ROOTFS="$SCRATCH/root"
if [ "$(id -u)" -eq 0 ]; then
  mkdir -p "$ROOTFS/var/lib/dpkg/info" "$ROOTFS/var/lib/dpkg/updates"
  cp /var/lib/dpkg/status "$ROOTFS/var/lib/dpkg/status"
  touch "$ROOTFS/var/lib/dpkg/available"
  quietly dpkg --root="$ROOTFS" -i "$DEB"
  log "installed with dpkg --root (its Depends satisfied by this system's packages)"
  INSTALLED=dpkg
else
  quietly dpkg-deb -x "$DEB" "$ROOTFS"
  log "not root: unpacked with dpkg-deb -x (Depends not checked by dpkg)"
  INSTALLED=extract
fi

# ---- every shared library found, and owned by a package named in Depends ----
owner() {  # library path -> the Debian package holding it (usrmerge: /usr/lib or /lib)
  local path="$1" real found
  real="$(readlink -f "$path")"
  for p in "$path" "${path#/usr}" "/usr$path" "$real" "${real#/usr}" "/usr$real"; do
    found="$(dpkg -S "$p" 2>/dev/null)" || continue
    [ -n "$found" ] && { sed -n '1s/:.*//p' <<<"$found"; return 0; }
  done
  return 1
}
mapfile -t ELVES < <(find "$ROOTFS/usr" -type f \( -perm -u+x -o -name '*.so' \) -exec sh -c \
  'head -c 4 "$1" | grep -q "ELF" && echo "$1"' _ {} \; | sort)
[ "${#ELVES[@]}" -ge 1 ] || fail "no ELF file in the package"
for elf in "${ELVES[@]}"; do
  name="${elf#"$ROOTFS"}"
  if ldd "$elf" | grep -q 'not found'; then
    ldd "$elf" >&2; fail "$name: a shared library is not found"
  fi
  for lib in $(readelf -d "$elf" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'); do
    path="$(ldd "$elf" | awk -v lib="$lib" '$1 == lib { print ($3 ~ /^\// ? $3 : $1) }')"
    [ -n "$path" ] || path="$(ldd "$elf" | awk -v lib="$lib" 'index($1, lib) { print $1 }')"
    pkg="$(owner "$path")" || fail "$name needs $lib ($path), which no Debian package holds"
    depends_on "$pkg" || fail "$name needs $lib from $pkg, which Depends does not name: $DEPENDS"
  done
  log "ok   $name: every library found, each one's package in Depends"
done

# ---- the manual page: gzip -9n (no name, no time stamp), rendered by man with every command ----
MANPAGE="$ROOTFS/usr/share/man/man1/qm3d.1.gz"
file -b "$MANPAGE" | grep -q '^gzip compressed data, max compression' ||
  fail "qm3d.1.gz is not gzip -9n: $(file -b "$MANPAGE")"
if command -v man >/dev/null; then
  MANWIDTH=200 man -l "$MANPAGE" >"$SCRATCH/man-l.txt" 2>"$SCRATCH/man.err" ||
    { cat "$SCRATCH/man.err" >&2; fail "man -l could not render qm3d.1.gz"; }
  MANPATH="$ROOTFS/usr/share/man" MANWIDTH=200 man qm3d >"$SCRATCH/man.txt" 2>"$SCRATCH/man.err" ||
    { cat "$SCRATCH/man.err" >&2; fail "man qm3d (MANPATH=$ROOTFS/usr/share/man) found no page"; }
  cmp -s "$SCRATCH/man.txt" "$SCRATCH/man-l.txt" || fail "man qm3d and man -l render different pages"
  grep -q '^NAME' "$SCRATCH/man.txt" && grep -q '^COMMANDS' "$SCRATCH/man.txt" ||
    fail "man qm3d has no NAME or COMMANDS section"
  # Every command of the packaged tool's --help and every metric of its --version, with its summary.
  mapfile -t COMMANDS < <(QM3D_DATA_DIR=/nonexistent "$ROOTFS/usr/bin/qm3d" --help |
    sed -n '/^Subcommands:/,$ s/^  \([a-z][a-z0-9_-]*\) .*/\1/p')
  mapfile -t METRICS < <("$ROOTFS/usr/bin/qm3d" --version | sed -n 's/^  \([a-z0-9_]*\): .*/\1/p')
  [ "${#COMMANDS[@]}" -ge 10 ] && [ "${#METRICS[@]}" -ge 5 ] ||
    fail "found ${#COMMANDS[@]} commands and ${#METRICS[@]} metrics in qm3d --help / --version"
  for c in "${COMMANDS[@]}"; do
    summary="$("$ROOTFS/usr/bin/qm3d" --help | sed -n "s/^  $c  *\([A-Z].\{0,30\}\).*/\1/p" | tr -s ' ')"
    grep -Eq "^ {7}$c( |$)" "$SCRATCH/man.txt" || fail "man qm3d does not list the command $c"
    tr -s ' \n' ' ' <"$SCRATCH/man.txt" | grep -Fq "$summary" ||
      fail "man qm3d does not give $c's summary ($summary)"
  done
  for m in "${METRICS[@]}"; do
    sed -n '/^METRICS/,/^COMMAND OPTIONS/p' "$SCRATCH/man.txt" | grep -Eq "^ {7}$m( |$)" ||
      fail "the METRICS section of man qm3d does not list $m"
  done
  log "ok   man qm3d: ${#COMMANDS[@]} commands and ${#METRICS[@]} metrics, each with its summary"
else
  log "man (man-db) not installed: the page's rendering is not checked"
fi

# ---- the packaged tool and Python module, with the package's tables ----
if [ "$HAVE_TABLES" -eq 1 ]; then
  unset QM3D_DATA_DIR
  TABLES="$ROOTFS/usr/share/qm3d/lab2000hl"
  DATA="$ROOTFS/usr/share/qm3d/data"
  mkdir "$SCRATCH/work" && cd "$SCRATCH/work"
  quietly "$ROOTFS/usr/bin/qm3d" demo
  log "ok   qm3d demo"
  "$ROOTFS/usr/bin/qm3d" --quiet pcqm "$DATA/clouds/sphere_2k_ref.ply" \
      "$DATA/clouds/sphere_2k_cnoise10.ply" --json >"$SCRATCH/tool.json" ||
    fail "the packaged tool could not score a bundled pair"
  read -r tool_tables tool_score < <("$PY" -c 'import json, sys
r = json.load(open(sys.argv[1])); print(r["options"]["data_dir"], repr(r["score"]))' \
      "$SCRATCH/tool.json")
  [ "$tool_tables" = "$TABLES" ] || fail "the packaged tool read the tables in $tool_tables, not $TABLES"
  log "ok   the packaged tool reads the package's tables: pcqm = $tool_score"
  read -r py_file py_tables py_score < <(PYTHONPATH="$ROOTFS/usr/lib/python3/dist-packages" "$PY" -c '
import sys, qm3d
r = qm3d.pcqm(sys.argv[1], sys.argv[2]).to_dict()
print(qm3d.__file__, r["options"]["data_dir"], repr(r["score"]))' \
      "$DATA/clouds/sphere_2k_ref.ply" "$DATA/clouds/sphere_2k_cnoise10.ply") ||
    fail "Debian's python3 could not import the package's qm3d and score a pair"
  [ "$py_file" = "$ROOTFS/usr/lib/python3/dist-packages/qm3d/__init__.py" ] ||
    fail "python3 imported $py_file, not the package's module"
  [ "$py_tables" = "$TABLES" ] || fail "the Python module read the tables in $py_tables, not $TABLES"
  [ "$py_score" = "$tool_score" ] || fail "Python pcqm = $py_score, the tool's = $tool_score"
  log "ok   python3 imports the package's module, reads its tables, same score"
  [ -z "$(ls -A "$SCRATCH/work")" ] || fail "files written in the working directory"
  cd "$SCRATCH"
fi

# ---- removal ----
if [ "$INSTALLED" = dpkg ]; then
  quietly dpkg --root="$ROOTFS" -r qm3d
  left="$(find "$ROOTFS" -path "$ROOTFS/var" -prune -o -type f -print)"
  [ -z "$left" ] || fail "dpkg -r left files behind: $left"
  log "ok   dpkg --root -r removed every file"
fi
log "passed in $((SECONDS - START)) s"
