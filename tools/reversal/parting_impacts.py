#!/usr/bin/env python3
"""Where a one-sided reversal run parts (docs/BACKWARD.md, "Two solutions of a step with a soft
impact"): for each seed, the forward and backward impacts at the harness's first difference, and
whether another impact of the same step precedes it forward or follows it backward. Needs a
build with tools/reversal/return_root_probe.patch applied (its VCI_DEBUG_RECORDS lines):

  python3 tools/reversal/parting_impacts.py build/test/fuzz/vci_fuzz SEED...

Prints one line per seed: the first difference's kind, then F[...] the forward impact there (time,
condition 0 discrete / 2 blended, impulse, leaving sub-step tau2, weight w) with the impact before
it in its step, if any; B[...] the backward impact nearest that time with the impact after it in
its step, if any; R[...] the second roots the VCI_DEBUG_RETURN search found at that time
(direction, and the impulse in the stepper's sign: minus the recorded one backward)."""
import os
import re
import subprocess
import sys

RETURN = re.compile(r'RETURN dir\s+(-?1) t\s+(\S+) mu_w\s+(\S+) mu\s+(\S+)')
RECORD = re.compile(r'RECORD dir\s+(-?1) t\s+(\S+) wall\s+(\d+) cond\s+(\d) impulse\s+(\S+) tau2\s+(\S+) w\s+(\S+)')
SAME_STEP = 1e-8   # step ends agree to the printed digits (tau2 to 11 significant digits)


def records(lines, direction):
    out = []
    for line in lines:
        m = RECORD.match(line)
        if m and int(m.group(1)) == direction:
            out.append(dict(t=float(m.group(2)), wall=int(m.group(3)), cond=int(m.group(4)),
                            impulse=float(m.group(5)), tau2=float(m.group(6)), w=float(m.group(7))))
    return out


def text(r):
    return 't %.7f wall %d cond %d impulse %.6g tau2 %.4g w %.3g' % (
        r['t'], r['wall'], r['cond'], r['impulse'], r['tau2'], r['w'])


def main():
    exe, seeds = os.path.abspath(sys.argv[1]), sys.argv[2:]
    env = dict(os.environ, VCI_DEBUG_RECORDS='1', VCI_DEBUG_RETURN='1')
    for seed in seeds:
        run = subprocess.run([exe, '--reversal', '-1', seed], capture_output=True, text=True, env=env)
        lines = (run.stdout + run.stderr).splitlines()
        summary = [l for l in lines if l.startswith('reversal seed')][-1]
        m = re.search(r'first difference from the end: ([\w-]+): (?:forward #\d+ )?t (\S+)', summary)
        if not m:
            print(seed, summary.split('first difference from the end: ')[-1])
            continue
        t = float(m.group(2))
        fwd, bwd = records(lines, 1), records(lines, -1)
        i = min(range(len(fwd)), key=lambda k: abs(fwd[k]['t'] - t))
        k = min(range(len(bwd)), key=lambda k: abs(bwd[k]['t'] - t))
        f_end = fwd[i]['t'] + fwd[i]['tau2']
        before = i > 0 and abs(fwd[i - 1]['t'] + fwd[i - 1]['tau2'] - f_end) < SAME_STEP
        b_end = bwd[k]['t'] - bwd[k]['tau2']
        after = k + 1 < len(bwd) and abs(bwd[k + 1]['t'] - bwd[k + 1]['tau2'] - b_end) < SAME_STEP
        second = ['dir %s mu %s' % (r.group(1), r.group(4)) for r in map(RETURN.match, lines)
                  if r and abs(float(r.group(2)) - t) < 1e-5]
        print(seed, m.group(1),
              'F[', text(fwd[i]), '| before it in its step:', text(fwd[i - 1]) if before else 'none', ']',
              'B[', text(bwd[k]), '| after it in its step:', text(bwd[k + 1]) if after else 'none', ']',
              'R[', '; '.join(second) or 'none', ']')
        sys.stdout.flush()


if __name__ == '__main__':
    main()
