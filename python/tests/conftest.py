"""Shared helpers of the Python tests: the exact references (test/python/vci_python_ref, built by
CMake from the project's reference modules in test/support) and paths."""
import os
import shutil
import subprocess

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, os.pardir, os.pardir))
BUILD = os.path.join(REPO, "build")


def ref_program():
    path = os.environ.get("VCI_PYTHON_REF") or os.path.join(BUILD, "test", "python", "vci_python_ref")
    if not os.path.exists(path):
        pytest.fail(f"the reference program {path} is missing: build the target vci_python_ref "
                    "(cmake --build --preset default), or run the tests through ctest")
    return path


def _run_ref(*args):
    cmd = [ref_program(), args[0], *(f"{float(a):.17g}" for a in args[1:])]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout.split("\n")
    return [line.split() for line in out if line.strip()]


def walls_exact(theta0, omega0, theta_w, t):
    """(theta, omega, impact times) of the exact walled pendulum (g/l = 9.8)."""
    rows = _run_ref("walls", theta0, omega0, theta_w, t)
    theta, omega, n = float(rows[0][0]), float(rows[0][1]), int(rows[0][2])
    times = np.array([float(r[0]) for r in rows[1:]])
    assert len(times) == n
    return theta, omega, times


def paper_exact(theta0, thetadot0, phi0, t):
    """(theta, phi, thetadot, impact times) of the paper's nonholonomic pendulum (reference of
    test/support/vci_ref_pendulum.f90)."""
    rows = _run_ref("paper", theta0, thetadot0, phi0, t)
    theta, phi, thd, n = float(rows[0][0]), float(rows[0][1]), float(rows[0][2]), int(rows[0][3])
    times = np.array([float(r[0]) for r in rows[1:]])
    assert len(times) == n
    return theta, phi, thd, times


def slope(h, err):
    """Least-squares slope of log(err) against log(h): the observed order."""
    return float(np.polyfit(np.log(np.asarray(h)), np.log(np.asarray(err)), 1)[0])


def c_compiler():
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.fail("no C compiler (cc): the header and C-pointer tests need one (Debian: gcc)")
    return cc


def include_dir():
    return os.environ.get("VCI_INCLUDE_DIR") or os.path.join(REPO, "include")


@pytest.fixture
def workdir(tmp_path):
    return tmp_path
