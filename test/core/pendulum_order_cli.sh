#!/bin/bash
# Issue 25, item 6: the pendulum example with a scheme built from L starts from the exact
# (q(0), p(0)) and its impact times converge at the scheme's order to the exact ones.
# Usage: pendulum_order_cli.sh PENDULUM ORDER "H1 H2 ..." FLAGS...
# Exact impact times: t1 + k * transit (tools/reference/print_references.f90, from mpmath quadrature in
# tools/reference/references.py). Observed order = least-squares slope of log(max impact-time error)
# against log(h); passes when within 0.3 of ORDER. The example prints t to 12 decimals (5e-13).
exe=$1; order=$2; hs=$3; shift 3
t1=1.23260159696178838650314
tr=1.315919052795016419565854
rows=""
for h in $hs; do
  out=$("$exe" --no-output --t-final 4 --h "$h" "$@") || { echo "FAIL: $exe --h $h $* failed"; echo "$out"; exit 1; }
  echo "$out" | grep -q '^start: exact' || { echo "FAIL: the summary does not say the exact start was used"; echo "$out"; exit 1; }
  times=$(echo "$out" | sed -n 's/^impact [0-9]* t=\([^ ]*\).*/\1/p' | tr '\n' ' ')
  err=$(echo "$times" | awk -v t1=$t1 -v tr=$tr '{ e = 0; for (k = 1; k <= NF; k++) { d = $k - (t1 + (k - 1) * tr); if (d < 0) d = -d; if (d > e) e = d }; if (NF != 3) e = -1; printf "%.3e", e }')
  [[ "$err" == "-1.000e+00" ]] && { echo "FAIL: h = $h: expected 3 impacts, got: $times"; exit 1; }
  echo "h = $h  impact times: $times  max error $err"
  rows="$rows $h $err"
done
echo "$rows" | awk -v p=$order '{ n = 0; for (i = 1; i < NF; i += 2) { x[n] = log($i); y[n] = log($(i + 1)); n++ }
  sx = 0; sy = 0; for (i = 0; i < n; i++) { sx += x[i]; sy += y[i] }; mx = sx / n; my = sy / n
  num = 0; den = 0; for (i = 0; i < n; i++) { num += (x[i] - mx) * (y[i] - my); den += (x[i] - mx)^2 }
  s = num / den; printf "observed order %.2f over %d step sizes (expected %d +- 0.3)\n", s, n, p
  if (s < p - 0.3 || s > p + 0.3) { print "FAIL"; exit 1 } }'
