#!/usr/bin/env bash
# |H(q,p) - H0| of the paper's ellipse (h = 1e-2) with both impact energy conditions, at several
# horizons: the table in docs/IMPACT_ENERGY.md. Usage: tools/impact_energy/compare.sh [build dir]
set -euo pipefail
bin="${1:-build}/bin/ellipse"
echo "| t-final (s) | condition | impacts | H change | wall time (s) |"
echo "|---:|---|---:|---:|---:|"
for T in 10 100 1000; do
  for mode in discrete hamiltonian; do
    out=$("$bin" --t-final "$T" --impact-energy "$mode" --quiet --no-output)
    imp=$(echo "$out" | awk '/^impacts:/ {print $2}')
    dH=$(echo "$out" | awk '/^energy H/ {print $NF}')
    wt=$(echo "$out" | awk '/^wall time/ {print $3}')
    echo "| $T | $mode | $imp | $dH | $wt |"
  done
done
