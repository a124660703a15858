#!/bin/bash
# Issue 25 item 5: vci's Lobatto (constraints at the nodes) against CVODE-Adams on the paper's
# nonholonomic pendulum, at every error level 1e-4 ... 1e-10, in one run on one machine.
#
#   bench/nonholo_vs_cvode.sh            # writes its section of docs/bench/lobatto.md
#   OUT=/tmp/x.md bench/nonholo_vs_cvode.sh
#
# It builds the results drivers of tools/results (read-only: their own CMake project, in
# $RESULTS_BUILD) and bench/lobatto_nonholo.f90 (in $BUILD_DIR), then, back to back:
#   1. cvode_results_driver sweep (pendulum)                    rtol = atol = 1e-3 ... 1e-13
#   2. vci_results_driver sweep vci-lobatto (pendulum)          s = 1 ... 4, the report's step family
#   3. vci_bench_lobatto_nonholo S H 1 whole RTOL               s = 3, 4 at step sizes between the
#                                                               family's (timed as the driver does),
#                                                               Newton rtol 1e-14 (the report's), 1e-10,
#                                                               1e-8, 1e-6: swept as CVODE's tol is
#   4. cvode_results_driver sweep again; CVODE's cost per tolerance is the mean of the two sweeps
# Errors: max-norm of the configuration error at T = 5 s against the exact reference
# (`vci_results_driver reference`). CPU times are medians of repeats (>= 0.1 s each); compare the
# ratios of one run only, the machine is shared.
set -eu
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD_DIR=${BUILD_DIR:-$ROOT/build-bench}
RESULTS_BUILD=${RESULTS_BUILD:-$BUILD_DIR/results-drivers}
OUT=${OUT:-$ROOT/docs/bench/lobatto.md}
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
export OPENBLAS_NUM_THREADS=1

cmake -S "$ROOT/tools/results" -B "$RESULTS_BUILD" -DVCI_ROOT="$ROOT" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$RESULTS_BUILD" -j1 --target vci_results_driver cvode_results_driver >/dev/null
cmake -S "$ROOT" -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release \
  -DVCI_BUILD_BENCH=ON -DVCI_BUILD_TESTS=OFF -DVCI_BUILD_EXAMPLES=OFF >/dev/null
cmake --build "$BUILD_DIR" -j1 --target vci_bench_lobatto_nonholo >/dev/null
BENCH="$BUILD_DIR/bin/vci_bench_lobatto_nonholo"

"$RESULTS_BUILD/vci_results_driver" reference "$WORK/ref.json" >/dev/null
"$RESULTS_BUILD/cvode_results_driver" sweep "$WORK/cvode1.csv" pendulum >/dev/null
"$RESULTS_BUILD/vci_results_driver" sweep "$WORK/vci.csv" vci-lobatto pendulum >/dev/null
: >"$WORK/fine.txt"
# N steps over T = 5 s: h = 5/N between the family's 0.1, 0.07, 0.05, 0.03, 0.02, 0.01
for rtol in 1e-14 1e-10 1e-8 1e-6; do
  for s in 3 4; do
    for n in 60 65 80 90 110 120 130 140 150 200 300 400; do
      "$BENCH" "$s" "$(awk -v n=$n 'BEGIN { printf "%.17g", 5 / n }')" 1 whole "$rtol" >>"$WORK/fine.txt"
    done
  done
done
"$RESULTS_BUILD/cvode_results_driver" sweep "$WORK/cvode2.csv" pendulum >/dev/null

/usr/bin/python3 "$ROOT/bench/python/nonholo_vs_cvode.py" "$WORK" "$OUT" \
  "$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)$(git -C "$ROOT" diff --quiet HEAD 2>/dev/null || echo ' (with uncommitted changes)')" \
  "$(lscpu 2>/dev/null | sed -n 's/^Model name:[[:space:]]*//p' | head -n 1), $(nproc 2>/dev/null || echo '?') cores"
