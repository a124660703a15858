#!/usr/bin/env bash
# Run each scene through the Fortran example and the C example and compare the impact lines
# "impact k t=T ...": same count, times within TOL. Usage: compare_impacts.sh F_ELLIPSE C_ELLIPSE
# F_PENDULUM C_PENDULUM. The Fortran examples print t to 12 decimals (so ~5e-13 of rounding);
# the ellipse's C callbacks do the Fortran arithmetic, the pendulum's round differently and 5000
# steps amplify that to ~1e-12.
set -euo pipefail
fail=0
compare() {  # name fortran_exe c_exe tol
  local name=$1 fexe=$2 cexe=$3 tol=$4 ft ct
  ft=$("$fexe" --no-output | sed -n 's/^impact [0-9]* t=\([^ ]*\).*/\1/p')
  ct=$("$cexe" | sed -n 's/^impact [0-9]* t=\([^ ]*\).*/\1/p')
  if [[ -z "$ft" ]]; then echo "FAIL $name: the Fortran example printed no impacts"; fail=1; return; fi
  paste <(echo "$ft") <(echo "$ct") | awk -v name="$name" -v tol="$tol" -v nf="$(echo "$ft" | wc -l)" \
    -v nc="$(echo "$ct" | wc -l)" '
    { d = $1 - $2; if (d < 0) d = -d
      printf "%s impact %d: Fortran t=%s  C t=%s  |diff| = %.2e\n", name, NR, $1, $2, d
      if (!(d <= tol)) { print "FAIL " name ": impact " NR " differs by more than " tol; bad = 1 } }
    END { if (nf != nc) { print "FAIL " name ": " nf " impacts in Fortran, " nc " in C"; bad = 1 }
          exit bad }' || fail=1
}
compare ellipse "$1" "$2" 1e-12
compare pendulum "$3" "$4" 5e-11
exit $fail
