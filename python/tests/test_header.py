"""The cffi declarations (vci/_cdefs.py) against include/vci.h.

* prototypes and typedefs: compiled after #include "vci.h" (C refuses a redeclaration that
  conflicts: another argument type, count or return type);
* constants: static assertions against the header's enum values and macros;
* the callback structs: sizeof and every member's offset printed by a program compiled with the
  header, compared with cffi's layout of our declaration;
* coverage: every function the header declares is bound here or listed in UNBOUND.
"""
import os
import re
import subprocess

import pytest

from vci import _cdefs
from vci._lib import ffi

from conftest import c_compiler, include_dir


def _compile(tmp_path, source, run=False):
    src = tmp_path / "check.c"
    src.write_text(source)
    exe = tmp_path / "check"
    cmd = [c_compiler(), "-std=c11", "-Wall", "-Werror", "-pedantic-errors", "-I", include_dir(), str(src),
           "-o", str(exe)]
    res = subprocess.run(cmd, capture_output=True, text=True)
    assert res.returncode == 0, f"the C compiler refused the declarations:\n{res.stderr}"
    if run:
        return subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout
    return None


def test_prototypes_and_constants_compile_with_the_header(tmp_path):
    asserts = "\n".join(f'_Static_assert({k} == {v}, "{k} is not {v} in vci.h");'
                        for k, v in _cdefs.CONSTANTS.items())
    source = f'#include "vci.h"\n{_cdefs.DECLARATIONS}\n{asserts}\nint main(void) {{ return 0; }}\n'
    _compile(tmp_path, source)


def test_struct_layout_matches_the_header(tmp_path):
    lines = ['#include <stdio.h>', '#include <stddef.h>', '#include "vci.h"', 'int main(void) {']
    expected = []
    for struct in ("vci_callbacks", "vci_lagrangian_callbacks", "vci_progress", "vci_ensemble_config",
                   "vci_ensemble_results"):
        lines.append(f'  printf("{struct} sizeof %zu\\n", sizeof({struct}));')
        expected.append(f"{struct} sizeof {ffi.sizeof(struct)}")
        for name, field in ffi.typeof(struct).fields:
            lines.append(f'  printf("{struct} {name} %zu\\n", offsetof({struct}, {name}));')
            expected.append(f"{struct} {name} {field.offset}")
    lines += ["  return 0;", "}"]
    got = _compile(tmp_path, "\n".join(lines) + "\n", run=True).split("\n")
    assert [g for g in got if g] == expected
    # and the header's struct has no member that ours lacks: its size is the end of our last member
    for struct in ("vci_callbacks", "vci_lagrangian_callbacks", "vci_ensemble_config", "vci_ensemble_results"):
        last = ffi.typeof(struct).fields[-1][1]
        assert ffi.sizeof(struct) == last.offset + ffi.sizeof(last.type)


def test_every_header_function_is_bound_or_listed():
    with open(os.path.join(include_dir(), "vci.h")) as f:
        header = f.read()
    header = re.sub(r"/\*.*?\*/", " ", header, flags=re.S)
    declared = set(re.findall(r"^\s*(?:const\s+)?\w+\s*\*?\s*(vci_\w+)\s*\(", header, flags=re.M))
    declared |= set(re.findall(r"#define\s+(vci_\w+)\s+vci_\w+", header))
    bound = set(re.findall(r"(vci_\w+)\s*\(", _cdefs.DECLARATIONS)) - {
        m for m in re.findall(r"\(\*(vci_\w+)\)", _cdefs.DECLARATIONS)}
    assert declared, "no function found in vci.h: the pattern is wrong"
    missing = declared - bound - set(_cdefs.UNBOUND)
    assert not missing, f"vci.h declares functions the package neither binds nor lists in UNBOUND: {sorted(missing)}"
    stale = bound - declared
    assert not stale, f"bound but not in vci.h: {sorted(stale)}"


def test_every_bound_function_resolves_in_the_library():
    from vci._lib import lib
    for name in re.findall(r"^\s*(?:const\s+)?\w+\s*\*?\s*(vci_\w+)\s*\(", _cdefs.DECLARATIONS, flags=re.M):
        assert getattr(lib, name) is not None


@pytest.mark.parametrize("status", range(0, 11))
def test_status_strings(status):
    from vci.errors import BY_STATUS, status_string
    assert status_string(status)
    if status:
        assert BY_STATUS[status].status == status
