#!/bin/bash
# The demo: build vci, run the paper's ellipse and pendulum, and draw the paper's four figures.
#   bash tools/demo.sh
# On a fresh Debian 12 run as root it first installs what is missing (apt-get). Leaves the runs'
# .h5 files, fig1..fig4 PNGs and the ellipse ensemble's plot in demo-output/ (next to build/, in the
# repository root).
set -euo pipefail
cd "$(dirname "$0")/.."

bash tools/install-deps.sh

echo "== configure and build (build/)"
cmake --preset default
cmake --build --preset default

out=demo-output
mkdir -p "$out"
bin=build/bin
echo
echo "== ellipse, 2 s (Fig. 1)"
"$bin/ellipse" --t-final 2 --output "$out/ellipse_2s.h5"
echo
echo "== ellipse, 25 s (Fig. 2)"
"$bin/ellipse" --t-final 25 --output "$out/ellipse_25s.h5"
echo
echo "== pendulum, 5 s, h = 1e-3 (Fig. 3)"
"$bin/pendulum" --t-final 5 --output "$out/pendulum_5s.h5"
echo
echo "== pendulum, 100 s, h = 1e-4 (Fig. 4)"
"$bin/pendulum" --h 1e-4 --t-final 100 --quiet --output "$out/pendulum_100s.h5"
echo
echo "== figures"
/usr/bin/python3 tools/plots/plot_figures.py "$out"
echo
echo "== ellipse ensemble: 121 perturbations of the start, 30 s (docs/ENSEMBLES.md)"
"$bin/ellipse_ensemble" --quiet --output "$out/ellipse_ensemble.h5"
/usr/bin/python3 tools/ensemble/plot_ensemble.py "$out/ellipse_ensemble.h5" "$out/ellipse_ensemble.png"
echo
echo "demo done: $(cd "$out" && pwd)"
ls -l "$out"
