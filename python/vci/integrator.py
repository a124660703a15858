"""The integrator: a vci_integrator with NumPy state, exceptions and impact records."""
import dataclasses
import math
import os
import re
from typing import NamedTuple, Optional

import numpy as np

from ._callbacks import FailureLog
from ._lib import ffi, lib
from .errors import ArgumentError, DtypeError, last_error, make_error
from .model import LagrangianModel, Model

SCHEMES = {"left": 1, "midpoint": 2, "lobatto": 3, "composition": 4}
IMPACT_ENERGY = {"discrete": 0, "hamiltonian": 1}
_DIRECTIONS = {1: 1, -1: -1, "forward": 1, "backward": -1}


def impact_dtype(n):
    """The structured dtype of impact records: time t, fraction alpha of the step, gap (0-based
    index into the gap functions), impulse (p+ - p- = impulse * grad g, forward time), q (n,) on
    the wall."""
    return np.dtype([("t", "f8"), ("alpha", "f8"), ("gap", "i4"), ("impulse", "f8"), ("q", "f8", (n,))])


def as_vector(name, x, n):
    """x as a contiguous float64 array of shape (n,) (a number when n = 1), or ArgumentError/DtypeError."""
    arr = np.asarray(x)
    if arr.dtype.kind not in "iuf":
        raise DtypeError(f"{name}: an array of dtype {arr.dtype} cannot be read as float64 "
                         "(give real numbers)")
    if arr.ndim == 0 and n == 1:
        arr = arr.reshape(1)
    if arr.shape != (n,):
        raise ArgumentError(f"{name} has shape {arr.shape}, expected ({n},) for a model of n = {n}")
    return np.ascontiguousarray(arr, dtype=np.float64)


def _real(name, x):
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.integer, np.floating)):
        raise DtypeError(f"{name} must be a real number, got {type(x).__name__}")
    return float(x)


class State(NamedTuple):
    """A state of the integrator: time t, configuration q (n,), momentum p (n,)."""
    t: float
    q: np.ndarray
    p: np.ndarray


class Stats(NamedTuple):
    """Counters over the integrator's life."""
    steps: int
    impacts: int
    newton_iterations: int


class Progress(NamedTuple):
    """What a progress callback (Integrator.set_progress) is told: steps done of this integrate
    call and its total, impacts so far, model time, wall seconds of this call, rate, estimated
    seconds left (-1: unknown)."""
    steps_done: int
    steps_total: int
    impacts: int
    t: float
    elapsed: float
    steps_per_second: float
    eta: float


class CheckReport(NamedTuple):
    """The model checker's verdict (check_model): passed when every supplied derivative agrees
    with central differences within the tolerance, worst the largest relative mismatch, lines
    one text line per comparison."""
    passed: bool
    worst: float
    lines: list


def check_model(model, q, v, h=0.0, tol=0.0):
    """Compare every derivative callback the model supplies with central differences at one point
    (vci_check_model): q (n,) and v (n,) (the second configuration of L_d(q, v, h) for a
    DiscreteModel, the velocity for a LagrangianModel); h > 0 is needed by a discrete model;
    tol <= 0: the library's default 1e-6. Returns a CheckReport; a callback that fails at the point
    raises CallbackError naming it."""
    if not isinstance(model, Model):
        raise ArgumentError(f"model must be a vci DiscreteModel or LagrangianModel, got {type(model).__name__}")
    a, b = as_vector("q", q, model.n), as_vector("v", v, model.n)
    h = _real("h", h)
    if isinstance(model, LagrangianModel) and h <= 0.0:
        h = 1.0  # not used by a continuous model's checks, but the library asks for h > 0
    passed, worst = ffi.new("int *"), ffi.new("double *")
    size = 8192
    report = ffi.new("char[]", size)
    model._log.clear()
    status = lib.vci_check_model(model.handle, ffi.from_buffer("double[]", a), ffi.from_buffer("double[]", b), h,
                                 _real("tol", tol), passed, worst, report, size)
    if status != 0:
        msg = last_error(None)
        found = model._log.latest()
        if found is not None:
            name, exc, last = found
            raise make_error(status, f"{msg}; Python callback {name} raised {last}") from exc
        raise make_error(status, msg)
    lines = [ln for ln in ffi.string(report).decode("utf-8", "replace").split("\n") if ln.strip()]
    return CheckReport(bool(passed[0]), float(worst[0]), lines)


@dataclasses.dataclass
class Trajectory:
    """A recorded run: t (N+1,), q and p (N+1, n), energy (N,) the discrete energy of each step,
    multipliers (N, m), impacts (a structured array, impact_dtype)."""
    t: np.ndarray
    q: np.ndarray
    p: np.ndarray
    energy: np.ndarray
    multipliers: np.ndarray
    impacts: np.ndarray


class Integrator:
    """Integrate a model with step h.

    Integrator(model, h, scheme=None, stages=None, rtol=1e-12, atol=0.0, max_iterations=30,
               impact_energy=None, max_impacts=None, on_impact=None)

    scheme ('left', 'midpoint', 'lobatto' with stages = s in 1..8, 'composition' with stages = the
    order) is for a LagrangianModel only (default 'midpoint'); 'composition' takes only the library's
    separable models, so a Python model gets ArgumentError from the library. impact_energy 'hamiltonian' keeps H(q, p) at impacts;
    None (default) is the library's default: 'discrete', except 'composition', which keeps 'hamiltonian' unless asked.
    max_impacts bounds the impacts of one step (default: the library's max(16, 4 ngaps)). on_impact(record)
    is called at each impact with a record of impact_dtype; every impact is also kept in
    `impacts` (cleared by the next init_*).
    """

    def __init__(self, model, h, *, scheme=None, stages=None, rtol=1e-12, atol=0.0, max_iterations=30,
                 impact_energy=None, max_impacts=None, on_impact=None):
        if not isinstance(model, Model):
            raise ArgumentError(f"model must be a vci DiscreteModel or LagrangianModel, got {type(model).__name__}")
        self.model = model  # keeps its callbacks alive
        self._log = model._log
        self.h = _real("h", h)
        handle = ffi.new("vci_integrator *")
        self._clear()
        status = lib.vci_integrator_create(handle, model.handle, self.h)
        if status != 0:
            raise make_error(status, last_error(None))
        self._h = handle
        self.n, self.m, self.ngaps = model.n, model.m, model.ngaps
        self._impact_dtype = impact_dtype(self.n)
        self._impacts = []
        self.on_impact = on_impact
        if on_impact is not None and not callable(on_impact):
            raise ArgumentError(f"on_impact must be callable, got {type(on_impact).__name__}")
        self._impact_cb = ffi.callback("vci_impact_fn", self._impact)
        self._check(lib.vci_set_impact_callback(self._h[0], self._impact_cb, ffi.NULL))
        self.scheme = None
        if scheme is not None or stages is not None:
            self.set_scheme(scheme or "lobatto", stages)
        elif isinstance(model, LagrangianModel):
            self.scheme = ("midpoint", None)
        self.set_tolerances(rtol=rtol, atol=atol, max_iterations=max_iterations)
        if impact_energy is not None:
            self.set_impact_energy(impact_energy)
        if max_impacts is not None:
            self._check(lib.vci_set_max_impacts(self._h[0], int(max_impacts)))
        self._output = None
        self._progress_fn = None
        self._progress_cb = None
        self._progress_exc = None

    # ---- plumbing ----
    def _clear(self):
        self._log.clear()

    def _check(self, status):
        if status == 0:
            return
        buf = ffi.new("char[]", 2048)
        if lib.vci_last_error(self._h[0], buf, 2048) == 0:
            msg = ffi.string(buf).decode("utf-8", "replace")
        else:
            msg = last_error(None)
        interrupt = self._log.interrupt()
        if interrupt is not None:
            raise interrupt
        found = None
        m = re.search(r"returned (-?\d+)", msg)
        if m:
            found = self._log.lookup(int(m.group(1)))
        if found is None and status == 2:
            found = self._log.latest()
        if found is not None:
            name, exc, last = found
            msg = f"{msg}; Python callback {name} raised {last}"
            err = make_error(status, msg)
            raise err from exc
        raise make_error(status, msg)

    def _impact(self, t, alpha, gap, q, impulse, user):
        try:
            rec = np.zeros((), dtype=self._impact_dtype)
            rec["t"], rec["alpha"], rec["gap"], rec["impulse"] = t, alpha, gap, impulse
            rec["q"] = np.frombuffer(ffi.buffer(q, 8 * self.n), dtype=np.float64)
            self._impacts.append(rec)
            if self.on_impact is not None:
                self.on_impact(rec)
            return 0
        except BaseException as exc:  # noqa: B902
            return self._log.record("on_impact", exc)

    @property
    def handle(self):
        """The library's vci_integrator handle (cffi pointer)."""
        return self._h[0]

    # ---- settings ----
    def set_scheme(self, scheme, stages=None):
        """'left', 'midpoint', 'lobatto' (stages = s, 1..8) or 'composition' (stages = the order,
        2, 4, 6, 8 or 10); resets the state."""
        if scheme not in SCHEMES:
            raise ArgumentError(f"unknown scheme {scheme!r}; one of {sorted(SCHEMES)}")
        if scheme in ("lobatto", "composition") and stages is None:
            raise ArgumentError(f"the {scheme} scheme needs stages = "
                                + ("s (1..8)" if scheme == "lobatto" else "the order (2, 4, 6, 8, 10)"))
        self._check(lib.vci_set_scheme(self._h[0], SCHEMES[scheme], int(stages or 0)))
        self.scheme = (scheme, stages if scheme in ("lobatto", "composition") else None)

    def set_tolerances(self, rtol=1e-12, atol=0.0, max_iterations=30):
        """Newton's tolerances (a row converges when |r_i| <= atol + rtol * size of its terms)."""
        self._check(lib.vci_set_tolerances(self._h[0], _real("atol", atol), _real("rtol", rtol),
                                           int(max_iterations)))

    def set_impact_energy(self, mode):
        """'discrete' (the paper's condition) or 'hamiltonian' (keeps H(q, p))."""
        if mode not in IMPACT_ENERGY:
            raise ArgumentError(f"unknown impact energy condition {mode!r}; one of {sorted(IMPACT_ENERGY)}")
        self._clear()
        self._check(lib.vci_set_impact_energy(self._h[0], IMPACT_ENERGY[mode]))

    def set_progress(self, fn, interval=1.0):
        """Call fn(Progress) at most once per `interval` wall seconds during integrate (one library
        call, record=False) and after its last step; fn = None: no more reports. A truthy return
        stops the run after the current step: integrate then raises StoppedError, the state being
        that of the last step done. An exception inside fn also stops the run and is raised by
        integrate."""
        if fn is not None and not callable(fn):
            raise ArgumentError(f"the progress callback must be callable, got {type(fn).__name__}")
        interval = _real("interval", interval)
        if fn is None:
            self._check(lib.vci_set_progress(self._h[0], ffi.NULL, interval, ffi.NULL))
            self._progress_fn = self._progress_cb = None
            return
        cb = ffi.callback("vci_progress_fn", self._progress)
        self._check(lib.vci_set_progress(self._h[0], cb, interval, ffi.NULL))
        self._progress_fn, self._progress_cb = fn, cb

    def _progress(self, info, user):
        try:
            p = Progress(int(info.steps_done), int(info.steps_total), int(info.impacts), info.t, info.elapsed,
                         info.steps_per_second, info.eta)
            return 1 if self._progress_fn(p) else 0
        except BaseException as exc:  # noqa: B902 -- carried to integrate, never through C
            self._progress_exc = exc
            return 1

    # ---- starting ----
    def init_from_pair(self, t0, q0, q1):
        """Start from q0 at t0 and q1 at t0 + h: the state becomes (t0 + h, q1, D2 L_d(q0, q1, h))."""
        a, b = as_vector("q0", q0, self.n), as_vector("q1", q1, self.n)
        self._impacts = []
        self._clear()
        self._check(lib.vci_init_from_pair(self._h[0], _real("t0", t0), ffi.from_buffer("double[]", a),
                                           ffi.from_buffer("double[]", b)))

    def init_from_momentum(self, t0, q0, p0):
        """Start from (q0, p0) at t0."""
        a, b = as_vector("q0", q0, self.n), as_vector("p0", p0, self.n)
        self._impacts = []
        self._clear()
        self._check(lib.vci_init_from_momentum(self._h[0], _real("t0", t0), ffi.from_buffer("double[]", a),
                                               ffi.from_buffer("double[]", b)))

    # ---- stepping ----
    @staticmethod
    def _direction(direction):
        try:
            return _DIRECTIONS[direction]
        except (KeyError, TypeError):
            raise ArgumentError(f"direction must be +1, -1, 'forward' or 'backward', got {direction!r}") from None

    def step(self, direction=1):
        """One step forward (+1) or backward (-1)."""
        d = self._direction(direction)
        self._clear()
        self._check(lib.vci_step(self._h[0], d))

    def integrate(self, nsteps=None, direction=1, *, t_final=None, record=False):
        """nsteps steps (or as many as reach t_final) in one direction.

        record=False: one call into the library (full speed); returns the final State.
        record=True: step by step; returns a Trajectory of every state. A failure raises the
        VciError; its attribute `trajectory` holds the states up to the last accepted step.
        """
        d = self._direction(direction)
        if (nsteps is None) == (t_final is None):
            raise ArgumentError("give either nsteps or t_final")
        if t_final is not None:
            t = self.t
            nsteps = max(0, math.ceil(d * (_real("t_final", t_final) - t) / self.h - 1e-9))
        if isinstance(nsteps, (bool, np.bool_)) or not isinstance(nsteps, (int, np.integer)) or nsteps < 0:
            raise ArgumentError("nsteps must be a non-negative integer")
        if not record:
            self._clear()
            self._progress_exc = None
            status = lib.vci_integrate(self._h[0], nsteps, d)
            exc, self._progress_exc = self._progress_exc, None
            if exc is not None and status == 11:
                raise exc
            self._check(status)
            return self.state
        return self._record(nsteps, d)

    def _record(self, nsteps, d):
        n, m = self.n, self.m
        t = np.empty(nsteps + 1)
        q = np.empty((nsteps + 1, n))
        p = np.empty((nsteps + 1, n))
        energy = np.empty(nsteps)
        lam = np.empty((nsteps, m))
        first_impact = len(self._impacts)
        tp = ffi.new("double *")
        en = ffi.new("double *")
        h = self._h
        self._check(lib.vci_get_state(h[0], tp, ffi.from_buffer("double[]", q[0]), ffi.from_buffer("double[]", p[0])))
        t[0] = tp[0]
        k = 0
        try:
            for k in range(1, nsteps + 1):
                self._clear()
                st = lib.vci_step(h[0], d)
                if st != 0:
                    k -= 1
                    self._check(st)
                lib.vci_get_state(h[0], tp, ffi.from_buffer("double[]", q[k]), ffi.from_buffer("double[]", p[k]))
                t[k] = tp[0]
                lib.vci_get_energy(h[0], en)
                energy[k - 1] = en[0]
                if m:
                    lib.vci_get_multipliers(h[0], ffi.from_buffer("double[]", lam[k - 1]))
        except Exception as exc:
            exc.trajectory = Trajectory(t[:k + 1], q[:k + 1], p[:k + 1], energy[:k], lam[:k],
                                        self._impact_array(self._impacts[first_impact:]))
            raise
        return Trajectory(t, q, p, energy, lam, self._impact_array(self._impacts[first_impact:]))

    def _impact_array(self, recs):
        out = np.zeros(len(recs), dtype=self._impact_dtype)
        for i, r in enumerate(recs):
            out[i] = r
        return out

    # ---- reading ----
    @property
    def state(self):
        """The current State(t, q, p)."""
        t = ffi.new("double *")
        q, p = np.empty(self.n), np.empty(self.n)
        self._check(lib.vci_get_state(self._h[0], t, ffi.from_buffer("double[]", q), ffi.from_buffer("double[]", p)))
        return State(t[0], q, p)

    @property
    def t(self):
        return self.state.t

    @property
    def q(self):
        return self.state.q

    @property
    def p(self):
        return self.state.p

    @property
    def multipliers(self):
        """The multipliers lambda (m,) of the last step."""
        lam = np.empty(self.m)
        self._check(lib.vci_get_multipliers(self._h[0], ffi.from_buffer("double[]", lam) if self.m else ffi.NULL))
        return lam

    @property
    def energy(self):
        """The discrete energy E_d of the last step (NaN after init_from_momentum until a step)."""
        e = ffi.new("double *")
        self._check(lib.vci_get_energy(self._h[0], e))
        return e[0]

    @property
    def index(self):
        """The index k of the current state (t = t0 + k h)."""
        k = ffi.new("int64_t *")
        self._check(lib.vci_get_index(self._h[0], k))
        return int(k[0])

    @property
    def stats(self):
        """Stats(steps, impacts, newton_iterations) over the integrator's life."""
        s, i, it = ffi.new("int64_t *"), ffi.new("int64_t *"), ffi.new("int64_t *")
        self._check(lib.vci_get_stats(self._h[0], s, i, it))
        return Stats(int(s[0]), int(i[0]), int(it[0]))

    @property
    def energy_fallbacks(self):
        """Soft impacts at which the discrete energy condition was blended with H, or H was kept."""
        c = ffi.new("int64_t *")
        self._check(lib.vci_get_energy_fallbacks(self._h[0], c))
        return int(c[0])

    @property
    def irreversible_impacts(self):
        """Impacts whose energy condition could not be tied to the sub-step leaving them up to the next
        wall, free steps in which a run back would poke a wall this run does not see, touches whose
        arriving momentum leaves the wall, and impacts whose energy condition has a second root of the
        other kind (meeting a wall within the step or leaving it free; a run back through any of them
        need not return; docs/BACKWARD.md, docs/DESIGN.md)."""
        c = ffi.new("int64_t *")
        self._check(lib.vci_get_irreversible_impacts(self._h[0], c))
        return int(c[0])

    @property
    def split_steps(self):
        """(steps the safety net took as equal sub-steps, the most sub-steps one needed)."""
        c, m = ffi.new("int64_t *"), ffi.new("int64_t *")
        self._check(lib.vci_get_split_steps(self._h[0], c, m))
        return int(c[0]), int(m[0])

    def set_step_splits(self, max_splits):
        """The safety net's bound: retry a failed step as up to max_splits equal sub-steps (1: off)."""
        self._check(lib.vci_set_step_splits(self._h[0], int(max_splits)))

    def set_poke_samples(self, on=True):
        """The poke screen (on, the default): a wall crossed and left again within one sub-step is an
        impact; off: the gaps are tested at the sub-steps' ends only (docs/BACKWARD.md)."""
        self._check(lib.vci_set_poke_samples(self._h[0], 1 if on else 0))

    def set_bordered_impacts(self, on=True, min_unknowns=0):
        """Impact stages by bordering (on, the default: the sub-step's block factorised in its own
        structure, the alpha/mu border by its Schur complement) or whole (off); min_unknowns >= 2:
        border only stage systems of at least that many unknowns (0 keeps the current bound, 16)."""
        self._check(lib.vci_set_bordered_impacts(self._h[0], 1 if on else 0, int(min_unknowns)))

    @property
    def bordered_directions(self):
        """Impact-stage Newton directions solved by bordering over the integrator's life."""
        c = ffi.new("int64_t *")
        self._check(lib.vci_get_bordered_directions(self._h[0], c))
        return int(c[0])

    @property
    def impacts(self):
        """Every impact since the last init_*, a structured array of impact_dtype(n)."""
        return self._impact_array(self._impacts)

    # ---- output ----
    @staticmethod
    def _path(path):
        path = os.fspath(path)
        if not isinstance(path, str) or not path:
            raise ArgumentError("path must be a non-empty string")
        return path

    def open_output(self, path, *, append=False, every=1, compress=0):
        """Write the trajectory of later steps to the HDF5 file path (replaced if it exists).
        every=k stores every k-th state (and the run's last; impacts always in full); compress=L
        gzip level 1..9 with shuffle (0: none). append=True continues the file instead, with the
        file's own every and compression: the run must go on from its last state, in its
        direction (start it with restore(path)); a run that does not is refused (OutputError) at
        its first step. OutputError when the library was built without HDF5; ArgumentError for an
        every outside [1, 2^30] or a level outside [0, 9]. Layout: docs/OUTPUT.md."""
        path = self._path(path)
        if append:
            if every != 1 or compress != 0:
                raise ArgumentError("open_output: append=True keeps the file's own every and "
                                    "compression; do not pass them")
            self._check(lib.vci_append_output(self._h[0], path.encode()))
        elif every == 1 and compress == 0:
            self._check(lib.vci_open_output(self._h[0], path.encode()))
        else:
            self._check(lib.vci_open_output_every(self._h[0], path.encode(), int(every), int(compress)))
        self._output = path

    def restore(self, path):
        """Start from the last state of the HDF5 file path (written by open_output, the Fortran
        writer or the examples' --output): with the checkpoint the file keeps, the run continues
        bit for bit as if it had never stopped. The integrator needs the file's model sizes and h
        (ArgumentError otherwise); OutputError when the file cannot be read."""
        path = self._path(path)
        self._impacts = []
        self._clear()
        self._check(lib.vci_restore_from_file(self._h[0], path.encode()))

    def close_output(self):
        """Finish and close the output file, if any."""
        self._check(lib.vci_close_output(self._h[0]))
        self._output = None

    # ---- life ----
    def close(self):
        """Destroy the library's integrator (finishing its output file)."""
        h = getattr(self, "_h", None)
        if h is not None and h[0] != ffi.NULL:
            lib.vci_integrator_destroy(h)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def __del__(self):
        try:
            self.close()
        except Exception:  # noqa: BLE001
            pass

    def __repr__(self):
        return f"<vci.Integrator h={self.h} scheme={self.scheme} model={self.model!r}>"
