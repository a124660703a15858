"""Where the package finds libvci.so (vci/_lib.py): VCI_LIBRARY first, and a clear ImportError."""
import os
import subprocess
import sys

from conftest import REPO


def _import(env_library):
    env = dict(os.environ, PYTHONPATH=os.path.join(REPO, "python"), VCI_LIBRARY=env_library)
    return subprocess.run([sys.executable, "-c", "import vci; print(vci.library_path)"], env=env,
                          capture_output=True, text=True)


def test_vci_library_is_used():
    import vci
    res = _import(vci.library_path)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == vci.library_path


def test_a_wrong_vci_library_is_a_clear_import_error(tmp_path):
    res = _import(str(tmp_path / "libnothere.so"))
    assert res.returncode != 0
    assert "ImportError: vci: cannot load libvci.so" in res.stderr and "libnothere.so (VCI_LIBRARY" in res.stderr
