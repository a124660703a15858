"""The formula path's on-disk cache (cache= or VCI_FORMULA_CACHE): the generated module and numba's
compiled code are kept, a second build loads them, and the model computes the same run."""
import glob
import os

import numpy as np

import vci

import models


def _run(model):
    it = vci.Integrator(model, 0.05, scheme="lobatto", stages=4, rtol=1e-15)
    it.init_from_momentum(0.0, [0.0], [4.0])
    st = it.integrate(200)
    return np.concatenate([st.q, st.p, it.impacts["t"]])


def _numba_files(root, module):
    """numba's cache files of the generated module (beside it, or under NUMBA_CACHE_DIR)."""
    stem = os.path.basename(module)[:-3]
    return sorted(glob.glob(os.path.join(root, "**", stem + ".*"), recursive=True))


def test_cache_is_written_and_reused(tmp_path):
    import numba
    reference = _run(models.walls_formula())  # no cache: nothing written anywhere
    first = models.walls_formula(cache=tmp_path)
    modules = glob.glob(os.path.join(tmp_path, "vci_formula_*.py"))
    assert len(modules) == 1
    # numba's index and object files of the five callbacks (the walled pendulum's L is separable:
    # V, grad V, its Hessian, the gaps and their gradients)
    root = numba.config.CACHE_DIR or str(tmp_path)
    files = _numba_files(root, modules[0])
    assert len([f for f in files if f.endswith(".nbi")]) == 5, files
    stamp = {p: os.stat(p).st_mtime_ns for p in files}
    second = models.walls_formula(cache=tmp_path)
    # loaded, not compiled again: no file rewritten, none added
    assert {p: os.stat(p).st_mtime_ns for p in _numba_files(root, modules[0])} == stamp
    assert glob.glob(os.path.join(tmp_path, "vci_formula_*.py")) == modules
    np.testing.assert_array_equal(_run(first), reference)
    np.testing.assert_array_equal(_run(second), reference)
    # another model, another module
    models.walls_formula(cache=tmp_path, hessians=False)
    assert len(glob.glob(os.path.join(tmp_path, "vci_formula_*.py"))) == 2
