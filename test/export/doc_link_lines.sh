#!/usr/bin/env bash
# Every link line of the docs, run as written: in the ```sh blocks of README.md and docs/*.md, each
# line that starts with `cc` or `gfortran` and asks pkg-config for vci. The programs they name are
# the docs' own: app.c is README's C program, app.f90 README's first Fortran sample, prog.f the
# legacy program test/export/legacy/ellipse77.f. Each line must build a.out, and a.out must run
# with no LD_LIBRARY_PATH, loading libvci from the install (the line's rpath), and exit 0. A line
# with `pkg-config --static` runs against STATIC_PC_DIR (an install of libvci.a alone), and its
# a.out must not load libvci at all.
#
# Usage: doc_link_lines.sh SOURCE_DIR WORK_DIR STATIC_PC_DIR   (PKG_CONFIG_PATH: the installed vci.pc)
set -euo pipefail
src=$1 work=$2 static_pc=$3
rm -rf "$work"
mkdir -p "$work"
cd "$work"
libdir=$(pkg-config --variable=libdir vci)
libdir=$(cd "$libdir" && pwd -P)

awk '/^```c$/{f=1; next} /^```/{if (f) exit} f' "$src/README.md" > app.c
awk '/^```fortran$/{f=1; next} /^```/{if (f) exit} f' "$src/README.md" > app.f90
cp "$src/test/export/legacy/ellipse77.f" prog.f
for f in app.c app.f90 prog.f; do [ -s "$f" ] || { echo "FAIL: no $f from the docs"; exit 1; }; done

count=0
for doc in "$src/README.md" "$src"/docs/*.md; do
  # the sh blocks' link lines, with their line numbers
  while IFS=$'\t' read -r lineno line; do
    count=$((count + 1))
    echo "--- ${doc#$src/}:$lineno: $line"
    rm -f a.out
    pcpath=$PKG_CONFIG_PATH
    case "$line" in *--static*) pcpath=$static_pc ;; esac
    env -u LD_LIBRARY_PATH PKG_CONFIG_PATH="$pcpath" bash -c "$line" \
      || { echo "FAIL: ${doc#$src/}:$lineno does not build"; exit 1; }
    [ -x a.out ] || { echo "FAIL: ${doc#$src/}:$lineno made no a.out"; exit 1; }
    resolved=$(env -u LD_LIBRARY_PATH ldd ./a.out | awk '/libvci\.so/ {print $3}')
    case "$line:$resolved" in
      *--static*:) echo "libvci linked statically" ;;
      *--static*:*) echo "FAIL: ${doc#$src/}:$lineno: a static link loads $resolved"; exit 1 ;;
      *:"$libdir"/*) echo "libvci from $resolved" ;;
      *) echo "FAIL: ${doc#$src/}:$lineno: a.out finds libvci at '$resolved', not in $libdir"; exit 1 ;;
    esac
    env -u LD_LIBRARY_PATH ./a.out > run.log 2>&1 || { cat run.log; echo "FAIL: ${doc#$src/}:$lineno: a.out failed"; exit 1; }
    tail -n 2 run.log
  done < <(awk '/^```sh$/{f=1; next} /^```/{f=0} f && /^(cc|gfortran) / && /pkg-config/ {print FNR "\t" $0}' "$doc")
done
# README's three (C, modern Fortran, legacy Fortran) and docs/C_API.md's four at least
[ "$count" -ge 7 ] || { echo "FAIL: only $count link lines found in the docs (expected at least 7)"; exit 1; }
echo "$count link lines built and ran"
