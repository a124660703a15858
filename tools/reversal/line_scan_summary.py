#!/usr/bin/env python3
"""Summary of the impulse-line scan (tools/reversal/line_scan.patch, docs/BACKWARD.md "Two roots
on the impulse line"): reads the output of

  GFORTRAN_UNBUFFERED_ALL=y VCI_DEBUG_SCAN=1 VCI_FUZZ_VERBOSE=1 build/test/fuzz/vci_fuzz --reversal 1 20000 1800

(a build with the patch applied) and counts, for the left rule and the symmetric schemes, the
impacts scanned, those whose scan solved every sub-step ("reliable"), and those where the leaving
roots of e2 = E- or the arriving roots of e1 = E- number two or more (MULTIROOT), with the runs."""
import collections
import re
import sys

buf, stats, multi = [], collections.Counter(), []
for line in open(sys.argv[1]):
    line = line.rstrip('\n')
    if line.startswith('ROOTS') or line == 'MULTIROOT':
        buf.append(line)
        continue
    m = re.match(r'reversal seed (\d+): kind (\d) n (\d+) ng (\d+) (\w+) s (\d+)', line)
    if not m:
        continue
    scheme = m.group(5) + (' s' + m.group(6) if m.group(5) in ('lobatto', 'composition') else '')
    family = 'left' if scheme == 'left' else 'symmetric'
    for i, b in enumerate(buf):
        if not b.startswith('ROOTS'):
            continue
        reliable = b.endswith('fails   0')
        stats[family, 'impacts'] += 1
        stats[family, 'reliable'] += reliable
        if i + 1 < len(buf) and buf[i + 1] == 'MULTIROOT':
            stats[family, 'multiroot', 'reliable' if reliable else 'with failed scan sub-steps'] += 1
            if reliable:
                multi.append(f"seed {m.group(1)} {scheme}: {b}\n    run: {line.split(': status')[-1][:150]}")
    buf = []
for key in sorted(stats, key=str):
    print(' '.join(key), stats[key])
print('\n'.join(multi))
