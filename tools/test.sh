#!/usr/bin/env bash
# Build vci and run the whole test suite: the README's test command and what CI runs.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
cmake --preset default
cmake --build --preset default
ctest --preset default
# The API reference (docs/BUILD.md): Doxygen over vci.h and the public modules, failing on an
# undocumented public symbol (install-deps.sh installs doxygen; ctest's api_reference checks the same)
cmake --build --preset default --target vci_docs
# The full configuration, -DVCI_WITH_MPI=ON -DVCI_WITH_OPENMP=ON (preset mpi, build-mpi/): every
# target, and the whole suite in it -- the default one on parallel HDF5, and the tests labelled `mpi`
# (ensembles over ranks, run with mpirun --oversubscribe -np 2; docs/ENSEMBLES.md)
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
