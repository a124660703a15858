"""Malformed restart files: every rank, shape, size and type the reader takes from a file is
checked before use. A good file from each example is damaged one way at a time (h5py), then
`--from FILE` and `--from FILE --append` must end cleanly: refused with exit status 1 and a message
naming the file, or (where the damage only costs the checkpoint) accepted. Never a signal, a hang,
a runtime error or an allocation the file dictates.

Issue 24 item 7: extents are checked against the file's size before anything is cut or read (an
extent of 2^40 rows in a small file is refused at once, not cut row by row for hours); a
checkpoint whose time is not its row's t is not used (the run restarts from that row's state, at
its t); a checkpoint of a future layout version refuses the file; `--from` a FIFO is refused at
once, not opened (which would block).

Usage: malformed_files.py ELLIPSE_EXE PENDULUM_EXE WORKDIR
"""
import os
import re
import shutil
import subprocess
import sys

import h5py
import numpy as np

ellipse, pendulum, work = sys.argv[1:4]
os.makedirs(work, exist_ok=True)
os.chdir(work)

def run(cmd):
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    except subprocess.TimeoutExpired:
        return None, "", "timeout"
    return p.returncode, p.stdout, p.stderr

def good(exe, name, t_final):
    rc, out, err = run([exe, "--t-final", t_final, "--flush-every", "1", "--quiet", "--output", name])
    assert rc == 0, (exe, rc, out, err)
    return name

ELL = good(ellipse, "good_ellipse.h5", "3")
PEN = good(pendulum, "good_pendulum.h5", "1.5")

def replace(f, name, data, dtype=None):
    del f[name]
    f.create_dataset(name, data=data, dtype=dtype)

def set_attr(f, name, value):
    del f.attrs[name]
    f.attrs[name] = value

def record(f, i, value):
    f["checkpoint/record"][i] = value

def grow(f, name, rows):
    d = f[name]
    d.resize((rows,) + d.shape[1:])

# (label, source file, damage, expected): "refuse" = exit status 1 naming the file; "accept" = runs
CASES = [
    ("impacts/step shape (3, 1000)", ELL, lambda f: replace(f, "impacts/step", np.zeros((1000, 3), np.int64)), "refuse"),
    ("impacts/q wrong width", ELL, lambda f: replace(f, "impacts/q", np.zeros((2, 5))), "refuse"),
    ("checkpoint/record 14 x 14", ELL, lambda f: replace(f, "checkpoint/record", np.zeros((14, 14))), "accept"),
    ("checkpoint/record with NaN", ELL, lambda f: f["checkpoint/record"].__setitem__(8, np.nan), "accept"),
    ("checkpoint/record row 1e300", ELL, lambda f: f["checkpoint/record"].__setitem__(0, 1e300), "accept"),
    ("checkpoint/record too short", ELL, lambda f: replace(f, "checkpoint/record", np.zeros(3)), "accept"),
    ("/t scalar", ELL, lambda f: replace(f, "t", 1.0), "refuse"),
    ("/t rank 3", ELL, lambda f: replace(f, "t", np.zeros((2, 2, 2))), "refuse"),
    ("/t empty", ELL, lambda f: replace(f, "t", np.zeros(0)), "refuse"),
    ("/t strings", ELL, lambda f: replace(f, "t", np.array([b"abc"] * 301)), "refuse"),
    ("/q wrong width", ELL, lambda f: replace(f, "q", np.zeros((301, 4))), "refuse"),
    ("/q rank 1", ELL, lambda f: replace(f, "q", np.zeros(903)), "refuse"),
    ("/energy missing", ELL, lambda f: f.__delitem__("energy"), "refuse"),
    ("attribute h with 50 values", ELL, lambda f: set_attr(f, "h", np.full(50, 0.01)), "refuse"),
    ("attribute h NaN", ELL, lambda f: set_attr(f, "h", np.nan), "refuse"),
    ("attribute h negative", ELL, lambda f: set_attr(f, "h", -0.01), "refuse"),
    ("attribute n an array", ELL, lambda f: set_attr(f, "n", np.array([3, 3, 3, 3], np.int32)), "refuse"),
    ("attribute n = 2^31 - 1", ELL, lambda f: set_attr(f, "n", np.int32(2**31 - 1)), "refuse"),
    ("attribute n = 0", ELL, lambda f: set_attr(f, "n", np.int32(0)), "refuse"),
    ("attribute n a string", ELL, lambda f: set_attr(f, "n", np.bytes_(b"3")), "refuse"),
    ("attribute m > n", ELL, lambda f: set_attr(f, "m", np.int32(7)), "refuse"),
    ("attribute n_gaps = -1", ELL, lambda f: set_attr(f, "n_gaps", np.int32(-1)), "refuse"),
    ("attribute direction unknown", ELL, lambda f: set_attr(f, "direction", np.bytes_(b"sideways")), "refuse"),
    ("attribute direction an integer", ELL, lambda f: set_attr(f, "direction", np.int32(1)), "refuse"),
    ("attribute direction 10 kB", ELL, lambda f: set_attr(f, "direction", np.bytes_(b"f" * 10000)), "refuse"),
    ("steps_completed negative", ELL, lambda f: set_attr(f, "steps_completed", np.int64(-5)), "refuse"),
    ("steps_completed 2^62", ELL, lambda f: set_attr(f, "steps_completed", np.int64(2**62)), "accept"),
    ("steps_completed a real", ELL, lambda f: set_attr(f, "steps_completed", 3.5), "refuse"),
    ("/lambda wrong width", PEN, lambda f: replace(f, "lambda", np.zeros((1500, 3))), "refuse"),
    ("/lambda missing", PEN, lambda f: f.__delitem__("lambda"), "refuse"),
    ("attribute m = 0 (the pendulum has 1)", PEN, lambda f: set_attr(f, "m", np.int32(0)), "refuse"),
    # extents the file's bytes cannot hold (2^40 rows of /t in a file of a few kB)
    ("/t extent 2^40 rows", ELL, lambda f: grow(f, "t", 2**40), "refuse"),
    ("/q extent 2^40 rows", ELL, lambda f: grow(f, "q", 2**40), "refuse"),
    ("/energy extent 2^40, steps_completed 2^62", ELL,
     lambda f: (grow(f, "energy", 2**40), set_attr(f, "steps_completed", np.int64(2**62))), "refuse"),
    ("/impacts/time extent 2^40", ELL, lambda f: grow(f, "impacts/time", 2**40), "refuse"),
    # a checkpoint whose time is not its row's: the row's state serves (at the row's t)
    ("checkpoint step index + 1e13", ELL, lambda f: record(f, 1, f["checkpoint/record"][1] + 1e13), "row"),
    ("checkpoint step index - 1", ELL, lambda f: record(f, 1, f["checkpoint/record"][1] - 1), "row"),
    ("checkpoint step index 0", ELL, lambda f: record(f, 1, 0.0), "row"),
    ("checkpoint t0 = 1", ELL, lambda f: record(f, 2, 1.0), "row"),
    ("checkpoint t0 = 1e308", ELL, lambda f: record(f, 2, 1e308), "row"),
    ("checkpoint version 1 (older)", ELL, lambda f: f["checkpoint"].attrs.__setitem__("version", np.int32(1)), "row"),
    ("checkpoint version 999 (newer)", ELL,
     lambda f: f["checkpoint"].attrs.__setitem__("version", np.int32(999)), "refuse"),
    # layout 3 (before the split counts and /checkpoint/start): still read, at the row's t
    ("checkpoint layout 3 (older, read)", PEN,
     lambda f: (f["checkpoint"].attrs.__setitem__("version", np.int32(3)),
                replace(f, "checkpoint/record", f["checkpoint/record"][:-2]), f.__delitem__("checkpoint/start")), "row"),
    ("checkpoint/start wrong length", PEN, lambda f: replace(f, "checkpoint/start", np.zeros(9)), "row"),
    ("checkpoint/start length NaN", PEN, lambda f: f["checkpoint/start"].__setitem__(1, np.nan), "row"),
    ("checkpoint version a string", ELL,
     lambda f: f["checkpoint"].attrs.__setitem__("version", np.bytes_(b"3")), "row"),
]

def start_time(out):
    for line in out.splitlines():
        if line.startswith("start state: t ="):
            # Fortran's es24.16 writes 1.0000000000000000+308 for a three-digit exponent
            return float(re.sub(r"(\d)([+-]\d{3})$", r"\1E\2", line.split()[4]))
    return None

failures = 0
for label, src, damage, expected in CASES:
    exe = ellipse if src == ELL else pendulum
    t_more = "4" if src == ELL else "2"
    for mode in ("from", "append"):
        path = "bad.h5"
        shutil.copyfile(src, path)
        with h5py.File(path, "r+") as f:
            damage(f)
        cmd = [exe, "--from", path, "--t-final", t_more, "--quiet"]
        cmd += ["--append"] if mode == "append" else ["--no-output"]
        rc, out, err = run(cmd)
        text = out + err
        ok = rc is not None and rc in (0, 1) and "runtime error" not in text.lower() and "error allocating" not in text.lower()
        if expected == "refuse":
            ok = ok and rc == 1 and path in err
        elif expected == "row":
            # the run restarts from the checkpoint's row (the last on disk), at that row's t
            with h5py.File(src, "r") as g:
                t_row = float(g["t"][int(g["checkpoint/record"][0])])
            t = start_time(out)
            ok = ok and rc == 0 and t is not None and abs(t - t_row) <= 1e-15 * max(1.0, abs(t_row))
            if not ok:
                err = "started at t = %s, the row's t is %r; %s" % (t, t_row, err)
        else:
            ok = ok and rc == 0
        print("%-4s %-34s --%-6s exit %s: %s" % ("ok" if ok else "FAIL", label, mode, rc, err.strip()[:110]))
        failures += not ok
# --from a FIFO (or anything else that is not a regular file): refused at once, never opened
for fifo in ("fifo.h5", "fifo.csv"):
    if os.path.lexists(fifo):
        os.remove(fifo)      # (a previous run's)
    os.mkfifo(fifo)
for path in ("fifo.h5", "fifo.csv"):
    for mode in ("from", "append"):
        cmd = [ellipse, "--from", path, "--t-final", "4", "--quiet"]
        cmd += ["--append"] if mode == "append" else ["--no-output"]
        try:
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=20)
            rc, err = p.returncode, p.stderr
        except subprocess.TimeoutExpired:
            rc, err = None, "no answer within 20 s (blocked opening the FIFO)"
        ok = rc == 1 and path in err and "regular file" in err
        print("%-4s %-34s --%-6s exit %s: %s" % ("ok" if ok else "FAIL", "FIFO " + path, mode, rc, err.strip()[:110]))
        failures += not ok
print("%d runs wrong" % failures)
sys.exit(1 if failures else 0)
