#!/usr/bin/env bash
# Doxygen input filter for preprocessed Fortran (.F90; docs/Doxyfile FILTER_PATTERNS): Doxygen's
# Fortran parser does not run the preprocessor, and two branches of an #ifdef that each open the same
# procedure leave it one `end` short. This keeps the branches the default build compiles (macros
# defined: VCI_HAVE_HDF5; not VCI_HAVE_MPI) and blanks the others and the directive lines, so line
# numbers stay those of the file. Handles #ifdef, #ifndef, #else, #endif (nested).
# Usage: apidocs_fpp.sh FILE
exec awk -v defined="VCI_HAVE_HDF5" '
BEGIN { n = split(defined, d, " "); for (i = 1; i <= n; i++) def[d[i]] = 1; depth = 0; active[0] = 1 }
/^#[ \t]*ifdef[ \t]/  { depth++; parent[depth] = active[depth-1]; cond[depth] = ($2 in def);  active[depth] = parent[depth] && cond[depth]; print ""; next }
/^#[ \t]*ifndef[ \t]/ { depth++; parent[depth] = active[depth-1]; cond[depth] = !($2 in def); active[depth] = parent[depth] && cond[depth]; print ""; next }
/^#[ \t]*else/        { active[depth] = parent[depth] && !cond[depth]; print ""; next }
/^#[ \t]*endif/       { depth--; print ""; next }
{ if (active[depth]) print; else print "" }
' "$1"
