#!/usr/bin/python3
"""Replace one scene's rows in a full run's sweep CSVs by a fresh partial run's (run_results.sh --scene).

    merge_scene_rows.py OUT PART SCENE [COMMIT [SECONDS [LOAD_AT_START]]]

OUT holds a full run's output (vci_sweep.csv, dop853_sweep.csv, cvode_sweep.csv, meta.json, ...);
PART the partial run's vci, dop853 and cvode sweep CSVs for SCENE. Rows of SCENE in OUT's three
compiled-method CSVs (and its lines in vci_sweep.stderr) are dropped and PART's appended; the interpreted peers' rows (SciPy, Siconos)
and the long runs stay from the full run. meta.json gains a "refreshed" entry (scene, date, commit,
seconds, the 1-minute load average at the start and at the end) that make_report.py prints, so the
page says which rows are newer than its full run and how busy the machine was: the CPU-time ratios
of runs of microseconds move with the load (the walled pendulum's best vci/DOP853 ratios were
0.94-1.2 at a load below 1 and 0.83-2.2 beside two compiling jobs).
"""
import csv
import json
import os
import sys
import time


def merge(full_path, part_path, scene):
    with open(full_path, newline="") as f:
        rows = list(csv.reader(f))
    with open(part_path, newline="") as f:
        part = list(csv.reader(f))
    if not rows or not part or rows[0] != part[0]:
        sys.exit(f"merge_scene_rows.py: {full_path} and {part_path} do not have the same columns")
    kept = [r for r in rows[1:] if r and r[0] != scene]
    new = [r for r in part[1:] if r]
    if any(r[0] != scene for r in new):
        sys.exit(f"merge_scene_rows.py: {part_path} holds rows of scenes other than {scene}")
    if not new:
        sys.exit(f"merge_scene_rows.py: {part_path} has no rows for {scene}")
    with open(full_path, "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows([rows[0]] + kept + new)
    return len(rows) - 1 - len(kept), len(new)


def main(out, part, scene, commit="unknown", seconds="?", load_start="?"):
    for name in ("vci_sweep.csv", "dop853_sweep.csv", "cvode_sweep.csv"):
        old, new = merge(os.path.join(out, name), os.path.join(part, name), scene)
        print(f"{name}: {scene}: {old} rows replaced by {new}")
    # the failed runs' messages: that scene's lines (each starts with the scene's name) replaced
    err_full, err_part = os.path.join(out, "vci_sweep.stderr"), os.path.join(part, "vci_sweep.stderr")
    if os.path.exists(err_full) and os.path.exists(err_part):
        lines = [l for l in open(err_full) if not l.startswith(scene + " ")]
        lines += list(open(err_part))
        open(err_full, "w").writelines(lines)
    meta_path = os.path.join(out, "meta.json")
    meta = json.load(open(meta_path))
    entries = [e for e in meta.get("refreshed", []) if e.get("scene") != scene]
    entries.append({"scene": scene, "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
                    "commit": commit, "elapsed_s": seconds,
                    "load": f"{load_start} -> {open('/proc/loadavg').read().split()[0]}"})
    meta["refreshed"] = entries
    json.dump(meta, open(meta_path, "w"), indent=1)


if __name__ == "__main__":
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    main(*sys.argv[1:])
