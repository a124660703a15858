#!/usr/bin/env bash
# The layer check must fail on an upward use: copy src/ and make each kind of violation once
# (a lower layer using a higher one's module; a missing layer README; a source outside the layer
# folders), and require the check to pass on the untouched copy and to fail on each changed one.
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
check="$here/tools/check_layers.py"
py=/usr/bin/python3
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

fresh() { rm -rf "$work/src"; cp -r "$here/src" "$work/src"; }

fresh
"$py" "$check" "$work/src" > /dev/null || { echo "FAIL: the check rejects the untouched tree"; exit 1; }

expect_failure() {   # $1: what was broken; $2: text the report must contain
  if out="$("$py" "$check" "$work/src")"; then
    echo "FAIL: the check passed with $1"; exit 1
  fi
  grep -q -- "$2" <<< "$out" || { echo "FAIL: no '$2' in the report of $1:"; echo "$out"; exit 1; }
  echo "ok: rejected $1"
}

fresh   # core using the driver (integrate)
sed -i '0,/^  use vci_kinds/s//  use vci_integrator, only: vci_integrator_t\n  use vci_kinds/' "$work/src/core/vci_newton.f90"
expect_failure "core/vci_newton.f90 using vci_integrator" "layer 'core' uses vci_integrator of the higher layer 'integrate'"

fresh   # schemes using the C bindings, written with '::' and upper case
sed -i '0,/^  use vci_kinds/s//  use :: VCI_CAPI_REGISTRY\n  use vci_kinds/' "$work/src/schemes/vci_scheme.f90"
expect_failure "schemes/vci_scheme.f90 using vci_capi_registry" "uses vci_capi_registry of the higher layer 'bindings'"

fresh
rm "$work/src/io/README.md"
expect_failure "io/ without its README" "io: no README.md"

fresh
echo "module stray; end module" > "$work/src/vci_stray.f90"
expect_failure "a source outside the layer folders" "a source outside the layer folders"
echo "check_layers: all four kinds of violation rejected"
