#!/usr/bin/env bash
# The HTML report in a real browser: reports written by qm3d are opened in headless Chromium
# (software WebGL, no network) and checked: no script error or failed resource (the page's status
# element), every view drawn (screenshot pixels), and the heat map hot where the distortion is.
#
#   tests/report/test_report.sh [QM3D_BINARY] [--screenshot FILE.png]
#
# --screenshot keeps the screenshot of the bundled blob3 pair's report (README's docs/ image).
# Exit 77 (skipped, with a message) when chromium or three.js is missing.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
HERE="$ROOT/tests/report"
QM3D="$ROOT/build/apps/qm3d"
KEEP_SHOT=""
while [ $# -gt 0 ]; do
  case "$1" in
    --screenshot) KEEP_SHOT="$2"; shift 2 ;;
    *) QM3D="$1"; shift ;;
  esac
done
PY=/usr/bin/python3
export PYTHONDONTWRITEBYTECODE=1  # no __pycache__ in the source tree
CHROMIUM="$(command -v chromium || command -v chromium-browser || true)"
THREE="${QM3D_THREE_JS:-/usr/share/javascript/three/three.min.js}"
if [ -z "$CHROMIUM" ]; then
  echo "test_report: skipped: chromium not found (Debian package chromium)"; exit 77
fi
if [ ! -f "$THREE" ]; then
  echo "test_report: skipped: $THREE not found (Debian package libjs-three)"; exit 77
fi
[ -x "$QM3D" ] || { echo "test_report: $QM3D: not built"; exit 1; }
QM3D="$(realpath "$QM3D")"  # the blob3 report below runs from the source root

WORK="$(mktemp -d /tmp/qm3d-report-test.XXXXXX)"
trap 'rm -rf "$WORK"' EXIT
START=$SECONDS
fail() { echo "test_report: FAIL: $*"; exit 1; }

# Opens a page once: its DOM after the scripts ran, a screenshot and the browser's log.
open_page() {  # FILE.html NAME
  timeout 120 "$CHROMIUM" --headless=new --no-sandbox --use-angle=swiftshader \
    --enable-unsafe-swiftshader --virtual-time-budget=4000 --window-size=1400,1000 \
    --hide-scrollbars --force-device-scale-factor=1 --user-data-dir="$WORK/profile" \
    --host-resolver-rules="MAP * ~NOTFOUND" --proxy-server=127.0.0.1:9 \
    --enable-logging=stderr --v=0 \
    --screenshot="$WORK/$2.png" --dump-dom "file://$1" >"$WORK/$2.dom" 2>"$WORK/$2.log" \
    || fail "chromium failed on $1 (log: $(tail -3 "$WORK/$2.log"))"
  if grep -E ':CONSOLE|Uncaught|Failed to load resource|net::ERR_' "$WORK/$2.log" | grep -v dbus; then
    fail "$2: the browser logged the errors above"
  fi
  if grep -Eq '(src|href)="(https?:)?//' "$1"; then fail "$1 refers to the network"; fi
}

check_report() {  # FILE.html NAME HOT_SIDE
  open_page "$1" "$2"
  echo "test_report: $2 ($(du -k "$1" | cut -f1) KiB)"
  "$PY" "$HERE/check_report.py" "$WORK/$2.dom" "$WORK/$2.png" --hot-side "$3" \
    || fail "$2 (screenshot kept in $WORK only while running)"
}

"$PY" "$HERE/make_stimuli.py" "$WORK/stimuli"
S="$WORK/stimuli"

score_of() { "$PY" -c 'import json, sys; print(json.load(sys.stdin)["score"])'; }

# CMDM on a mesh pair with colour noise on the x > 0 half, drawn with --range 0,SCORE: the
# elements of the noisy half (about twice the mean) are red, the others blue.
cmdm_score="$("$QM3D" cmdm "$S/mesh_ref.ply" "$S/mesh_dist.ply" -q --json | score_of)"
"$QM3D" cmdm "$S/mesh_ref.ply" "$S/mesh_dist.ply" -q --report "$WORK/cmdm.html" \
  --range "0,$cmdm_score" >/dev/null
grep -q "\"range\":\[0.0,$cmdm_score\]" "$WORK/cmdm.html" || fail "cmdm: --range not in the report"
check_report "$WORK/cmdm.html" cmdm right
# PCQM on a cloud pair with the same half noise.
pcqm_score="$("$QM3D" pcqm "$S/cloud_ref.ply" "$S/cloud_dist.ply" -q --radius 0.02 --json | score_of)"
"$QM3D" pcqm "$S/cloud_ref.ply" "$S/cloud_dist.ply" -q --radius 0.02 --report "$WORK/pcqm.html" \
  --range "0,$pcqm_score" >/dev/null
check_report "$WORK/pcqm.html" pcqm right
# qm3d report (every metric) on a bundled pair, each object on its own scale, run from the
# source root with relative paths: the report (and README's screenshot of it) shows the inputs as
# given, not this machine's directories.
(cd "$ROOT" && "$QM3D" report data/meshes/blob3_ref.off data/meshes/blob3_bothnoise.off -q \
  -o "$WORK/blob3.html" >/dev/null)
grep -q '"reference":"data/meshes/blob3_ref.off"' "$WORK/blob3.html" \
  || fail "blob3: the report does not show the reference as given (data/meshes/blob3_ref.off)"
grep -q "$ROOT" "$WORK/blob3.html" && fail "blob3: the report holds the absolute path $ROOT"
check_report "$WORK/blob3.html" blob3 none
[ -z "$KEEP_SHOT" ] || cp "$WORK/blob3.png" "$KEEP_SHOT"

# batch --report-dir: one report per pair and an index sorted by score, linking to them.
printf 'reference,distorted,metric\n%s,%s,cmdm\n%s,%s,pcqm\n' \
  "$S/mesh_ref.ply" "$S/mesh_dist.ply" "$S/cloud_ref.ply" "$S/cloud_dist.ply" >"$WORK/list.csv"
"$QM3D" batch "$WORK/list.csv" -o "$WORK/results.csv" -q --report-dir "$WORK/reports" --radius 0.02
[ "$(ls "$WORK/reports"/*.html | wc -l)" -eq 3 ] || fail "batch: expected 2 reports and index.html"
open_page "$WORK/reports/index.html" index
grep -q '<div id="qm3d-status" hidden="">ok</div>' "$WORK/index.dom" || fail "index: status not ok"
for link in $(grep -o 'href="[^"]*\.html"' "$WORK/reports/index.html" | cut -d'"' -f2); do
  [ -f "$WORK/reports/$link" ] || fail "index links to a missing $link"
done
[ "$(grep -o 'href="[^"]*\.html"' "$WORK/reports/index.html" | wc -l)" -eq 2 ] || fail "index: expected 2 links"
check_report "$WORK/reports/$(grep -o 'href="mesh_dist[^"]*"' "$WORK/reports/index.html" | cut -d'"' -f2)" batch_cmdm none

# A missing three.js: one line naming the file, exit code 2, nothing written.
if "$QM3D" cmdm "$S/mesh_ref.ply" "$S/mesh_dist.ply" --report "$WORK/none.html" \
     --three-js "$WORK/missing.js" >/dev/null 2>"$WORK/err.txt"; then
  fail "a missing --three-js was accepted"
fi
[ "$(wc -l <"$WORK/err.txt")" -eq 1 ] && grep -q "missing.js: three.js not found" "$WORK/err.txt" \
  || fail "missing three.js: $(cat "$WORK/err.txt")"
[ ! -e "$WORK/none.html" ] || fail "a report was written without three.js"

echo "test_report: all passed in $((SECONDS - START)) s"
