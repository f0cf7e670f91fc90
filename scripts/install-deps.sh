#!/usr/bin/env bash
# Installs the Debian packages VoxSculpt needs, and any named as arguments, only those missing
# (idempotent).
# Runs apt-get as root, or through sudo when not root.
set -euo pipefail

packages=(
  build-essential cmake ninja-build ccache pkg-config
  libopenvdb-dev libboost-iostreams-dev libtbb-dev libblosc-dev libimath-dev
  libeigen3-dev libopenmesh-dev libglfw3-dev libglm-dev libhidapi-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  nlohmann-json3-dev libcli11-dev libnifti2-dev libspdlog-dev zlib1g-dev libstb-dev
  libegl-dev libegl-mesa0 libgl1-mesa-dri libgl-dev xvfb xauth
  libsuitesparse-dev libopenblas0-serial
  libgdcm-dev
  # the tests' independent readers and writers (run with /usr/bin/python3, Debian's)
  python3 python3-pydicom python3-numpy python3-nibabel python3-meshio
  nodejs # npm's gltf-validator checks the .glb files (tests/tools/gltf)
)
packages+=("$@") # extra packages a caller needs (fuzz/run.sh: clang)
# Debian's nodejs comes without npm (NodeSource's includes it).
command -v npm >/dev/null || packages+=(npm)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${#missing[@]} missing package(s): ${missing[*]}"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: not root and no sudo; install as root: apt-get install -y ${missing[*]}" >&2; exit 1; }
  sudo_cmd=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -q
"${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
