"""Restart from Python (Integrator.restore, open_output(append=True)) over the C ABI's
vci_restore_from_file and vci_append_output: a run split in two, the second half started from the
first half's HDF5 file and appended to it, equals the uninterrupted run bit for bit, state by state
and impact by impact (array_equal, no tolerance)."""
import numpy as np
import pytest

import vci

import models

h5py = pytest.importorskip("h5py")


def open_or_skip(it, path):
    """open_output, or skip the test in a build without HDF5 (the library says so)."""
    try:
        it.open_output(path)
    except vci.OutputError as exc:
        if "built without HDF5" in str(exc):
            pytest.skip(str(exc))
        raise


def whole_and_split(tmp_path, make, h, start, nsteps, split, **kw):
    """(file of the uninterrupted run, file of the split run, their final states)."""
    whole, parts = tmp_path / "whole.h5", tmp_path / "parts.h5"
    it = vci.Integrator(make(), h, **kw)
    it.init_from_momentum(0.0, *start)
    open_or_skip(it, whole)
    end_whole = it.integrate(nsteps)
    it.close()

    first = vci.Integrator(make(), h, **kw)
    first.init_from_momentum(0.0, *start)
    first.open_output(parts)
    first.integrate(split)
    first.close()

    second = vci.Integrator(make(), h, **kw)
    second.restore(parts)
    assert second.index == split
    second.open_output(parts, append=True)
    end_split = second.integrate(nsteps - split)
    second.close()
    return whole, parts, end_whole, end_split


def assert_same_files(a, b):
    ta, attrs_a = vci.read_output(a)
    tb, attrs_b = vci.read_output(b)
    assert attrs_a["steps_completed"] == attrs_b["steps_completed"]
    for field in ("t", "q", "p", "energy", "multipliers"):
        np.testing.assert_array_equal(getattr(ta, field), getattr(tb, field), err_msg=field)
    assert len(ta.impacts) == len(tb.impacts)
    for field in ("t", "alpha", "gap", "impulse", "q"):
        np.testing.assert_array_equal(ta.impacts[field], tb.impacts[field], err_msg=field)
    return ta


def test_walls_lobatto_split_run_is_the_whole_run(tmp_path):
    whole, parts, a, b = whole_and_split(tmp_path, models.walls_formula, 0.05, ([0.0], [4.0]), 200, 83,
                                         scheme="lobatto", stages=4, rtol=1e-15)
    assert a.t == b.t
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.p, b.p)
    traj = assert_same_files(whole, parts)
    # impacts on both sides of the split (step 83 is t = 4.15)
    assert np.any(traj.impacts["t"] < 83 * 0.05) and np.any(traj.impacts["t"] > 83 * 0.05)


def test_paper_pendulum_split_run_is_the_whole_run(tmp_path):
    """With a constraint (multipliers, the predictor's history in the checkpoint)."""
    whole, parts, a, b = whole_and_split(tmp_path, models.paper_formula, 0.01,
                                         (models.PAPER_Q0, models.paper_p0()), 500, 217, rtol=1e-15)
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.p, b.p)
    traj = assert_same_files(whole, parts)
    assert len(traj.impacts) >= 1


def test_restore_refusals(tmp_path):
    path = tmp_path / "run.h5"
    it = vci.Integrator(models.walls_python(), 0.05)
    it.init_from_momentum(0.0, [0.0], [4.0])
    open_or_skip(it, path)
    it.integrate(20)
    it.close_output()
    other_h = vci.Integrator(models.walls_python(), 0.04)
    with pytest.raises(vci.ArgumentError, match="step length"):
        other_h.restore(path)
    with pytest.raises(vci.StateError):
        other_h.step()  # no state after a refused restore
    other_model = vci.Integrator(models.paper_python(), 0.05)
    with pytest.raises(vci.ArgumentError, match="another model"):
        other_model.restore(path)
    with pytest.raises(vci.OutputError, match="does not exist"):
        it.restore(tmp_path / "missing.h5")
    with pytest.raises(vci.ArgumentError):
        it.restore("")
    # appending a run that does not continue the file is refused at its first step
    fresh = vci.Integrator(models.walls_python(), 0.05)
    fresh.init_from_momentum(0.0, [0.0], [4.0])
    fresh.open_output(path, append=True)
    with pytest.raises(vci.OutputError, match="last state"):
        fresh.integrate(5)
    got, _ = vci.read_output(path)
    assert len(got.t) == 21  # nothing was written to the file
