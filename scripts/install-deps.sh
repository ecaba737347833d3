#!/usr/bin/env bash
# Installs the Debian packages skelcd builds and tests with, but only those that are missing.
# Called by `make`; safe to run again. Needs root or sudo when something is missing.
# Extra packages may be named as arguments (make fuzz: clang-14 libclang-rt-14-dev).
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libassimp-dev assimp-testmodels liburdfdom-dev
  libhdf5-dev hdf5-tools zlib1g-dev libgtest-dev libgmock-dev libbenchmark-dev
  libtbb-dev libgmp-dev libcli11-dev libtomlplusplus-dev
  libplplot-dev plplot-driver-cairo
  nlohmann-json3-dev python3-h5py
  libtinyxml-dev libconsole-bridge-dev  # used directly by skinning/urdf*.cpp (SRDF, urdfdom messages)
  libpugixml-dev  # the Collada extras assimp does not hand over (skinning/detail/collada_bind_shape.cpp)
  pybind11-dev python3-pybind11 python3-dev python3-numpy python3-pytest  # the Python module (python/)
  python3-distributed  # skelcd.batch: clips as tasks on a Dask cluster
  "$@"
)

missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$p")
done
[[ ${#missing[@]} -eq 0 ]] && exit 0

echo "install-deps: installing ${missing[*]}" >&2
sudo_cmd=()
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null || { echo "install-deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo_cmd=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
