#!/usr/bin/env python3
"""Check that the library's layers use only the layers below them (docs/DESIGN.md, the map).

The layers are the folders of src/, lowest first, in the order src/CMakeLists.txt adds them
(its `foreach(_layer IN ITEMS ...)` line: the one place that order is written). Every Fortran
source of a layer may `use` (or be a submodule of) modules defined in its own layer or a lower one;
intrinsic modules and modules from outside the library (HDF5, MPI) are not checked. Each layer
folder must also have its README.md.

Usage: check_layers.py [SRC_DIR]   (default: the src/ beside this script's tools/ folder)
Exit status 0 when every use goes downward, 1 with one line per offending use otherwise.
"""
import pathlib
import re
import sys

USE = re.compile(r"^\s*use\s*(?:,\s*(intrinsic|non_intrinsic)\s*)?(?:::)?\s*([a-z_][a-z0-9_]*)", re.I)
SUBMODULE = re.compile(r"^\s*submodule\s*\(\s*([a-z_][a-z0-9_]*)", re.I)
MODULE = re.compile(r"^\s*module\s+(?!procedure\b|subroutine\b|function\b)([a-z_][a-z0-9_]*)\s*(?:!.*)?$", re.I)
ORDER = re.compile(r"foreach\s*\(\s*_layer\s+IN\s+ITEMS\s+([^)]*)\)", re.I)


def layer_order(src):
    m = ORDER.search((src / "CMakeLists.txt").read_text())
    if not m:
        raise SystemExit(f"{src}/CMakeLists.txt: no 'foreach(_layer IN ITEMS ...)' line naming the layers")
    return m.group(1).split()


def sources(src, layers):
    for rank, layer in enumerate(layers):
        for path in sorted((src / layer).glob("*")):
            if path.suffix.lower() in (".f90", ".f"):
                yield rank, layer, path


def main(argv):
    src = pathlib.Path(argv[1] if len(argv) > 1 else pathlib.Path(__file__).resolve().parent.parent / "src")
    layers = layer_order(src)
    problems = []
    for layer in layers:
        if not (src / layer / "README.md").is_file():
            problems.append(f"{src / layer}: no README.md saying what the layer holds and may use")
    for extra in sorted(p for p in src.glob("*") if p.suffix.lower() in (".f90", ".f", ".c")):
        problems.append(f"{extra}: a source outside the layer folders")
    defined = {}
    files = list(sources(src, layers))
    for rank, layer, path in files:
        for line in path.read_text(errors="replace").splitlines():
            m = MODULE.match(line)
            if m:
                defined[m.group(1).lower()] = (rank, layer)
    for rank, layer, path in files:
        for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            m = USE.match(line)
            name = None
            if m and (m.group(1) or "").lower() != "intrinsic":
                name = m.group(2).lower()
            m = SUBMODULE.match(line)
            if m:
                name = m.group(1).lower()
            if name is None or name not in defined:
                continue
            used_rank, used_layer = defined[name]
            if used_rank > rank:
                problems.append(f"{path}:{number}: layer '{layer}' uses {name} of the higher layer "
                                f"'{used_layer}' (order: {' < '.join(layers)})")
    for p in problems:
        print(p)
    if problems:
        print(f"check_layers: {len(problems)} problem(s)")
        return 1
    print(f"check_layers: {len(files)} sources in {len(layers)} layers, every use goes downward")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
