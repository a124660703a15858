"""One model shared by integrators in two threads (the C ABI allows it; cffi releases the GIL
during library calls, so Python callbacks of both run interleaved): the same results as one after
the other, and each thread's failure reported with its own Python exception."""
import math
import threading

import numpy as np
import pytest

import vci

import models


def _run(model, p0, out, key):
    try:
        it = vci.Integrator(model, 0.05, scheme="lobatto", stages=2, rtol=1e-15)
        it.init_from_momentum(0.0, [0.0], [p0])
        out[key] = it.integrate(300)
    except Exception as exc:  # noqa: BLE001 -- handed to the main thread
        out[key] = exc


def test_two_threads_share_a_python_model():
    model = models.walls_python()
    alone = {}
    for i, p0 in enumerate((4.0, 3.5)):
        _run(model, p0, alone, i)
    both = {}
    threads = [threading.Thread(target=_run, args=(model, p0, both, i)) for i, p0 in enumerate((4.0, 3.5))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for i in (0, 1):
        assert isinstance(both[i], vci.State), both[i]
        np.testing.assert_array_equal(both[i].q, alone[i].q)
        np.testing.assert_array_equal(both[i].p, alone[i].p)


def test_each_thread_gets_its_own_exception():
    def dl_dq(q, v):
        name = threading.current_thread().name
        if abs(q[0]) > 0.5:
            raise RuntimeError(f"raised in {name}")
        return [-9.8 * math.sin(q[0])]

    model = vci.LagrangianModel(1, 0, 2, lagrangian=lambda q, v: 0.5 * v[0] ** 2 + 9.8 * math.cos(q[0]),
                                dl_dq=dl_dq, dl_dv=lambda q, v: [v[0]], gaps=lambda q: [1 - q[0], q[0] + 1])
    out = {}
    threads = [threading.Thread(target=_run, args=(model, p0, out, i), name=f"worker{i}")
               for i, p0 in enumerate((4.0, 3.0))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for i in (0, 1):
        assert isinstance(out[i], vci.CallbackError)
        assert f"RuntimeError: raised in worker{i}" in str(out[i])
