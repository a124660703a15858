#!/usr/bin/env bash
# The export test: install the vci build into a temporary prefix and build, outside the source
# tree, (a) a C program with find_package(vci) (shared and static), (b) a C program with plain
# cc and pkg-config, (c) a modern Fortran program with find_package(vci), (d) a fixed-form
# Fortran 77 program through the legacy entry point with gfortran and pkg-config. Each runs a
# scene and exits nonzero if its numbers are off.
#
# Usage: run_export_test.sh SOURCE_DIR BUILD_DIR WORK_DIR CMAKE C_COMPILER Fortran_COMPILER
set -euo pipefail
src=$1 build=$2 work=$3 cmake=$4 cc=$5 fc=$6
here="$src/test/export"
rm -rf "$work"
mkdir -p "$work"
prefix="$work/prefix"

step() { printf '\n=== %s\n' "$*"; }

step "install into $prefix"
"$cmake" --install "$build" --prefix "$prefix" > "$work/install.log"
for f in include/vci.h; do test -f "$prefix/$f" || { echo "missing $f"; exit 1; }; done
pc=$(find "$prefix" -name vci.pc | head -n1)
cfg=$(find "$prefix" -name vci-config.cmake | head -n1)
ver=$(find "$prefix" -name vci-config-version.cmake | head -n1)
mod=$(find "$prefix" -name vci.mod | head -n1)
for f in "$pc" "$cfg" "$ver" "$mod"; do test -n "$f" || { echo "missing installed file"; cat "$work/install.log"; exit 1; }; done
ls "$(dirname "$pc")"/../libvci.so* "$(dirname "$pc")"/../libvci.a
echo "modules in $(dirname "$mod")"
case "$(dirname "$mod")" in */include/vci/GNU-*|*/include/vci/*-*) ;; *) echo "modules not in a per-compiler directory"; exit 1;; esac
libdir=$(cd "$(dirname "$pc")/.." && pwd)
export PKG_CONFIG_PATH="$libdir/pkgconfig"

step "(a) C with find_package(vci): vci::vci and vci::vci_static"
"$cmake" -S "$here/c_cmake" -B "$work/a" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_C_COMPILER="$cc" > "$work/a.log" \
  || { cat "$work/a.log"; exit 1; }
"$cmake" --build "$work/a" >> "$work/a.log" || { cat "$work/a.log"; exit 1; }
"$work/a/ellipse_shared"
if ldd "$work/a/ellipse_shared" | grep "libvci.so" > /dev/null; then echo "ellipse_shared: linked to libvci.so"; else echo "ellipse_shared does not use libvci.so"; exit 1; fi
"$work/a/ellipse_static"
if ldd "$work/a/ellipse_static" | grep "libvci.so" > /dev/null; then echo "ellipse_static uses libvci.so"; exit 1; fi

step "(b) C with cc and pkg-config: $(pkg-config --cflags --libs vci)"
"$cc" "$here/c_pkgconfig/pendulum.c" -o "$work/pendulum_pc" $(pkg-config --cflags --libs vci) -lm -Wl,-rpath,"$libdir"
"$work/pendulum_pc"

step "(c) modern Fortran with find_package(vci)"
"$cmake" -S "$here/fortran_cmake" -B "$work/c" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_Fortran_COMPILER="$fc" > "$work/c.log" \
  || { cat "$work/c.log"; exit 1; }
"$cmake" --build "$work/c" >> "$work/c.log" || { cat "$work/c.log"; exit 1; }
"$work/c/ellipse_modern"

step "(d) fixed-form Fortran 77 through VCIRUN: $fc ellipse77.f \$(pkg-config --libs vci)"
"$fc" -ffixed-form -std=legacy "$here/legacy/ellipse77.f" -o "$work/ellipse77" $(pkg-config --libs vci) -Wl,-rpath,"$libdir"
"$work/ellipse77"

step "export test passed"
