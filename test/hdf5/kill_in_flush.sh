#!/bin/bash
# A kill at every write of a run's file (enospc_shim with VCI_ENOSPC_KILL: SIGKILL at the (W+1)-th
# write to the .h5 file, W = 1, 2, ...), then --from on the killed file. A kill inside a flush can
# leave a dataset's new extent on disk while the chunk of its new rows lies beyond the file's end
# of allocation; the restart reader must take the impacts before it (vci_hdf5_output's
# readable_impacts_before) instead of refusing the file ("cannot read /impacts/step": 8 of the 415
# kill points of this run, the first impact's flush, before). Every --from must end with a status
# (0, or 1 with a message), never a crash. Other refusals are counted, not failed: a kill inside
# HDF5's own metadata flush can leave a file HDF5 cannot open (docs/OUTPUT.md, "Killed runs").
# With a fourth argument `append` (not a test: a count for docs/OUTPUT.md) the restart is
# `--from FILE --append` and only a crash fails.
# Usage: kill_in_flush.sh PENDULUM_EXE SHIM_SO WORKDIR [append]
set -u
exe=$1; shim=$2; dir=$3; mode=${4:-from}
mkdir -p "$dir"
fail() { echo "FAIL: $*"; exit 1; }
run=(--h 1e-4 --t-final 1.5 --flush-every 1000 --quiet --no-progress)
rm -f "$dir"/writes.*
LD_PRELOAD=$shim VCI_ENOSPC_LOG="$dir/writes" "$exe" "${run[@]}" --output "$dir/whole.h5" > /dev/null 2>&1 \
  || fail "the run without a kill"
total=$(grep -c '^write' "$dir"/writes.*)
[ "$total" -gt 100 ] || fail "only $total writes counted"
restarted=0; refused=0; impacts_refused=0
for w in $(seq 1 "$total"); do
  f=$dir/killed.h5
  rm -f "$f"
  (LD_PRELOAD=$shim VCI_ENOSPC_OPEN=1 VCI_ENOSPC_WRITES=$w VCI_ENOSPC_KILL=1 "$exe" "${run[@]}" --output "$f" \
     > /dev/null 2>&1; exit 0) 2> /dev/null
  if [ "$mode" = append ]; then
    "$exe" --from "$f" --append --t-final 1.6 --quiet --no-progress > "$dir/from.log" 2>&1; rc=$?
  else
    "$exe" --from "$f" --t-final 1.6 --no-output --quiet > "$dir/from.log" 2>&1; rc=$?
  fi
  case $rc in
    0) restarted=$((restarted + 1)) ;;
    1|2) refused=$((refused + 1))
       if grep -q 'cannot read /impacts/step' "$dir/from.log"; then
         impacts_refused=$((impacts_refused + 1)); echo "killed at write $((w + 1)): $(tail -1 "$dir/from.log")"
       fi ;;
    *) cat "$dir/from.log"; fail "killed at write $((w + 1)): --from ended with exit status $rc" ;;
  esac
done
echo "kill_in_flush ($mode): $total kill points: $restarted restart, $refused refused with a message"
[ "$mode" = append ] && exit 0
[ "$impacts_refused" = 0 ] || fail "$impacts_refused killed files refused for their unreadable last impacts"
[ "$restarted" -ge $((total * 9 / 10)) ] || fail "fewer than 9 in 10 killed files restart"
