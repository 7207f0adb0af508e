#!/usr/bin/env bash
# The committed data and documentation name the reference tools by repository and commit, never
# by how to build them (DEVELOPERS.md, "Fixed choices"): no compiler or build-system command line
# in a data file's header, a table or a document. Scripts that build qm3d itself live in scripts/
# and are not scanned.
#   check_no_build_recipes.sh SOURCE_DIR
set -euo pipefail
root="$1"
pattern='(g\+\+|clang\+\+|\bgcc\b|\bc\+\+)[[:space:]]+-|-fopenmp|-I/usr/include|cmake[[:space:]]+(-S|-B|--build|\.\.)|\bmake[[:space:]]+-j'
found=$(cd "$root" && grep -rnIE "$pattern" tests/data data docs bench/README* 2>/dev/null || true)
if [ -n "$found" ]; then
  echo "build command lines in committed data or documents:" >&2
  echo "$found" >&2
  exit 1
fi
echo "no build command lines in tests/data, data, docs"
