#!/usr/bin/env bash
# Timed fuzzing (docs/fuzzing.md). Builds the fuzz targets with clang, libFuzzer, AddressSanitizer
# and UndefinedBehaviorSanitizer in build-fuzz/, runs each target for the given minutes, merges the
# inputs that reached new code into fuzz/corpus/<target>, and records the figures in
# docs/fuzzing/results.json (then rendered into docs/fuzzing.md).
# Usage: fuzz/run.sh [--minutes N] [--parallel P] [TARGET...]   (default: all targets, 10 min, 1 at a time)
# (--when-asked: ctest's FuzzTimed test; it runs only with VOX_FUZZ_TIMED set)
# Exit status: 0 when no target crashed, hung or leaked; 1 otherwise (the inputs are in
# build-fuzz/artifacts/<target>/).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
minutes=10
parallel=1
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --minutes) minutes=$2; shift 2 ;;
    --parallel) parallel=$2; shift 2 ;;
    --when-asked) # from ctest: only when VOX_FUZZ_TIMED is set; 77 tells ctest the test was skipped
      if [ -z "${VOX_FUZZ_TIMED:-}" ]; then
        echo "fuzz/run.sh: the timed fuzzing runs take hours; run them with VOX_FUZZ_TIMED=1 ctest -L fuzz, or fuzz/run.sh"
        exit 77
      fi
      shift ;;
    -h|--help) sed -n '2,9p' "$0"; exit 0 ;;
    -*) echo "fuzz/run.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
    *) targets+=("$1"); shift ;;
  esac
done
all=(nifti metaimage nrrd inr dicom segmentation vdb obj ply stl off scene recording ccd_queries)
[ ${#targets[@]} -gt 0 ] || targets=("${all[@]}")
for t in "${targets[@]}"; do
  [ -d "$root/fuzz/corpus/$t" ] || { echo "fuzz/run.sh: unknown target '$t' (targets: ${all[*]})" >&2; exit 2; }
done

bash "$root/scripts/install-deps.sh" clang-14 libclang-rt-14-dev python3
build=$root/build-fuzz
export CCACHE_BASEDIR=$root
generator=()
if command -v ninja >/dev/null && [ ! -f "$build/Makefile" ]; then generator=(-G Ninja); fi
CC=clang-14 CXX=clang++-14 cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DVOX_FUZZ=ON -DVOX_BUILD_TESTS=OFF -DVOX_BUILD_BENCH=OFF >/dev/null
cmake --build "$build" --target vox_fuzz_all --parallel "$(nproc)"

run_one() {
  local t=$1 exe=$build/fuzz/fuzz_$1 fresh=$build/corpus-new/$1 art=$build/artifacts/$1 log=$build/logs/$1.log
  rm -rf "$art"
  mkdir -p "$fresh" "$art" "$(dirname "$log")"
  local before; before=$(find "$root/fuzz/corpus/$t" -type f | wc -l)
  local max_len=4096 extra=()
  # The .vdb reader's child process has its own memory limit: libFuzzer's limit on single
  # allocations (its default, 2 GB) would count the child's as the parent's failure.
  [ "$t" = vdb ] && max_len=16384 extra=(-malloc_limit_mb=1000000)
  local status=0 start; start=$(date +%s)
  # New inputs go to $fresh; the committed corpus seeds the run and is only read.
  "$exe" -max_total_time=$((minutes * 60)) -timeout=10 -rss_limit_mb=2048 -max_len=$max_len "${extra[@]}" \
    -print_final_stats=1 -artifact_prefix="$art/" "$fresh" "$root/fuzz/corpus/$t" >"$log" 2>&1 || status=$?
  local seconds=$(( $(date +%s) - start ))
  # Keep only what reaches code the corpus does not.
  "$exe" -merge=1 -artifact_prefix="$art/" "${extra[@]}" "$root/fuzz/corpus/$t" "$fresh" >>"$log" 2>&1 || true
  local after; after=$(find "$root/fuzz/corpus/$t" -type f | wc -l)
  local crashes; crashes=$(find "$art" -type f | wc -l)
  # One writer at a time: targets run in parallel.
  flock "$build/results.lock" python3 "$root/fuzz/record_run.py" "$root/docs/fuzzing/results.json" "$t" "$seconds" "$status" \
    "$before" "$after" "$crashes" "$log"
  echo "fuzz: $t: exit $status, corpus $before -> $after files, $crashes artifact(s); log $log"
}

export -f run_one
export root build minutes
# The .vdb reader's child process throws std::bad_alloc at its memory limit, as in the program,
# rather than have AddressSanitizer stop it; its own crashes are the parent's to report.
export ASAN_OPTIONS=allocator_may_return_null=1:allow_user_segv_handler=1
printf '%s\n' "${targets[@]}" | xargs -P "$parallel" -I{} bash -c 'run_one {}'
python3 "$root/fuzz/record_run.py" --render "$root/docs/fuzzing/results.json" "$root/docs/fuzzing.md"
if find "$build/artifacts" -type f | grep -q .; then
  echo "fuzz: failures found; inputs in $build/artifacts" >&2
  exit 1
fi
