#!/usr/bin/env bash
# Command 2 of the README: install, build, and run the whole test suite; non-zero on any failure.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${BUILD_DIR:-$root/build}
bash "$root/scripts/build.sh"
cd "$build"
# The timed fuzzing runs (label fuzz) take hours: `VOX_FUZZ_TIMED=1 ctest -L fuzz` runs them on
# purpose; the long random samples (label long) run with `ctest -L long`.
ctest --output-on-failure --no-tests=error --parallel "${JOBS:-$(nproc)}" -LE '^(fuzz|long)$' "$@"
