#!/bin/sh
# Cost of the explicit compositions (issue 32): the library's regular step against a hand-written
# loop of the same composition (bench/composition.f90; the two end in the same bits), and the
# walled run's extra cost per impact step. Writes docs/bench/composition.md: callgrind instructions
# per step (reproducible) and wall times (best of 5; the impact-step ratio as the median of 5
# back-to-back pairs with its range: they move with the machine's load).
#
#   tools/bench/run_composition.sh            # uses $BUILD_DIR (default: build), target built here
set -eu
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD_DIR=${BUILD_DIR:-$ROOT/build}
OUT=${OUT:-$ROOT/docs/bench/composition.md}
cmake --build "$BUILD_DIR" --target vci_bench_composition -j1 >/dev/null
EXE="$BUILD_DIR/bin/vci_bench_composition"
N=200000
{
  echo "# Explicit compositions: cost of a step"
  echo
  echo "Written by \`tools/bench/run_composition.sh\` ($(date -u +%Y-%m-%d), $(uname -m), $(nproc) cores). Pendulum"
  echo "(n = 1), θ(0) = 0, θ'(0) = 4, h = 0.01, $N steps; the walled run (walls ±1 rad) has 3520 impacts."
  echo "Instructions per step by \`valgrind --tool=callgrind --toggle-collect='*run_timed*'\`. \"integrate\": the"
  echo "library run without an observer (the steps before the last in one call, H at the end); \"step()\":"
  echo "the caller stepping one by one (the general path, H every step); \"hand\": the same composition"
  echo "written out in the bench (the three end in the same bits). \"Walled regular\": walls at ±2 rad,"
  echo "never reached (every walled step samples the gaps at the s − 1 internal stages). \"Impact step\":"
  echo "the run with walls at ±1 rad over the never-reached one, per impact step, in walled regular steps."
  echo
  echo "| order | stages | integrate / step | step() / step | hand / step | integrate / hand | step() / hand | walled regular / free | impact step / walled regular step |"
  echo "|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
  for o in 2 4 6 8 10; do
    for w in lib step hand walls far; do
      ir=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null --toggle-collect='*run_timed*' \
             "$EXE" --profile $w $o 2>&1 | awk '/Collected/ {print $4}')
      eval "ir_$w=$ir"
    done
    case $o in 2) s=1;; 4) s=3;; 6) s=9;; 8) s=17;; 10) s=35;; esac
    awk -v o=$o -v s=$s -v l=$ir_lib -v st=$ir_step -v hd=$ir_hand -v w=$ir_walls -v f=$ir_far -v n=$N 'BEGIN {
      imp = 3520; printf "| %d | %d | %d | %d | %d | %.2f | %.2f | %.2f | %.1f |\n", o, s, l/n, st/n, hd/n, l/hd, st/hd, f/l, (w - f*(n-imp)/n)/imp/(f/n) }'
  done
  echo
  echo "The FPU-β chain (n = 32, unit masses, β = 1, lowest mode of amplitude 0.5, 2000 steps) and Kepler"
  echo "(n = 2, e = 0.44 from pericentre, 100000 steps), no walls, h = 0.01: instructions per step of"
  echo "integrate and of the hand loop (\`--profile lib|hand <order> chain|kepler\`; the force is one"
  echo "routine that the model's callback and the hand loop both call; same bits checked below)."
  echo
  echo "| order | chain: integrate / step | chain: hand / step | chain: integrate / hand | Kepler: integrate / step | Kepler: hand / step | Kepler: integrate / hand |"
  echo "|---:|---:|---:|---:|---:|---:|---:|"
  for o in 2 4 6 8 10; do
    for sc in chain kepler; do
      for w in lib hand; do
        ir=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null --toggle-collect='*run_timed*' \
               "$EXE" --profile $w $o $sc 2>&1 | awk '/Collected/ {print $4}')
        eval "ir_${sc}_$w=$ir"
      done
    done
    awk -v o=$o -v cl=$ir_chain_lib -v ch=$ir_chain_hand -v kl=$ir_kepler_lib -v kh=$ir_kepler_hand 'BEGIN {
      printf "| %d | %d | %d | %.2f | %d | %d | %.2f |\n", o, cl/2000, ch/2000, cl/ch, kl/100000, kh/100000, kl/kh }'
  done
  echo
  echo "Targets (issue 32 item 6): integrate / hand ≤ 1.3 and impact step / walled regular step ≤ 4, read"
  echo "from the instruction columns above."
  echo
  echo "Wall times (best of 5; the impact-step ratio: median and range of 5 back-to-back pairs, a difference"
  echo "of two run times of which the impact steps are 1.8 %: at this size it is load noise, the instruction"
  echo "counts above are the measure; same bits checked):"
  echo
  echo '```'
  for o in 2 6 10; do "$EXE" $o; "$EXE" --scenes $o; done
  echo '```'
  echo
  echo "Stage 1 on a large chain (issue 32 item 1): the FPU-β chain of n = 1024 particles between walls at"
  echo "±0.6 from the results' fpu_walls start, T = 0.25, h = 0.005 (50 steps, 86 impacts), and the same run"
  echo "without walls: gradients (composed stages) per impact beyond the free run's, CPU per impact"
  echo "(\`vci_bench_composition --chainwalls <order> 1024 0.25 0.005\`; one run each, times move with the load):"
  echo
  echo '```'
  for o in 2 4 6 8 10; do "$EXE" --chainwalls $o 1024 0.25 0.005; done
  echo '```'
  echo
  echo "Error against CPU time on the walled pendulum over 10 s (18 impacts) from the exact start, final"
  echo "error against the exact solution (\`vci_bench_composition --sweep\`, best of 7 per run):"
  echo
  echo '```'
  "$EXE" --sweep 2>/dev/null
  echo '```'
} >"$OUT"
cat "$OUT"
