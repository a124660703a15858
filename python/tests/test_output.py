"""HDF5 output through the C ABI (vci_open_output), read back with h5py (docs/OUTPUT.md)."""
import os

import numpy as np
import pytest

import vci

import models

h5py = pytest.importorskip("h5py")  # python3-h5py is in tools/install-deps.sh


def test_hdf5_file_holds_the_run(tmp_path):
    path = tmp_path / "walls.h5"
    it = vci.Integrator(models.walls_formula(), 0.05, scheme="lobatto", stages=4, rtol=1e-15)
    it.init_from_momentum(0.0, [0.0], [4.0])
    try:
        it.open_output(path)
    except vci.OutputError as exc:
        if "built without HDF5" in str(exc):  # the no-hdf5 preset: the library says so, nothing to read
            pytest.skip(str(exc))
        raise
    traj = it.integrate(200, record=True)
    it.close_output()
    got, attrs = vci.read_output(path)
    assert attrs["status"] == 0 and attrs["direction"] == "forward" and attrs["h"] == 0.05
    assert attrs["steps_completed"] == 200 and attrs["n"] == 1 and attrs["n_gaps"] == 2
    # the file has exactly the states and impacts the integrator reported
    np.testing.assert_array_equal(got.t, traj.t)
    np.testing.assert_array_equal(got.q, traj.q)
    np.testing.assert_array_equal(got.p, traj.p)
    np.testing.assert_array_equal(got.energy, traj.energy)
    assert len(got.impacts) == 18
    for field in ("t", "alpha", "gap", "impulse", "q"):
        np.testing.assert_array_equal(got.impacts[field], traj.impacts[field])


def test_every_k_and_compression(tmp_path):
    """open_output(every=10, compress=1): every 10th state and the last, all impacts, the file's
    attributes say how it was made (docs/OUTPUT.md)."""
    it = vci.Integrator(models.walls_formula(), 0.05, scheme="lobatto", stages=4, rtol=1e-15)
    it.init_from_momentum(0.0, [0.0], [4.0])
    path = tmp_path / "every.h5"
    try:
        it.open_output(path, every=10, compress=1)
    except vci.OutputError as exc:
        if "built without HDF5" in str(exc):
            pytest.skip(str(exc))
        raise
    traj = it.integrate(205, record=True)
    it.close_output()
    got, attrs = vci.read_output(path)
    assert attrs["every"] == 10 and attrs["compression"] == 1 and attrs["start"] == "momentum"
    assert attrs["scheme"] == "lobatto" and attrs["stages"] == 4
    kept = list(range(0, 206, 10)) + [205]
    np.testing.assert_array_equal(got.t, traj.t[kept])
    np.testing.assert_array_equal(got.q, traj.q[kept])
    assert len(got.impacts) == len(traj.impacts) >= 18
    np.testing.assert_array_equal(got.impacts["t"], traj.impacts["t"])
    with h5py.File(path, "r") as f:
        np.testing.assert_array_equal(f["step"][:], kept)
        assert f["q"].compression == "gzip" and f["q"].shuffle
    with pytest.raises(vci.ArgumentError):
        it.open_output(tmp_path / "bad.h5", every=0)
    with pytest.raises(vci.ArgumentError):
        it.open_output(tmp_path / "bad.h5", compress=10)


def test_unwritable_path_is_an_output_error(tmp_path):
    it = vci.Integrator(models.walls_python(), 0.05)
    it.init_from_momentum(0.0, [0.0], [4.0])
    with pytest.raises(vci.OutputError) as info:
        it.open_output(tmp_path / "no_such_dir" / "x.h5")
    assert info.value.status == 8 and isinstance(info.value, OSError)
    assert "no_such_dir" in str(info.value) or "built without HDF5" in str(info.value)
    it.integrate(10)  # the integrator still works
    assert it.index == 10
    assert not os.path.exists(tmp_path / "no_such_dir")
