#!/bin/sh
# The banded FPU chain against n (issue 28 item 4): bench/chain_impacts.f90 with the declared
# bandwidth 1 and the model's banded Hessian callback (`bandcb`: no n x n Hessian block), OpenBLAS on
# one thread, n = 32 .. 4096, each n in a process of its own (so that the peak memory is that n's).
# Prints the table and least-squares exponents of time and memory against n (log-log fits over all
# n), then callgrind's instructions of the whole run at n <= CG_MAX (default 1024; a callgrind run
# at 4096 takes ~40 min), split into the steps' regular part (stepper advance minus resolve_impacts,
# per step) and the impact part (resolve_impacts, per impact step and per impact). Writes
# docs/bench/chain_scaling.md. Times move with the machine's load: compare within one run.
#
#   tools/bench/run_chain_scaling.sh             # uses $BUILD_DIR (default: build)
#   NS="32 64 128" CG_MAX=128 tools/bench/run_chain_scaling.sh
#   WHOLE=1 OUT=/tmp/whole.md tools/bench/run_chain_scaling.sh   # impact stages as whole matrices
#                                                                # (no bordering: the path before it)
#   SINGLE=1 OUT=docs/bench/chain_single_impact.md tools/bench/run_chain_scaling.sh
#        # a start where only the first mass meets a wall: one impact per impact step
#   EXE=/path/to/old/vci_bench_chain_impacts OUT=/tmp/before.md tools/bench/run_chain_scaling.sh
#        # another build's executable (before/after comparisons; nothing is rebuilt)
set -eu
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD_DIR=${BUILD_DIR:-$ROOT/build}
OUT=${OUT:-$ROOT/docs/bench/chain_scaling.md}
NS=${NS:-"32 64 128 256 512 1024 2048 4096"}
CG_MAX=${CG_MAX:-1024}
ARGS="bandcb"
[ "${WHOLE:-0}" = 1 ] && ARGS="bandcb whole"
[ "${SINGLE:-0}" = 1 ] && ARGS="$ARGS single"
if [ -n "${EXE:-}" ]; then
  :   # a given executable (e.g. an earlier build's, with its LD_LIBRARY_PATH): not rebuilt
else
  cmake --build "$BUILD_DIR" --target vci_bench_chain_impacts -j1 >/dev/null
  EXE="$BUILD_DIR/bin/vci_bench_chain_impacts"
fi
export OPENBLAS_NUM_THREADS=1
rows=$(mktemp)
for n in $NS; do
  "$EXE" $ARGS "$n" | tail -n 1 >>"$rows"
done
# least-squares slope of log(column) against log(n): fit COLUMN [MIN_N] (awk field of a table row)
fit() {
  awk -F'|' -v c="$1" -v m="${2:-0}" '$2 + 0 >= m { x = log($2); y = log($c); sx += x; sy += y; sxx += x * x; sxy += x * y; k++ }
    END { if (k < 2) { print "-"; exit } printf "%.2f", (k * sxy - sx * sy) / (k * sxx - sx * sx) }' "$rows"
}
{
  echo "# The banded FPU chain against n"
  echo
  echo "Written by \`tools/bench/run_chain_scaling.sh\` ($(date -u +%Y-%m-%d), $(uname -m), $(nproc) cores, commit"
  echo "$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)). \`OPENBLAS_NUM_THREADS=1 vci_bench_chain_impacts $ARGS N\`"
  echo "(bench/chain_impacts.f90), one process per n: the FPU-beta chain between walls |x_i| <= 0.6, midpoint"
  echo "from L, declared bandwidth 1 with the model's \`hessians_band\`, \`hamiltonian\` impacts, h = 0.01,"
  if [ "${SINGLE:-0}" = 1 ]; then
    echo "T = 2, a start where only the first mass meets a wall (x_i = 0.2 sin(2 pi i/(n+1)), v_i = 0,"
    echo "then x_1 = 0.595, v_1 = 2: one impact per impact step). Times: medians of individually timed steps."
  else
    echo "T = 2, docs/RESULTS.md's start scaled to n. Times: medians of individually timed steps."
  fi
  if [ "${WHOLE:-0}" = 1 ]; then
    echo "Impact stages: the whole stage matrix factorised (band block with the alpha/mu border) at every Newton iteration."
  else
    echo "Impact stages: bordered (the sub-step's band block factorised, kept across iterations while they contract, the alpha/mu border by its Schur complement)."
  fi
  echo
  echo "| n | band | steps | impact steps | impacts | regular step (us) | impact step (us) | impact / regular | LU per regular step | LU per impact step | memory growth (MB) | peak memory (MB) |"
  echo "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
  cat "$rows"
  echo
  # fields: 2 n, 6 impacts, 7 regular, 8 impact step, 13 peak memory; per impact = impact step * impact steps / impacts
  per=$(mktemp)
  awk -F'|' '{ printf "|%s|%.6g|\n", $2, $8 * $5 / $6 }' "$rows" >"$per"
  pfit=$(awk -F'|' '{ x = log($2); y = log($3); sx += x; sy += y; sxx += x * x; sxy += x * y; k++ }
    END { printf "%.2f", (k * sxy - sx * sy) / (k * sxx - sx * sx) }' "$per")
  ifit=$(awk -F'|' '{ x = log($2); y = log($6 / $5); sx += x; sy += y; sxx += x * x; sxy += x * y; k++ }
    END { printf "%.2f", (k * sxy - sx * sy) / (k * sxx - sx * sx) }' "$rows")
  echo "Fitted exponents (time or memory ~ n^e, least squares of the logs over n = $(echo $NS | tr ' ' ',')):"
  echo
  echo "| quantity | e |"
  echo "|---|---:|"
  echo "| regular step | $(fit 7) |"
  echo "| impact step | $(fit 8) |"
  echo "| impacts per impact step | $ifit |"
  echo "| impact step per impact (impact step x impact steps / impacts) | $pfit |"
  echo "| peak memory | $(fit 13) |"
  echo "| memory growth over the run, n >= 512 (below it the 12 MB base and page granularity dominate) | $(fit 12 512) |"
  rm -f "$per"
  echo
  echo "Instructions (valgrind --tool=callgrind, whole run, inclusive; regular part = advance -"
  echo "resolve_impacts per step, impact part = resolve_impacts per impact step and per impact):"
  echo
  echo "| n | instructions per step, regular part | per impact step, impact part | per impact | impact part / regular part |"
  echo "|---:|---:|---:|---:|---:|"
  for n in $NS; do
    [ "$n" -le "$CG_MAX" ] || continue
    f=$(mktemp)
    valgrind --tool=callgrind --callgrind-out-file="$f" "$EXE" $ARGS "$n" >/dev/null 2>&1
    adv=$(callgrind_annotate --inclusive=yes "$f" 2>/dev/null | awk '/__vci_stepper_MOD_advance / {gsub(",", "", $1); print $1; exit}')
    res=$(callgrind_annotate --inclusive=yes "$f" 2>/dev/null | awk '/__vci_stepper_MOD_resolve_impacts / {gsub(",", "", $1); print $1; exit}')
    rm -f "$f"
    awk -F'|' -v n="$n" -v adv="$adv" -v res="$res" '$2 + 0 == n {
      reg = (adv - res) / $4; imp = res / $5; per = res / $6
      printf "| %d | %.0f | %.0f | %.0f | %.2f |\n", n, reg, imp, per, imp / reg }' "$rows"
  done
  echo
  met=$(awk -F'|' '$9 + 0 <= 4 { c++ } END { print c + 0 }' "$rows")
  echo "Impacts per impact step ~ n^$ifit; an impact step costs ~ n^$(fit 8) and its cost per impact ~ n^$pfit."
  echo "Issue 28's target of an impact step <= 4 regular steps (impact / regular above) is met at $met of the"
  echo "$(echo $NS | wc -w) sizes: an impact step resolves all its impacts (the column impacts / impact steps), each"
  echo "with a stage 1 (Newton on the band block bordered by alpha, the block refactorised at each iteration) and a"
  echo "stage 2 (hamiltonian: the impulse from the rates along the impulse line where they decide, then the leaving"
  echo "sub-step with chord steps on stage 1's kept block; docs/DESIGN.md, \"The impact step's cost\")."
  echo "Memory: Newton's matrices are kept in band storage with their border apart (vci_banded_matrix),"
  echo "the Hessian blocks are band-sized, and the wall gradients are those of the walls a sub-step"
  echo "examines, in 8 columns of n (no n x n or n x n_gaps array: test band_memory; docs/DESIGN.md,"
  echo "\"Structured Newton matrices\")."
} >"$OUT"
rm -f "$rows"
echo "wrote $OUT"
