#!/bin/bash
# Ensemble scaling on this machine: the ellipse_ensemble workload (MEMBERS perturbations of the
# paper's ellipse over T seconds, h = 1e-2, impact times kept, no trajectories) on 1 and 2 ranks and
# 1 and 2 OpenMP threads, with the file written through (parallel) HDF5; every configuration REPEAT
# times (interleaved), the fastest kept. Writes docs/bench/ensemble_scaling.md and its section of docs/RESULTS.md.
#   bash bench/ensemble/run_scaling.sh [MEMBERS=10000] [T=10] [REPEAT=3]
set -euo pipefail
cd "$(dirname "$0")/../.."
members=${1:-10000} tfinal=${2:-10} repeat=${3:-3}
cmake --preset mpi > /dev/null
cmake --build --preset mpi --target ellipse_ensemble > /dev/null
exe=build-mpi/bin/ellipse_ensemble
work=build-mpi/bench_ensemble
rm -rf "$work"
mkdir -p "$work"
mpirun=(mpirun --oversubscribe)
[ "$(id -u)" -eq 0 ] && mpirun+=(--allow-run-as-root)
export OPENBLAS_NUM_THREADS=1   # members use LAPACK on 3x3 systems: no BLAS threads
common=(--members "$members" --t-final "$tfinal" --stride 0 --impact-cap 64 --quiet)
half=$(( (members + 1) / 2 ))

# name | ranks | threads | extra flags
configs=(
  "memory|1|1|--no-output"
  "r1t1|1|1|"
  "r1t2|1|2|"
  "r2t1|2|1|"
  "r2t1_block|2|1|--chunk $half"
)
uptime > "$work/load_before.txt"
# repetitions outermost: a change of the machine's load then touches every configuration alike
for i in $(seq 1 "$repeat"); do
  for c in "${configs[@]}"; do
    IFS='|' read -r name np nt extra <<< "$c"
    out="$work/$name.h5"
    # CPU seconds (user + system, every rank) beside the wall time the program reports
    TIMEFORMAT='%U %S'
    if [ "$np" = 1 ]; then
      { time OMP_NUM_THREADS=$nt "$exe" "${common[@]}" --threads "$nt" --output "$out" $extra \
          > "$work/$name.$i.log" ; } 2> "$work/$name.$i.cpu"
    else
      { time OMP_NUM_THREADS=$nt "${mpirun[@]}" -np "$np" "$exe" "${common[@]}" --threads "$nt" --output "$out" \
          $extra > "$work/$name.$i.log" ; } 2> "$work/$name.$i.cpu"
    fi
    echo "$name run $i: $(grep '^wall time' "$work/$name.$i.log"), cpu (user sys) $(cat "$work/$name.$i.cpu")"
  done
done
uptime > "$work/load_after.txt"
/usr/bin/python3 bench/ensemble/summarize.py "$work" "$members" "$tfinal" "$repeat" docs/bench/ensemble_scaling.md docs/RESULTS.md
