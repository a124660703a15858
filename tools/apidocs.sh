#!/usr/bin/env bash
# The API reference (docs/BUILD.md, "API reference"): Doxygen over include/vci.h and the public
# Fortran modules, configured by docs/Doxyfile, HTML into OUTDIR/html. Fails (exit 1) on any
# warning -- an undocumented public symbol, a doc comment Doxygen cannot read -- and on anything
# Doxygen's parsers report, listing it. Usage: tools/apidocs.sh [OUTDIR]   (default: build/apidocs)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/build/apidocs}
if ! command -v doxygen > /dev/null; then
  echo "apidocs: doxygen not found (Debian: apt-get install doxygen; tools/install-deps.sh installs it)" >&2
  exit 2
fi
version=$(sed -n 's/^project(vci VERSION \([0-9.]*\).*/\1/p' "$root/CMakeLists.txt")
mkdir -p "$out"
out=$(cd "$out" && pwd)
rm -rf "$out/html"
log="$out/warnings.log"
cd "$root"
status=0
{ cat docs/Doxyfile
  echo "OUTPUT_DIRECTORY = $out"
  echo "WARN_LOGFILE = $log"
  echo "PROJECT_NUMBER = $version"
} | doxygen - > "$out/doxygen.out" 2>&1 || status=$?
if [ -s "$log" ] || [ -s "$out/doxygen.out" ] || [ "$status" -ne 0 ]; then
  cat "$log" "$out/doxygen.out" >&2
  echo "apidocs: FAILED: $(grep -c . "$log" || true) warnings (doxygen exit status $status); see above" >&2
  exit 1
fi
echo "apidocs: $out/html/index.html (vci $version, no warnings)"
