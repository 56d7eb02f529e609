#!/usr/bin/env bash
# The whole test suite, in two builds (each configured and built here):
#   BUILD_DIR           Release: every test but the label "long" (the larger lobe searches
#                       of tables/regenerate.txt, about 11 minutes on 2 cores; the quick
#                       ones, searches up to order 7 among them, run); SHTOOL_TEST_LONG=1
#                       runs them too;
#   BUILD_DIR-check     clang, ASan + UBSan with no recovery, and libFuzzer's coverage:
#                       every test but the labels "long", "gpu" and "tables" (the shaders
#                       on lavapipe are Mesa's code, not ours, and its LLVM compiles them
#                       once more, so they are not even built here; the shipped tables'
#                       byte comparison checks results, not memory, and its generators are
#                       the unit tests' code) and the export-web page comparison in
#                       Chromium (tests/CMakeLists.txt: three.js's shaders at work; the
#                       shtool processes it compares run here in the case before it), and
#                       each reader's fuzz target for 20 s (label
#                       fuzz) from its committed corpus with a fixed seed.
#                       One ctest test per GoogleTest program there (its cases in one
#                       process), and its command-line tests compiled at -O0.
# The instrumented build compiles with -O1 -g1 (line tables: what a sanitizer's report
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

echo "== instrumented: clang, ASan + UBSan + libFuzzer" >&2
CXX=clang++ cmake -S "$root" -B "$build-check" "${instrumented_flags[@]}" -DSHTOOL_SANITIZE=ON -DSHTOOL_FUZZ=ON \
  -DSHTOOL_BUILD_BENCH=OFF -DSHTOOL_GPU_TESTS=OFF -DSHTOOL_TEST_PER_PROGRAM=ON -DPython3_EXECUTABLE=/usr/bin/python3 >/dev/null
cmake --build "$build-check" -j "$jobs"
stage_done "instrumented build"
ctest --test-dir "$build-check" --output-on-failure -j "$jobs" -LE 'long|gpu|tables'
stage_done "instrumented tests and fuzz runs"
stages+=("$(printf '%-40s %5d s' "total" $(($(date +%s) - started)))")
