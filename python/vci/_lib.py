"""The cffi binding (ABI mode): the FFI object and the loaded libvci.

Where the library comes from, first match wins:
  1. the environment variable VCI_LIBRARY (a path to libvci.so);
  2. the build tree next to this package: <repository>/build/src/libvci.so;
  3. the system's search (ctypes.util.find_library("vci"), then "libvci.so").
"""
import ctypes.util
import os

import cffi

from . import _cdefs

ffi = cffi.FFI()
ffi.cdef(_cdefs.cdef_text())
for _name, _value in _cdefs.CONSTANTS.items():
    globals()[_name] = _value


def _candidates():
    env = os.environ.get("VCI_LIBRARY")
    if env:
        return [("VCI_LIBRARY", env)]
    out = []
    here = os.path.dirname(os.path.abspath(__file__))
    build = os.path.join(here, os.pardir, os.pardir, "build", "src", "libvci.so")
    out.append(("build tree", os.path.normpath(build)))
    found = ctypes.util.find_library("vci")
    if found:
        out.append(("system", found))
    out.append(("system", "libvci.so"))
    return out


def _load():
    tried = []
    for origin, path in _candidates():
        if origin == "build tree" and not os.path.exists(path):
            tried.append(f"{path} ({origin}: no such file)")
            continue
        try:
            return ffi.dlopen(path), path
        except OSError as exc:
            tried.append(f"{path} ({origin}: {exc})")
            if origin == "VCI_LIBRARY":
                break
    raise ImportError("vci: cannot load libvci.so; tried " + "; ".join(tried)
                      + ". Build it (cmake --preset default && cmake --build --preset default) or set VCI_LIBRARY.")


lib, library_path = _load()

_ver = lib.vci_version()
if _ver // 10000 != _cdefs.CONSTANTS["VCI_VERSION_MAJOR"] or _ver // 100 % 100 < _cdefs.CONSTANTS["VCI_VERSION_MINOR"]:
    raise ImportError(f"vci: {library_path} is version {_ver}; this package needs "
                      f"{_cdefs.CONSTANTS['VCI_VERSION_MAJOR']}.{_cdefs.CONSTANTS['VCI_VERSION_MINOR']} or a later minor")
