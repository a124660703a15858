#!/bin/bash
# Runs the test ensemble (with members that fail on purpose) for several numbers of ranks, threads
# and chunks, verifies each file against in-memory runs, and checks with h5py that all files hold
# bitwise the same /members.
# Usage: run_matrix.sh DRIVER PYTHON WORKDIR "R:T:C ..." [MPIEXEC ARGS... NUMPROC_FLAG]
#   R:T:C = ranks, OpenMP threads, chunk (0: automatic). Without MPIEXEC every R must be 1.
set -euo pipefail
driver=$1 py=$2 work=$3 cases=$4
shift 4
here=$(cd "$(dirname "$0")" && pwd)
launcher=("$@")
if [ ${#launcher[@]} -gt 0 ] && [ "$(id -u)" -eq 0 ]; then
  launcher=("${launcher[0]}" --allow-run-as-root "${launcher[@]:1}")
fi
rm -rf "$work"
mkdir -p "$work"
files=()
for c in $cases; do
  IFS=: read -r np nt ch <<< "$c"
  f="$work/r${np}_t${nt}_c${ch}.h5"
  echo "== $np rank(s), $nt thread(s), chunk $ch"
  if [ ${#launcher[@]} -gt 0 ]; then
    OMP_NUM_THREADS=$nt "${launcher[@]}" "$np" "$driver" run "$f" --fail --threads "$nt" --chunk "$ch" --stride 25
  else
    [ "$np" = 1 ] || { echo "FAIL: $np ranks asked for without MPI"; exit 1; }
    "$driver" run "$f" --fail --threads "$nt" --chunk "$ch" --stride 25
  fi
  "$driver" verify "$f" --fail
  files+=("$f")
done
"$py" "$here/check_files.py" same "${files[@]}"
