#!/usr/bin/env bash
# The export test: install the vci build into a temporary prefix and build, outside the source
# tree, (a) a C program with find_package(vci) (shared and static), (b) a C program with plain
# cc and pkg-config, (c) a modern Fortran program with find_package(vci), (d) a fixed-form
# Fortran 77 program through the legacy entry point with gfortran and pkg-config, (e) a C program
# with `pkg-config --static` against an install of the static library alone, (f) the installed
# examples, on their own against the install, (g) every link line of the docs, as written. Each
# runs a scene and exits nonzero if its numbers are off. Before them: only the public Fortran
# modules are installed (docs/BUILD.md, "What is installed").
#
# Usage: run_export_test.sh SOURCE_DIR BUILD_DIR WORK_DIR CMAKE C_COMPILER Fortran_COMPILER WITH_HDF5
set -euo pipefail
src=$1 build=$2 work=$3 cmake=$4 cc=$5 fc=$6 with_hdf5=$7
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

step "only the public Fortran modules are installed"
expected="vci.mod vci_ensemble.mod"
case "$with_hdf5" in ON|on|1|TRUE|true) expected="$expected vci_ensemble_h5.mod vci_ensemble_mpi.mod vci_hdf5_output.mod";; esac
installed=$(cd "$(dirname "$mod")" && ls | sort | tr '\n' ' ' | sed 's/ $//')
expected=$(echo $expected | tr ' ' '\n' | sort | tr '\n' ' ' | sed 's/ $//')
echo "installed: $installed"
[ "$installed" = "$expected" ] || { echo "expected exactly: $expected"; exit 1; }

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

step "(e) C with pkg-config --static against the static library alone"
# a copy of the install without libvci.so*, as with -DVCI_BUILD_SHARED=OFF: the linker takes libvci.a,
# and vci.pc's Requires.private and Libs.private must bring LAPACK, HDF5 and the Fortran runtime
cp -a "$prefix" "$work/static-prefix"
rm -f "$work/static-prefix/${libdir#$prefix/}"/libvci.so*
(
  export PKG_CONFIG_PATH="$work/static-prefix/${libdir#$prefix/}/pkgconfig"
  echo "pkg-config --static --libs vci: $(pkg-config --static --libs vci)"
  "$cc" "$here/c_pkgconfig/pendulum.c" -o "$work/pendulum_static" $(pkg-config --static --cflags --libs vci)
)
if ldd "$work/pendulum_static" | grep "libvci" > /dev/null; then echo "pendulum_static uses libvci.so"; exit 1; fi
"$work/pendulum_static"

step "(f) the installed examples, built on their own against the install"
ex="$prefix/share/doc/vci/examples"
test -f "$ex/CMakeLists.txt" || { echo "examples not installed in $ex"; exit 1; }
for f in LICENSE CHANGELOG.md CITATION.cff README.md docs/C_API.md docs/BUILD.md docs/VERSIONING.md; do
  test -f "$prefix/share/doc/vci/$f" || { echo "missing share/doc/vci/$f"; exit 1; }
done
"$cmake" -S "$ex" -B "$work/f" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_Fortran_COMPILER="$fc" -DCMAKE_C_COMPILER="$cc" \
  > "$work/f.log" || { cat "$work/f.log"; exit 1; }
"$cmake" --build "$work/f" -j2 >> "$work/f.log" || { cat "$work/f.log"; exit 1; }
for ex_bin in ellipse pendulum vci_c_ellipse; do
  args=(--no-output); case $ex_bin in vci_c_*) args=();; esac
  "$work/f/bin/$ex_bin" "${args[@]}" 2>/dev/null | grep -E '^impact' > "$work/f_$ex_bin.txt" || true
  "$build/bin/$ex_bin" "${args[@]}" 2>/dev/null | grep -E '^impact' > "$work/b_$ex_bin.txt" || true
  [ -s "$work/b_$ex_bin.txt" ] || { echo "$ex_bin: no impact lines from the build tree's copy"; exit 1; }
  cmp "$work/f_$ex_bin.txt" "$work/b_$ex_bin.txt" || { echo "$ex_bin: installed example differs"; diff "$work/f_$ex_bin.txt" "$work/b_$ex_bin.txt"; exit 1; }
  echo "$ex_bin: $(wc -l < "$work/f_$ex_bin.txt") impact lines, the same as the build tree's"
done

step "(g) the docs' link lines, as written"
bash "$here/doc_link_lines.sh" "$src" "$work/g" "$work/static-prefix/${libdir#$prefix/}/pkgconfig"

step "export test passed"
