#!/usr/bin/env bash
# Build vci and run the whole test suite: the README's test command and what CI runs.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
cmake --preset default
cmake --build --preset default
ctest --preset default
# Ensembles over MPI ranks with parallel HDF5: a second, lean build (only what the tests labelled
# `mpi` need; build-mpi/) and those tests, run with mpirun --oversubscribe -np 2 (docs/ENSEMBLES.md)
cmake --preset mpi
cmake --build --preset mpi
ctest --preset mpi
# The C and core suites and the random-input harness (60 s) under AddressSanitizer and
# UndefinedBehaviorSanitizer, leak detection on; the threads test under ThreadSanitizer (docs/TESTING.md).
cmake --preset asan
cmake --build --preset asan
ctest --preset asan
cmake --preset tsan
cmake --build --preset tsan
ctest --preset tsan
