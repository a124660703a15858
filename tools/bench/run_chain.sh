#!/bin/sh
# Impact steps on the FPU-beta chain between walls (issue 28): bench/chain_impacts.f90 with the
# dense Newton matrices, with the declared bandwidth 1 (band block + Schur-complement border), and
# with that band and the model's banded Hessian callback (bandcb),
# OpenBLAS on one thread; then callgrind's instruction counts of the run at n = 128 and the
# functions that take the most of them. Writes docs/bench/chain.md. Times are medians of
# individually timed steps and move with the machine's load: compare within one run.
#
#   tools/bench/run_chain.sh               # uses $BUILD_DIR (default: build), target built here
set -eu
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD_DIR=${BUILD_DIR:-$ROOT/build}
OUT=${OUT:-$ROOT/docs/bench/chain.md}
NS=${NS:-"32 128 256"}
cmake --build "$BUILD_DIR" --target vci_bench_chain_impacts -j1 >/dev/null
EXE="$BUILD_DIR/bin/vci_bench_chain_impacts"
export OPENBLAS_NUM_THREADS=1
{
  echo "# The FPU chain between walls: regular and impact steps"
  echo
  echo "Written by \`tools/bench/run_chain.sh\` ($(date -u +%Y-%m-%d), $(uname -m), $(nproc) cores)."
  echo "\`OPENBLAS_NUM_THREADS=1 vci_bench_chain_impacts [banded|bandcb] $NS\` (bench/chain_impacts.f90): midpoint"
  echo "from L, analytic Hessians, \`hamiltonian\` impacts, h = 0.01, T = 2, walls |x_i| <= 0.6."
  echo
  # shellcheck disable=SC2086
  "$EXE" $NS
  echo
  # shellcheck disable=SC2086
  "$EXE" banded $NS | tail -n +3
  echo
  # shellcheck disable=SC2086
  "$EXE" bandcb $NS | tail -n +3
  echo
  echo "Instructions (valgrind --tool=callgrind) of the whole run at n = 128, inclusive, by function:"
  echo
  for mode in dense banded bandcb; do
    arg=""; [ "$mode" != dense ] && arg=$mode
    f=$(mktemp)
    # shellcheck disable=SC2086
    valgrind --tool=callgrind --callgrind-out-file="$f" "$EXE" $arg 128 >/dev/null 2>&1
    echo "$mode:"
    echo
    echo '```'
    callgrind_annotate --inclusive=yes "$f" 2>/dev/null | grep -E 'PROGRAM TOTALS|resolve_impacts|MOD_advance|dgetrf_|dgbtrf_|step_jacobian|linear_solve|lagrangian_hessians|lagrangian_band_hessians|MOD_substep ' | sed 's/ \[.*\]//'
    echo '```'
    echo
    rm -f "$f"
  done
  echo "With the band declared the LU factorisations leave the profile, Newton's matrix is zeroed,"
  echo "filled and sized on the band and border only, each wall's gradient comes from the model's"
  echo "gap_gradient when first needed, and stage 1 is solved on the wall the chord crosses first (then"
  echo "only on walls already crossed there. \"1, cb\" (bandcb) adds the model's banded Hessian callback"
  echo "(hessians_band): no n x n Hessian block is formed or checked. Larger n, fitted exponents:"
  echo "docs/bench/chain_scaling.md; what is still allocated n x n: docs/DESIGN.md, \"Structured Newton matrices\"."
} >"$OUT"
echo "wrote $OUT"
