#!/bin/sh
# Regenerate the table of docs/STABILITY.md (between the table markers) from a build directory.
#   tools/stability/regenerate.sh [build-dir]      (default: build)
set -e
build=${1:-build}
root=$(cd "$(dirname "$0")/../.." && pwd)
cmake --build "$build" --target vci_stability_table
"$build/bin/vci_stability_table" > "$build/stability_table.md"
"$(command -v /usr/bin/python3 || command -v python3)" - "$root/docs/STABILITY.md" "$build/stability_table.md" <<'PY'
import sys
doc, table = sys.argv[1], open(sys.argv[2]).read()
text = open(doc).read()
begin, end = '<!-- table begin -->\n', '<!-- table end -->'
i, j = text.index(begin) + len(begin), text.index(end)
open(doc, 'w').write(text[:i] + table + text[j:])
PY
echo "updated $root/docs/STABILITY.md"
