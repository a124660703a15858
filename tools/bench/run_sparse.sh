#!/usr/bin/env bash
# docs/bench/sparse.md: the chain with long-range springs (bench/sparse_chain.f90) with dense, banded
# and sparse (KLU) Newton matrices — `sparse` with the dense Hessian callback read in the pattern,
# `sparsecb` with the sparse callback alone; per step the instructions (callgrind, one dump after
# each vci integrate call; step 1, which holds the set-up, is left out) and the wall time (the
# bench's own medians, one run without valgrind), medians over regular and over impact steps, and
# the peak resident memory of the run without valgrind; then the exponents of a least-squares fit of
# log(instructions) against log(n) per mode (over the n it ran).
# Usage: tools/bench/run_sparse.sh [build dir (default build)] [steps (default 40)] [n ...]
# (default n: 128 256 512 1024; under callgrind their impact steps take minutes, so dense runs only
# up to n = 128, banded up to 256, sparse up to 512; sparsecb at every n).
set -euo pipefail
build=${1:-build}; steps=${2:-40}; shift $(( $# > 2 ? 2 : $# )) || true
ns=("$@"); [ ${#ns[@]} -eq 0 ] && ns=(128 256 512 1024)
bin="$build/bin/vci_bench_sparse_chain"
export OPENBLAS_NUM_THREADS=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
echo "| n | L | Newton matrices | impact steps | regular step (instructions) | impact step (instructions) | impact / regular | regular step (us) | impact step (us) | sum q^2 at the end | peak memory (MB) |"
echo "|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|"
for n in "${ns[@]}"; do
  for m in dense banded sparse sparsecb; do
    if [ "$m" = dense ] && [ "$n" -gt 128 ]; then continue; fi
    if [ "$m" = banded ] && [ "$n" -gt 256 ]; then continue; fi
    if [ "$m" = sparse ] && [ "$n" -gt 512 ]; then continue; fi
    "$bin" "$m" "$steps" "$n" > "$work/t" 2> /dev/null
    valgrind --tool=callgrind --dump-after=__vci_integrator_MOD_integrate \
      --callgrind-out-file="$work/cg" "$bin" "$m" "$steps" "$n" > /dev/null 2> "$work/err"
    /usr/bin/python3 - "$work" "$m" "$n" <<'PY'
import glob, re, statistics, sys
work, mode, n = sys.argv[1], sys.argv[2], sys.argv[3]
cls = {}
for line in open(work + '/err'):
    mm = re.match(r'step (\d+) (\d+) impact ([TF])', line)
    if mm: cls[int(mm.group(2))] = mm.group(3) == 'T'
ir = {}
for f in glob.glob(work + '/cg.*'):
    k = int(f.rsplit('.', 1)[1])
    for line in open(f):
        if line.startswith('totals:'): ir[k] = int(line.split()[1])
reg = [ir[k] for k in ir if k > 1 and not cls.get(k, False)]
imp = [ir[k] for k in ir if k > 1 and cls.get(k, False)]
t = open(work + '/t').read().split('|')
mr = statistics.median(reg) if reg else 0
mi = statistics.median(imp) if imp else 0
print(f"| {n} | {t[2].strip()} | {mode} | {len(imp)} | {mr:.0f} | {mi:.0f} | {mi / mr if mr else 0:.1f} | {t[7].strip()} | {t[8].strip()} | {t[9].strip()} | {int(t[10]) / 1024:.1f} |")
with open(work + '/rows', 'a') as f:
    f.write(f"{mode} {n} {mr} {mi}\n")
PY
    rm -f "$work"/cg*
  done
done
/usr/bin/python3 - "$work/rows" <<'PY'
import math, sys
rows = {}
for line in open(sys.argv[1]):
    m, n, r, i = line.split()
    rows.setdefault(m, []).append((float(n), float(r), float(i)))
def slope(pts):
    pts = [p for p in pts if p[1] > 0]
    if len(pts) < 2: return float('nan')
    xs = [math.log(p[0]) for p in pts]; ys = [math.log(p[1]) for p in pts]
    mx = sum(xs) / len(xs); my = sum(ys) / len(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
print()
print("| Newton matrices | n | regular step exponent | impact step exponent |")
print("|---|---|---:|---:|")
for m, pts in rows.items():
    if len(pts) < 2: continue
    print(f"| {m} | {int(pts[0][0])}..{int(pts[-1][0])} | {slope([(n, r) for n, r, i in pts]):.2f} | {slope([(n, i) for n, r, i in pts]):.2f} |")
PY
