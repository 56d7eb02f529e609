#!/usr/bin/env bash
# The whole test suite, in three builds (each configured and built here):
#   BUILD_DIR           Release: every test but the label "long" (the larger lobe searches
#                       of tables/regenerate.txt, about 11 minutes on 2 cores; the quick
#                       ones, searches up to order 7 among them, run); SHTOOL_TEST_LONG=1
#                       runs them too;
#   BUILD_DIR-sanitize  ASan + UBSan, no recovery: every test but the labels "long" and
#                       "gpu" (shaders on lavapipe: Mesa's code, not ours, and its LLVM
#                       compiles them once more; the C++ around them is test code);
#   BUILD_DIR-fuzz      clang + libFuzzer: each reader's fuzz target for 30 s (label fuzz).
# The instrumented builds compile with -O1 -g1 (line tables: what a sanitizer's report
# prints): half the compile time of -O2 -g, and the whole run has to fit the CI's
# 90 minutes on 2 cores from a cold start.
# Installs what is missing first (scripts/setup.sh).
#   scripts/test.sh [BUILD_DIR]
set -euo pipefail
# The engine checks that run three.js, Babylon.js and splat-transform in node fail here
# when node or npm cannot run them (a plain `ctest` elsewhere skips them, saying why).
export CI="${CI:-1}"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$root/build}"
jobs="$(nproc)"
export CMAKE_GENERATOR="${CMAKE_GENERATOR:-Ninja}"  # as scripts/setup.sh says
instrumented_flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG")

# Each stage's wall time, said when it ends and again together at the end (the CI has
# 90 minutes on 2 cores; this suite's budget is half of that).
started=$(date +%s)
stage_start=$started
stages=()
stage_done() {
  local now
  now=$(date +%s)
  stages+=("$(printf '%-40s %5d s' "$1" $((now - stage_start)))")
  echo "== $1: $((now - stage_start)) s" >&2
  stage_start=$now
}
trap 'if ((${#stages[@]})); then printf "== stage times\n" >&2; printf "   %s\n" "${stages[@]}" >&2; fi' EXIT

"$root/scripts/setup.sh" "$build"
stage_done "setup: packages, Release build"
if [ "${SHTOOL_TEST_LONG:-0}" = 1 ]; then
  ctest --test-dir "$build" --output-on-failure -j "$jobs"
else
  ctest --test-dir "$build" --output-on-failure -j "$jobs" -LE long
fi
stage_done "Release tests"

echo "== sanitizers (ASan + UBSan)" >&2
cmake -S "$root" -B "$build-sanitize" "${instrumented_flags[@]}" -DSHTOOL_SANITIZE=ON \
  -DSHTOOL_BUILD_BENCH=OFF -DPython3_EXECUTABLE=/usr/bin/python3 >/dev/null
cmake --build "$build-sanitize" -j "$jobs"
stage_done "sanitizer build"
ctest --test-dir "$build-sanitize" --output-on-failure -j "$jobs" -LE 'long|gpu'
stage_done "sanitizer tests"

echo "== fuzz targets (clang, libFuzzer)" >&2
CXX=clang++ cmake -S "$root" -B "$build-fuzz" "${instrumented_flags[@]}" -DSHTOOL_FUZZ=ON \
  -DSHTOOL_BUILD_TESTS=OFF -DSHTOOL_BUILD_BENCH=OFF >/dev/null
cmake --build "$build-fuzz" -j "$jobs" --target fuzz_table_reader fuzz_table_kinds fuzz_obj fuzz_json_inputs \
  fuzz_images fuzz_gltf fuzz_ply fuzz_engine_lights
stage_done "fuzz build"
ctest --test-dir "$build-fuzz" --output-on-failure -j "$jobs" -L fuzz
stage_done "fuzz runs"
stages+=("$(printf '%-40s %5d s' "total" $(($(date +%s) - started)))")
