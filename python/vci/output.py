"""Reading the HDF5 trajectory files the library writes (Integrator.open_output; layout:
docs/OUTPUT.md). Needs h5py (Debian: python3-h5py)."""
import numpy as np

from .integrator import Trajectory, impact_dtype


def read_output(path):
    """(Trajectory, attributes) of the HDF5 file at path. The impacts are records of impact_dtype
    with 0-based gap indices, as the Integrator reports them (the file numbers walls from 1).
    Rows beyond the attribute steps_completed (a run killed mid-flush) are left out."""
    import h5py
    with h5py.File(path, "r") as f:
        attrs = {k: (v.decode() if isinstance(v, bytes) else v.item() if hasattr(v, "item") else v)
                 for k, v in f.attrs.items()}
        steps = int(attrs.get("steps_completed", len(f["energy"])))
        n, m = int(attrs["n"]), int(attrs["m"])
        t = f["t"][:steps + 1]
        q = f["q"][:steps + 1]
        p = f["p"][:steps + 1]
        energy = f["energy"][:steps]
        lam = f["lambda"][:steps] if m > 0 and "lambda" in f else np.empty((steps, m))
        # index of the last state on disk: its row, or /step's entry when the file keeps every k-th
        last_index = int(f["step"][steps]) if "step" in f else steps
        imp = np.zeros(0, dtype=impact_dtype(n))
        if "impacts" in f:
            g = f["impacts"]
            k = len(g["time"])
            imp = np.zeros(k, dtype=impact_dtype(n))
            imp["t"] = g["time"][:]
            imp["alpha"] = g["alpha"][:]
            imp["gap"] = g["gap_index"][:] - 1
            imp["impulse"] = g["impulse"][:]
            imp["q"] = g["q"][:].reshape(k, n)
            imp = imp[g["step"][:] < last_index]
    return Trajectory(t, q, p, energy, lam, imp), attrs
