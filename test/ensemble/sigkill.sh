#!/bin/bash
# A killed ensemble: start a long ensemble writing its file, SIGKILL every process once the file
# holds some members, then check that the file opens (h5py), is marked incomplete, and that every
# member it holds is bitwise the member's in-memory run.
# Usage: sigkill.sh DRIVER PYTHON WORKDIR [MPIEXEC ARGS... NUMPROC_FLAG]   (MPI: 2 ranks)
set -euo pipefail
driver=$1 py=$2 work=$3
shift 3
here=$(cd "$(dirname "$0")" && pwd)
launcher=("$@")
if [ ${#launcher[@]} -gt 0 ] && [ "$(id -u)" -eq 0 ]; then
  launcher=("${launcher[0]}" --allow-run-as-root "${launcher[@]:1}")
fi
rm -rf "$work"
mkdir -p "$work"
f="$work/killed.h5"
# ~5000 members of 2000 steps: minutes of work, killed after a few chunks
args=(run "$f" --members 5000 --nsteps 2000 --threads 1 --chunk 4)
if [ ${#launcher[@]} -gt 0 ]; then
  setsid "${launcher[@]}" 2 "$driver" "${args[@]}" > "$work/run.log" 2>&1 &
else
  setsid "$driver" "${args[@]}" > "$work/run.log" 2>&1 &
fi
pid=$!
export HDF5_USE_FILE_LOCKING=FALSE   # read while the writer holds the file
held=0
for _ in $(seq 1 300); do
  sleep 0.2
  # (every rank: the killed file must show the members distributed, and on a loaded machine one
  # rank can run a dozen chunks before the other's first)
  held=$("$py" "$here/check_files.py" every-rank "$f")
  [ "$held" -ge 8 ] && break
  kill -0 "$pid" 2> /dev/null || break
done
if ! kill -0 "$pid" 2> /dev/null; then
  echo "FAIL: the ensemble ended before it was killed"; cat "$work/run.log"; exit 1
fi
# SIGKILL every process of the session started above at once: mpirun and every rank (OpenMPI puts
# each rank in its own process group, but they stay in the session)
kill -9 $(ps -eo pid=,sid= | awk -v s="$pid" '$2 == s { print $1 }')
wait "$pid" 2> /dev/null || true
sleep 0.5
echo "killed after the file held $held members"
unset HDF5_USE_FILE_LOCKING
"$py" "$here/check_files.py" killed "$f"
"$driver" verify "$f" --partial
