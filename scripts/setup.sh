#!/usr/bin/env bash
# qm3d set-up: installs the Debian 12 packages qm3d needs, finds (or fetches) the LAB2000HL tables,
# configures and builds into build/, and runs the demo on the bundled data.
#
#   scripts/setup.sh              # everything
#   QM3D_SKIP_APT=1 scripts/setup.sh   # do not touch packages (build only)
#
# Idempotent: packages already installed are not reinstalled; the build is incremental.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${QM3D_BUILD_DIR:-$ROOT/build}"
JOBS="${QM3D_JOBS:-$(nproc)}"

PACKAGES=(
  build-essential cmake pkg-config git ca-certificates curl
  libeigen3-dev libcgal-dev libgmp-dev libmpfr-dev libnanoflann-dev
  liblzf-dev libpcl-dev libopenmpi-dev
  nlohmann-json3-dev libcli11-dev libstb-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  clang libclang-rt-14-dev
  python3 python3-numpy time
  pybind11-dev python3-dev python3-pytest python3-pandas python3-open3d python3-distributed
  python3-pip python3-venv python3-setuptools python3-wheel python3-yaml
  locales
  slurm-wlm munge
  chromium libjs-three
  dpkg-dev file man-db
)

log() { printf '[setup] %s\n' "$*" >&2; }

as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi
}

install_packages() {
  if [ -n "${QM3D_SKIP_APT:-}" ]; then log "QM3D_SKIP_APT set: not installing packages"; return; fi
  local missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [ ${#missing[@]} -eq 0 ]; then log "all Debian packages present"; return; fi
  log "installing: ${missing[*]}"
  as_root apt-get update -q
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
}

# The LAB2000HL tables are third-party data (MEPP-team/PCQM, resources/, MPL-2.0). They are never
# committed here: use $QM3D_DATA_DIR, else ../shared/data/lab2000hl beside the checkout, else
# download them once into ~/.local/share/qm3d/lab2000hl.
TABLE_FILES=(L_data.txt RegularGrid_0_0_1.txt RegularGrid_0_0_2.txt RegularGridInit_0_0_1.txt RegularGridInit_0_0_2.txt)
TABLE_URL="https://raw.githubusercontent.com/MEPP-team/PCQM/master/resources"

have_tables() { for f in "${TABLE_FILES[@]}"; do [ -s "$1/$f" ] || return 1; done; }

find_tables() {
  if [ -n "${QM3D_DATA_DIR:-}" ] && have_tables "$QM3D_DATA_DIR"; then echo "$QM3D_DATA_DIR"; return; fi
  if have_tables "$ROOT/../shared/data/lab2000hl"; then
    (cd "$ROOT/../shared/data/lab2000hl" && pwd); return
  fi
  local dest="${XDG_DATA_HOME:-$HOME/.local/share}/qm3d/lab2000hl"
  if ! have_tables "$dest"; then
    log "fetching the LAB2000HL tables (MPL-2.0) from $TABLE_URL into $dest"
    mkdir -p "$dest"
    for f in "${TABLE_FILES[@]}"; do curl -fsSL "$TABLE_URL/$f" -o "$dest/$f.part" && mv "$dest/$f.part" "$dest/$f"; done
    curl -fsSL "https://raw.githubusercontent.com/MEPP-team/PCQM/master/LICENSE.md" -o "$dest/LICENSE-MPL2.txt" || true
  fi
  echo "$dest"
}

build() {
  local tables="$1"
  log "configuring in $BUILD_DIR (tables: $tables)"
  cmake -S "$ROOT" -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DQM3D_DEFAULT_DATA_DIR="$tables" >/dev/null
  log "building with $JOBS jobs"
  cmake --build "$BUILD_DIR" -j "$JOBS"
}

# The Python package: installed for Debian's python3 (/usr/local/lib/python3.X/dist-packages)
# when run as root; otherwise the PYTHONPATH line to use it from the build tree.
install_python() {
  if [ ! -d "$BUILD_DIR/python/qm3d" ]; then
    log "the Python package was not built (pybind11-dev / python3-dev missing?)"
    return
  fi
  if [ "$(id -u)" -eq 0 ] && [ -z "${QM3D_SKIP_PYTHON_INSTALL:-}" ]; then
    cmake --install "$BUILD_DIR" --component python >/dev/null
    log "Python package installed: /usr/bin/python3 -c 'import qm3d' works"
  else
    log "Python package built; use it with: export PYTHONPATH=$BUILD_DIR/python"
  fi
}

run_demo() {
  if [ -x "$BUILD_DIR/apps/qm3d" ]; then
    log "demo: qm3d demo"
    "$BUILD_DIR/apps/qm3d" demo
  else
    log "the qm3d executable is not built yet; no demo to run"
  fi
}

install_packages
TABLES="$(find_tables)"
build "$TABLES"
install_python
run_demo
log "done. Run scripts/test.sh to run the test suite."
