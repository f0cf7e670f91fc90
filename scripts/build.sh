#!/usr/bin/env bash
# Installs missing Debian packages, then configures and builds VoxSculpt (Release) in ./build.
# Usage: scripts/build.sh   (BUILD_DIR and JOBS may be set in the environment)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${BUILD_DIR:-$root/build}
jobs=${JOBS:-$(nproc)}
# ccache keys on paths relative to the checkout, so another clone of the project reuses the cache.
export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$root}

bash "$root/scripts/install-deps.sh"
generator=()
if command -v ninja >/dev/null && [ ! -f "$build/Makefile" ]; then generator=(-G Ninja); fi
cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release >/dev/null
echo "build: compiling in $build with $jobs jobs"
cmake --build "$build" --parallel "$jobs"
