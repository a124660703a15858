#!/usr/bin/env python3
"""Summarise vci_impact_jumps output (one file per build): the per-impact RMS that test_stab_long
bounds, a table of jump sizes by bucket of the shortest sub-step beside the impact,
s = min(alpha of the first impact, 1 - alpha of the last), and the largest jumps.

A jump from rounding a position over a sub-step s h is about v_x ulp(x) / (s h) in H (x grows as
2 t: p_x = 2 is conserved, no force or impulse acts along x), so the last column,
|jump| s h / (2 ulp(x)), is <= ~1 when that is the mechanism.
Usage: buckets.py file [file ...]"""
import math
import sys

H = 1.0e-2


def load(path):
    rows = []
    with open(path) as f:
        for line in f:
            if line.startswith('#'):
                continue
            w = line.split()
            r = dict(step=int(w[0]), nimp=int(w[1]), a1=float(w[2]), a2=float(w[3]), arrive=float(w[4]),
                     cond=float(w[5]), leave=float(w[6]), jump=float(w[7]), theta=float(w[8]))
            r['x'] = float(w[9]) if len(w) > 9 else 2.0 * r['step'] * H   # older files: x ~ 2 t
            r['s'] = min(r['a1'], 1.0 - r['a2'])
            r['ratio'] = abs(r['jump']) * r['s'] * H / (2.0 * math.ulp(abs(r['x'])))
            rows.append(r)
    return rows


EDGES = [0.0, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 0.5 + 1e-12]


def main():
    for path in sys.argv[1:]:
        rows = load(path)
        n = len(rows)
        rms = math.sqrt(sum(r['jump'] ** 2 for r in rows[1:]) / (n - 1))
        free = [r['jump'] - r['arrive'] - r['cond'] - r['leave'] for r in rows[1:]]
        print(f'## {path}: {n} impact steps, per-impact rms {rms:.3e}, max |jump| '
              f'{max(abs(r["jump"]) for r in rows):.3e}; free-flight part rms '
              f'{math.sqrt(sum(v * v for v in free) / len(free)):.2e}')
        print()
        print('| s = min(alpha, 1 - alpha) | impacts | rms jump | max jump | max arrive | max leave | '
              'share of sum jump^2 | max jump s h / (2 ulp x) |')
        print('|---|---:|---:|---:|---:|---:|---:|---:|')
        tot = sum(r['jump'] ** 2 for r in rows)
        for lo, hi in zip(EDGES[:-1], EDGES[1:]):
            sel = [r for r in rows if lo <= r['s'] < hi]
            label = f'[{lo:.0e}, {min(hi, 0.5):.0e})'
            if not sel:
                print(f'| {label} | 0 | | | | | | |')
                continue
            s2 = sum(r['jump'] ** 2 for r in sel)
            print(f'| {label} | {len(sel)} | {math.sqrt(s2 / len(sel)):.2e} | '
                  f'{max(abs(r["jump"]) for r in sel):.2e} | {max(abs(r["arrive"]) for r in sel):.2e} | '
                  f'{max(abs(r["leave"]) for r in sel):.2e} | {s2 / tot:.3f} | '
                  f'{max(r["ratio"] for r in sel):.2f} |')
        print()
        print('largest jumps: step, impacts, alpha (first), 1 - alpha (last), arrive, cond, leave, jump, x')
        for r in sorted(rows, key=lambda r: -abs(r['jump']))[:8]:
            print(f"  {r['step']} {r['nimp']} {r['a1']:.3e} {1 - r['a2']:.3e} {r['arrive']:.2e} {r['cond']:.2e} "
                  f"{r['leave']:.2e} {r['jump']:.2e} {r['x']:.4g}")
        print()


if __name__ == '__main__':
    main()
