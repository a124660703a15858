#!/usr/bin/env bash
# Issue 3's acceptance: `ellipse --t-final 3 --output f` then `ellipse --backward --from f` prints the
# start state back to 1e-9 (relative, max over q and p). Usage: backward_cli.sh <bin dir> <work dir>
set -euo pipefail
bin=$1; work=$2
mkdir -p "$work" && cd "$work" && rm -f f f.h5 f.csv
"$bin/ellipse" --t-final 3 --output f --quiet > fwd.txt
"$bin/ellipse" --backward --from f --quiet > bwd.txt
grep -q '^status: ok' fwd.txt && grep -q '^status: ok' bwd.txt
# start state of the forward run (2 lines) vs end state of the backward run (2 lines)
start=$(grep -A1 '^start state' fwd.txt | sed 's/.*[qp] =//')
back=$(grep -A1 '^end state' bwd.txt | sed 's/.*[qp] =//')
awk -v a="$start" -v b="$back" 'BEGIN {
  n = split(a, x, " "); m = split(b, y, " "); if (n != m || n == 0) { print "cannot parse"; exit 1 }
  worst = 0
  for (i = 1; i <= n; i++) { d = x[i] - y[i]; if (d < 0) d = -d; s = (x[i] < 0 ? -x[i] : x[i]); if (s < 1) s = 1; if (d / s > worst) worst = d / s }
  printf "largest relative difference between the start and the backward end state: %.3e\n", worst
  exit (worst < 1e-9 ? 0 : 1) }'
