#!/usr/bin/env bash
# Install, from Debian's archive, whatever vci's build, tests and demos need and is missing.
# Usage: tools/install-deps.sh [extra packages...]. Runs apt-get only when something is missing.
set -euo pipefail
packages=(cmake make gfortran gcc liblapack-dev libblas-dev libsuitesparse-dev libhdf5-dev hdf5-tools pkg-config python3
          python3-numpy python3-h5py python3-matplotlib python3-cffi python3-numba python3-sympy python3-pytest
          valgrind doxygen
          openmpi-bin libopenmpi-dev libhdf5-openmpi-dev libasan8 libubsan1 libtsan2 "$@")
missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep "install ok installed" > /dev/null; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0
echo "installing: ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  SUDO=sudo
  command -v sudo >/dev/null || { echo "need root (or sudo) to apt-get install: ${missing[*]}" >&2; exit 1; }
else
  SUDO=
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
