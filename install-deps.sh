#!/usr/bin/env bash
# Installs what hopper needs from Debian 12 packages. Idempotent: installs only what is missing.
# Runs apt-get update first (only when something is missing); uses sudo when not root.
set -euo pipefail

packages=(
  build-essential cmake pkg-config git
  libeigen3-dev libboost-program-options-dev libtomlplusplus-dev nlohmann-json3-dev
  libhdf5-dev hdf5-tools libopenmpi-dev openmpi-bin zlib1g-dev
  libgtest-dev googletest
  python3 python3-numpy python3-scipy python3-matplotlib python3-h5py python3-pandas python3-xarray
  python3-venv python3-setuptools python3-wheel  # pip install ./analysis (tests/install)
  pybind11-dev python3-pybind11 python3-dev  # the Python module hopper_engine (docs/usage.md)
  slurm-wlm munge  # the local single-node Slurm of the `slurm` tests (slurm/slurm-up.sh)
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages already installed"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: not root and no sudo; install: ${missing[*]}" >&2; exit 1; }
  SUDO="sudo"
fi
echo "install-deps: installing ${missing[*]}"
$SUDO apt-get update
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends "${missing[@]}"
