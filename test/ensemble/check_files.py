#!/usr/bin/env python3
"""Checks of ensemble files with h5py, independent of vci's own reader (layout: docs/ENSEMBLES.md).

  check_files.py same FILE...     every file has the documented layout, is complete, and all hold
                                  bitwise the same /members (whatever ranks, threads, chunks wrote them)
                                  and, when there is one, the same /analysis (ellipse_ensemble's)
  check_files.py done FILE        print how many members the file holds (status != -1); 0 if unreadable
  check_files.py every-rank FILE  the same, but 0 until every rank has run one of them
  check_files.py killed FILE      a killed run's file: opens, not complete, holds some members, and
                                  every member it holds has all its datasets written
"""
import sys

import h5py
import numpy as np


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def layout(f, path):
    """Assert the documented datasets, types and shapes; return the /members dataset names."""
    a = f.attrs
    if a["format"] != b"vci-ensemble" or a["format_version"] != 1:
        fail(f"{path}: not a vci-ensemble format 1 file")
    nm, n, npar = int(a["n_members"]), int(a["n"]), int(a["n_params"])
    cap, ns = int(a["impact_cap"]), int(a["samples"])
    want = {
        "status": ((nm,), "i4"), "message": ((nm,), "S"), "t0": ((nm,), "f8"), "q0": ((nm, n), "f8"),
        "v0": ((nm, n), "f8"), "t": ((nm,), "f8"), "q": ((nm, n), "f8"), "p": ((nm, n), "f8"),
        "steps": ((nm,), "i8"), "impacts": ((nm,), "i8"), "newton_iterations": ((nm,), "i8"),
        "energy_kind": ((nm,), "i4"), "energy_start": ((nm,), "f8"), "energy_end": ((nm,), "f8"),
        "energy_change": ((nm,), "f8"),
    }
    if npar > 0:
        want["params"] = ((nm, npar), "f8")
    if cap > 0:
        want["impact_t"] = ((nm, cap), "f8")
        want["impact_gap"] = ((nm, cap), "i4")
    if ns > 0:
        want["trajectory/count"] = ((nm,), "i4")
        want["trajectory/t"] = ((nm, ns), "f8")
        want["trajectory/q"] = ((nm, ns, n), "f8")
        want["trajectory/p"] = ((nm, ns, n), "f8")
    for name, (shape, kind) in want.items():
        d = f["members"].get(name)
        if d is None:
            fail(f"{path}: /members/{name} missing")
        if d.shape != shape:
            fail(f"{path}: /members/{name} has shape {d.shape}, want {shape}")
        if kind == "S":
            if d.dtype.kind != "S" or d.dtype.itemsize != int(a["message_length"]):
                fail(f"{path}: /members/{name} is {d.dtype}")
        elif d.dtype != np.dtype("<" + kind):
            fail(f"{path}: /members/{name} is {d.dtype}, want {kind}")
    for name in ("rank", "thread", "seconds"):
        if f["run"].get(name) is None or f["run"][name].shape != (nm,):
            fail(f"{path}: /run/{name} missing or of the wrong shape")
    return sorted(want)


def same(paths):
    ref = None
    for path in paths:
        with h5py.File(path, "r") as f:
            names = layout(f, path)
            if f.attrs["complete"] != 1 or f.attrs["members_run"] != f.attrs["n_members"]:
                fail(f"{path}: not complete")
            if np.any(f["members/status"][:] < 0):
                fail(f"{path}: members not run")
            data = {"members/" + k: f["members"][k][()].tobytes() for k in names}
            if "analysis" in f:  # the example's own numbers, compared as well
                for k, d in f["analysis"].items():
                    data["analysis/" + k] = d[()].tobytes()
                for k, v in f["analysis"].attrs.items():
                    data["analysis@" + k] = np.asarray(v).tobytes()
            ranks = sorted(set(f["run/rank"][:].tolist()))
            print(f"{path}: {f.attrs['n_members']} members, ranks {ranks} (of {f.attrs['ranks']}), "
                  f"threads {f.attrs['threads']}, chunk {f.attrs['chunk']}, failed {f.attrs['members_failed']}")
            if f.attrs["ranks"] > 1 and len(ranks) < 2:
                print(f"  note: one rank ran every member")
        if ref is None:
            ref, ref_path = data, path
        else:
            if sorted(data) != sorted(ref):
                fail(f"{ref_path} and {path} hold different datasets")
            for k in ref:
                if data[k] != ref[k]:
                    fail(f"/{k} differs bitwise between {ref_path} and {path}")
    print(f"{len(paths)} files: identical " + ", ".join(sorted({"/" + k.split("/")[0].split("@")[0] for k in ref})))


def done(path):
    try:
        with h5py.File(path, "r") as f:
            print(int(np.count_nonzero(f["members/status"][:] >= 0)))
    except Exception:  # not yet created, or not yet readable
        print(0)


def every_rank(path):
    """As done, but 0 until every rank has run a member the file holds: sigkill.sh kills once this
    is large enough, and the killed file must show the members distributed (a rank that starts
    late on a loaded machine is not a fault)."""
    try:
        with h5py.File(path, "r") as f:
            held = f["members/status"][:] >= 0
            ranks = set(f["run/rank"][:][held].tolist())
            print(0 if len(ranks) < f.attrs["ranks"] else int(np.count_nonzero(held)))
    except Exception:  # not yet created, or not yet readable
        print(0)


def killed(path):
    with h5py.File(path, "r") as f:
        layout(f, path)
        st = f["members/status"][:]
        held = st >= 0
        if f.attrs["complete"] != 0:
            fail("a killed run's file says it is complete")
        if held.sum() < 1 or held.all():
            fail(f"expected some but not all members, found {held.sum()} of {st.size}")
        # a member is written entirely before its status: what the file holds is whole
        t, steps = f["members/t"][:], f["members/steps"][:]
        if np.any(np.isnan(t[held & (st == 0)])) or np.any(steps[held & (st == 0)] <= 0):
            fail("a member with a status lacks its final state")
        if np.any(~np.isnan(f["members/t"][:][~held])):
            print("note: members without a status have data (written, status not yet)")
        ranks = sorted(set(f["run/rank"][:][held].tolist()))
        if f.attrs["ranks"] > 1 and len(ranks) < 2:
            fail(f"{f.attrs['ranks']} ranks, but only rank(s) {ranks} wrote members: not distributed")
        print(f"{path}: killed run holds {held.sum()} of {st.size} members (written by ranks {ranks}), "
              "readable with h5py")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        print(__doc__)
        sys.exit(2)
    mode, files = sys.argv[1], sys.argv[2:]
    {"same": lambda: same(files), "done": lambda: done(files[0]),
     "every-rank": lambda: every_rank(files[0]), "killed": lambda: killed(files[0])}[mode]()
