"""Ensembles: many members of one model, each from its own start, over the C ABI's
vci_ensemble_run (OpenMP threads, results in memory) and vci_ensemble_run_file (the ensemble HDF5
file; over MPI ranks when the library is built with MPI).

    ens = vci.Ensemble(model, 0.05, scheme="lobatto", stages=4, rtol=1e-15)
    res = ens.run(200, q0, p0)            # q0, p0: (N, n) arrays (start="momentum")
    res.q, res.p, res.impacts, res.status

Every member is what an Integrator with the same settings gives from its start, bit for bit,
whatever the threads. Compiled callbacks (the formula path's numba cfuncs, C function pointers) run
on several threads at once. Python callables hold the GIL while they run, so their members are
serialised: an Ensemble of such a model runs on one thread (threads > 1 is refused with
ArgumentError), which costs what the members cost one after another.
"""
import re
from typing import List, NamedTuple

import numpy as np

from ._callbacks import _address
from ._lib import ffi, lib
from .errors import ArgumentError, DtypeError, last_error, make_error
from .integrator import IMPACT_ENERGY, SCHEMES, _real
from .model import LagrangianModel, Model

_START = {"pair": 0, "momentum": 1}
_MESSAGE_SIZE = 512


def python_callbacks(model):
    """Names of the model's callbacks that are Python callables (they need the GIL)."""
    names = [name for name, obj in model.callbacks.items()
             if not isinstance(obj, ffi.CData) and _address(obj) is None]
    formula = getattr(model, "formula", None)
    if formula is not None and getattr(formula, "backend", "numba") != "numba":
        names += [name for name in model.callbacks if name not in names]
    return names


class EnsembleResult(NamedTuple):
    """Per member k (first index): status (0 = ok, else the vci.h status that stopped it), t, q (N, n),
    p (N, n) of its last accepted state (NaN if it never started), steps, impacts (all of them),
    newton_iterations, energy_start/energy_end (H(q, p) when the model has `energy`, else E_d of
    the first and last steps), impact_t/impact_gap (N, impact_cap): its first impact times and gap
    indices (NaN / -1 beyond), messages: why it failed ('' if it did not)."""
    status: np.ndarray
    t: np.ndarray
    q: np.ndarray
    p: np.ndarray
    steps: np.ndarray
    impacts: np.ndarray
    newton_iterations: np.ndarray
    energy_start: np.ndarray
    energy_end: np.ndarray
    impact_t: np.ndarray
    impact_gap: np.ndarray
    messages: List[str]

    @property
    def failed(self):
        """Indices of the members that failed."""
        return np.flatnonzero(self.status != 0)

    def error(self, k):
        """The VciError member k failed with (None if it did not)."""
        if self.status[k] == 0:
            return None
        return make_error(int(self.status[k]), f"member {k}: {self.messages[k]}")


def _table(name, x, n_members, n):
    arr = np.asarray(x)
    if arr.dtype.kind not in "iuf":
        raise DtypeError(f"{name}: an array of dtype {arr.dtype} cannot be read as float64 (give real numbers)")
    if n == 1 and arr.ndim == 1 and arr.shape[0] == n_members:
        arr = arr.reshape(n_members, 1)
    if arr.shape != (n_members, n):
        raise ArgumentError(f"{name} has shape {arr.shape}, expected ({n_members}, {n}): one row per member "
                            f"of a model of n = {n}")
    return np.ascontiguousarray(arr, dtype=np.float64)


class Ensemble:
    """Members of one model with shared settings.

    Ensemble(model, h, scheme=None, stages=None, rtol=None, atol=None, max_iterations=None,
             impact_energy='discrete', max_impacts=None, impact_cap=0, threads=None)

    scheme/stages as for Integrator (a LagrangianModel only; 'left', 'midpoint', 'lobatto'); None
    for the other settings keeps the library's defaults (those of an Integrator). impact_cap: impact
    times kept per member. threads: OpenMP threads (None or 0: OMP_NUM_THREADS); a model with Python
    callables runs on one thread (they hold the GIL), threads > 1 then raises ArgumentError.
    """

    def __init__(self, model, h, *, scheme=None, stages=None, rtol=None, atol=None, max_iterations=None,
                 impact_energy="discrete", max_impacts=None, impact_cap=0, threads=None):
        if not isinstance(model, Model):
            raise ArgumentError(f"model must be a vci DiscreteModel or LagrangianModel, got {type(model).__name__}")
        self.model = model
        self.h = _real("h", h)
        self.python = python_callbacks(model)
        if threads is not None and (isinstance(threads, bool) or not isinstance(threads, (int, np.integer))
                                    or threads < 0):
            raise ArgumentError(f"threads must be a non-negative integer, got {threads!r}")
        if self.python and threads not in (None, 0, 1):
            raise ArgumentError(f"threads = {threads} with Python callbacks ({', '.join(self.python)}): they hold the "
                                "GIL, so their members cannot run in parallel; give compiled callbacks (numba cfunc, "
                                "vci.formula) or threads = 1")
        self.threads = 1 if self.python else int(threads or 0)
        if scheme is not None and scheme not in SCHEMES:
            raise ArgumentError(f"unknown scheme {scheme!r}; one of {sorted(SCHEMES)}")
        if scheme is not None and not isinstance(model, LagrangianModel):
            raise ArgumentError("a scheme is for a LagrangianModel only (a DiscreteModel is its own scheme)")
        if scheme == "lobatto" and stages is None:
            raise ArgumentError("the lobatto scheme needs stages = s (1..8)")
        if impact_energy not in IMPACT_ENERGY:
            raise ArgumentError(f"unknown impact energy condition {impact_energy!r}; one of {sorted(IMPACT_ENERGY)}")
        self.scheme = (scheme, stages if scheme == "lobatto" else None)
        self.settings = dict(rtol=rtol, atol=atol, max_iterations=max_iterations, impact_energy=impact_energy,
                             max_impacts=max_impacts)
        for name in ("impact_cap",):
            if isinstance(impact_cap, bool) or not isinstance(impact_cap, (int, np.integer)) or impact_cap < 0:
                raise ArgumentError(f"{name} must be a non-negative integer, got {impact_cap!r}")
        self.impact_cap = int(impact_cap)

    def _config(self, nsteps, direction, start, stride=0, chunk=0):
        if isinstance(nsteps, (bool, np.bool_)) or not isinstance(nsteps, (int, np.integer)) or nsteps < 0:
            raise ArgumentError("nsteps must be a non-negative integer")
        if start not in _START:
            raise ArgumentError(f"start must be 'pair' or 'momentum', got {start!r}")
        if direction not in (1, -1, "forward", "backward"):
            raise ArgumentError(f"direction must be +1, -1, 'forward' or 'backward', got {direction!r}")
        c = ffi.new("vci_ensemble_config *")
        c.size = ffi.sizeof("vci_ensemble_config")
        c.h = self.h
        c.nsteps = int(nsteps)
        c.direction = {1: 1, -1: -1, "forward": 1, "backward": -1}[direction]
        c.start_kind = _START[start]
        scheme, stages = self.scheme
        c.scheme = SCHEMES[scheme] if scheme is not None else -1
        c.stages = int(stages or 0)
        s = self.settings
        c.atol = -1.0 if s["atol"] is None else _real("atol", s["atol"])
        c.rtol = -1.0 if s["rtol"] is None else _real("rtol", s["rtol"])
        c.max_iterations = int(s["max_iterations"] or 0)
        c.impact_energy = IMPACT_ENERGY[s["impact_energy"]]
        c.max_impacts_per_step = int(s["max_impacts"] or 0)
        c.impact_cap = self.impact_cap
        c.stride = int(stride)
        c.threads = self.threads
        c.chunk = int(chunk)
        return c

    def _starts(self, q0, v0, t0):
        q = np.asarray(q0)
        if q.ndim == 0:
            raise ArgumentError(f"q0 must be an array of shape (N, {self.model.n}), got a scalar")
        n_members = q.shape[0]
        if n_members < 1:
            raise ArgumentError("q0 has no rows: an ensemble needs at least one member")
        n = self.model.n
        q = _table("q0", q0, n_members, n)
        v = _table("v0", v0, n_members, n)
        t = np.asarray(t0)
        if t.dtype.kind not in "iuf":
            raise DtypeError(f"t0: an array of dtype {t.dtype} cannot be read as float64")
        if t.ndim == 0:
            t = np.full(n_members, float(t))
        if t.shape != (n_members,):
            raise ArgumentError(f"t0 has shape {t.shape}, expected a number or ({n_members},)")
        return n_members, np.ascontiguousarray(t, dtype=np.float64), q, v

    def run(self, nsteps, q0, v0, *, t0=0.0, start="momentum", direction=1):
        """Run every member nsteps steps from (t0[k], q0[k], v0[k]); v0 is p0 (start='momentum') or q1
        at t0 + h (start='pair'). q0, v0: (N, n) (or (N,) when n = 1); t0 a number or (N,).
        Returns an EnsembleResult; a member's failure is in its status and message, it does not
        stop the others nor raise (res.error(k) gives it as an exception)."""
        config = self._config(nsteps, direction, start)
        n_members, t, q, v = self._starts(q0, v0, t0)
        n, cap = self.model.n, self.impact_cap
        out = dict(status=np.full(n_members, -1, dtype=np.intc), t=np.empty(n_members), q=np.empty((n_members, n)),
                   p=np.empty((n_members, n)), steps=np.zeros(n_members, dtype=np.int64),
                   impacts=np.zeros(n_members, dtype=np.int64), newton_iterations=np.zeros(n_members, dtype=np.int64),
                   energy_start=np.empty(n_members), energy_end=np.empty(n_members),
                   impact_t=np.empty((n_members, cap)), impact_gap=np.empty((n_members, cap), dtype=np.intc))
        r = ffi.new("vci_ensemble_results *")
        r.size = ffi.sizeof("vci_ensemble_results")
        ctypes = {"status": "int *", "impact_gap": "int *", "steps": "int64_t *", "impacts": "int64_t *",
                  "newton_iterations": "int64_t *"}
        for name, arr in out.items():
            if arr.size:
                setattr(r, name, ffi.cast(ctypes.get(name, "double *"), ffi.from_buffer(arr)))
        messages = ffi.new("char[]", _MESSAGE_SIZE * n_members)
        r.messages = messages
        r.message_size = _MESSAGE_SIZE
        self.model._log.clear()
        status = lib.vci_ensemble_run(self.model.handle, config, n_members, ffi.from_buffer("double[]", t),
                                      ffi.from_buffer("double[]", q), ffi.from_buffer("double[]", v), r)
        interrupt = self.model._log.interrupt()
        if interrupt is not None:
            raise interrupt
        if status != 0:
            raise make_error(status, last_error(None))
        raw = ffi.buffer(messages)[:]
        msgs = [raw[k * _MESSAGE_SIZE:(k + 1) * _MESSAGE_SIZE].split(b"\0", 1)[0].decode("utf-8", "replace")
                for k in range(n_members)]
        if self.python:
            msgs = [self._python_cause(m) for m in msgs]
        return EnsembleResult(messages=msgs, **out)

    def _python_cause(self, message):
        # members with Python callables run on this thread, so their codes are in its failure log
        found = re.search(r"stat = (-?\d+)", message)
        entry = self.model._log.lookup(int(found.group(1))) if found else None
        if entry is None:
            return message
        name, _, last = entry
        return f"{message}; Python callback {name} raised {last}"

    def run_file(self, path, nsteps, q0, v0, *, t0=0.0, start="momentum", direction=1, stride=0, chunk=0,
                 overwrite=False):
        """The members of run() written to the ensemble HDF5 file `path` (docs/ENSEMBLES.md; read it
        with h5py); with stride > 0 also their states every stride steps. An existing file raises
        OutputError unless overwrite. Returns the number of members that failed. A library built
        with MPI runs this over MPI_COMM_WORLD (every rank calling it alike)."""
        for name, val in (("stride", stride), ("chunk", chunk)):
            if isinstance(val, bool) or not isinstance(val, (int, np.integer)) or val < 0:
                raise ArgumentError(f"{name} must be a non-negative integer, got {val!r}")
        if not isinstance(path, (str, bytes)) and not hasattr(path, "__fspath__"):
            raise ArgumentError(f"path must be a string or path, got {type(path).__name__}")
        import os
        fpath = os.fsencode(path)
        config = self._config(nsteps, direction, start, stride, chunk)
        n_members, t, q, v = self._starts(q0, v0, t0)
        failed = ffi.new("int64_t *")
        self.model._log.clear()
        status = lib.vci_ensemble_run_file(self.model.handle, config, n_members, ffi.from_buffer("double[]", t),
                                           ffi.from_buffer("double[]", q), ffi.from_buffer("double[]", v),
                                           fpath, 1 if overwrite else 0, -1, failed)
        interrupt = self.model._log.interrupt()
        if interrupt is not None:
            raise interrupt
        if status != 0:
            raise make_error(status, last_error(None))
        return int(failed[0])

    def __repr__(self):
        scheme = self.scheme[0] or ("midpoint" if isinstance(self.model, LagrangianModel) else "discrete")
        return f"<vci.Ensemble of {self.model!r}, h={self.h}, scheme={scheme}, threads={self.threads or 'OMP'}>"
