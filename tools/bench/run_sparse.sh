#!/usr/bin/env bash
# docs/bench/sparse.md: the chain with long-range springs (bench/sparse_chain.f90) with dense, banded
# and sparse (KLU) Newton matrices; per step the instructions (callgrind, one dump after each
# vci integrate call; step 1, which holds the set-up, is left out) and the wall time (the bench's
# own medians, one run without valgrind), medians over regular and over impact steps.
# Usage: tools/bench/run_sparse.sh [build dir (default build)] [steps (default 40)] [n ...]
# (default n: 128 256 512; dense is skipped above 256, its impact steps take minutes under callgrind).
set -euo pipefail
build=${1:-build}; steps=${2:-40}; shift $(( $# > 2 ? 2 : $# )) || true
ns=("$@"); [ ${#ns[@]} -eq 0 ] && ns=(128 256 512)
bin="$build/bin/vci_bench_sparse_chain"
export OPENBLAS_NUM_THREADS=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
echo "| n | L | Newton matrices | impact steps | regular step (instructions) | impact step (instructions) | impact / regular | regular step (us) | impact step (us) | sum q^2 at the end |"
echo "|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|"
for n in "${ns[@]}"; do
  for m in dense banded sparse; do
    if [ "$m" = dense ] && [ "$n" -gt 256 ]; then continue; fi
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
print(f"| {n} | {t[2].strip()} | {mode} | {len(imp)} | {mr:.0f} | {mi:.0f} | {mi / mr if mr else 0:.1f} | {t[7].strip()} | {t[8].strip()} | {t[9].strip()} |")
PY
    rm -f "$work"/cg*
  done
done
