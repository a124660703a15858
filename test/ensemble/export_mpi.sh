#!/bin/bash
# The installed MPI-enabled vci: install the build into a temporary prefix, then build a downstream
# program (a) with find_package(vci) and (b) with mpifort and pkg-config, and run each on 2 ranks.
# Usage: export_mpi.sh BUILD_DIR WORK_DIR CMAKE MPIFORT MPIEXEC ARGS... NUMPROC_FLAG
set -euo pipefail
build=$1 work=$2 cmake=$3 mpifort=$4
shift 4
here=$(cd "$(dirname "$0")" && pwd)
launcher=("$@")
[ "$(id -u)" -eq 0 ] && launcher=("${launcher[0]}" --allow-run-as-root "${launcher[@]:1}")
rm -rf "$work"
mkdir -p "$work"
prefix="$work/prefix"
"$cmake" --install "$build" --prefix "$prefix" > "$work/install.log"
pc=$(find "$prefix" -name vci.pc | head -n1)
libdir=$(cd "$(dirname "$pc")/.." && pwd)
export PKG_CONFIG_PATH="$libdir/pkgconfig"
[ "$(pkg-config --variable=with_mpi vci)" = 1 ] || { echo "FAIL: vci.pc does not say with_mpi=1"; exit 1; }

echo "=== (a) find_package(vci)"
"$cmake" -S "$here/export_mpi" -B "$work/a" -DCMAKE_PREFIX_PATH="$prefix" > "$work/a.log" || { cat "$work/a.log"; exit 1; }
"$cmake" --build "$work/a" >> "$work/a.log" || { cat "$work/a.log"; exit 1; }
(cd "$work/a" && "${launcher[@]}" 2 ./ens_export)

echo "=== (b) $mpifort ens_export.F90 \$(pkg-config --cflags --libs vci)"
mkdir -p "$work/b"
(cd "$work/b" && "$mpifort" "$here/export_mpi/ens_export.F90" -o ens_export $(pkg-config --cflags --libs vci) \
   -Wl,-rpath,"$libdir" && "${launcher[@]}" 2 ./ens_export)
