#!/bin/bash
# The ensemble example: one process and (with MPI) two ranks, or (without MPI) one and two
# threads, write files that h5py reads with bitwise the same /members and /analysis; the
# unperturbed member has as many impacts as the plain ellipse example over the same time.
# Usage: example.sh ELLIPSE_ENSEMBLE ELLIPSE PYTHON WORKDIR [MPIEXEC ARGS... NUMPROC_FLAG]
set -euo pipefail
exe=$1 ellipse=$2 py=$3 work=$4
shift 4
here=$(cd "$(dirname "$0")" && pwd)
launcher=("$@")
if [ ${#launcher[@]} -gt 0 ] && [ "$(id -u)" -eq 0 ]; then
  launcher=("${launcher[0]}" --allow-run-as-root "${launcher[@]:1}")
fi
rm -rf "$work"
mkdir -p "$work"
args=(--members 41 --t-final 20 --quiet)
OMP_NUM_THREADS=2 "$exe" "${args[@]}" --output "$work/one.h5" | tee "$work/one.log"
if [ ${#launcher[@]} -gt 0 ]; then
  OMP_NUM_THREADS=1 "${launcher[@]}" 2 "$exe" "${args[@]}" --output "$work/two.h5" | tee "$work/two.log"
else
  OMP_NUM_THREADS=1 "$exe" "${args[@]}" --output "$work/two.h5" > "$work/two.log"
fi
"$py" "$here/check_files.py" same "$work/one.h5" "$work/two.h5"
h5dump -H "$work/two.h5" > "$work/h5dump.txt" || { echo "FAIL: h5dump cannot read the file"; exit 1; }
grep -q 'DATASET "status"' "$work/h5dump.txt" || { echo "FAIL: h5dump shows no /members/status"; exit 1; }
# the printed numbers are the same too (all but the wall time and the file name)
diff <(grep -v -e '^wall time' -e '^file:' -e ' rank(s)' "$work/one.log") \
     <(grep -v -e '^wall time' -e '^file:' -e ' rank(s)' "$work/two.log")
mine=$(sed -n 's/^unperturbed run: \([0-9]*\) impacts$/\1/p' "$work/one.log")
plain=$("$ellipse" --t-final 20 --no-output --quiet | sed -n 's/^impacts: *\([0-9]*\).*/\1/p')
echo "unperturbed member: $mine impacts; ellipse example: $plain"
[ -n "$mine" ] && [ "$mine" = "$plain" ] || { echo "FAIL: impact counts differ"; exit 1; }
grep -q '^largest Lyapunov exponent: *[0-9.]* +-' "$work/one.log" || { echo "FAIL: no Lyapunov estimate"; exit 1; }
