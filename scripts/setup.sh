#!/usr/bin/env bash
# Installs the Debian packages shtool needs (only those missing), then configures and
# builds it in Release: every target, or only the TARGETs named (the demo builds the
# `shtool` executable alone, not the tests and benchmarks it never runs). Idempotent: a
# second run installs nothing and rebuilds only what changed. CXX, when set, is the
# compiler of a new tree (CMake reads it at the first configure only): the demo passes
# clang++, the test suite leaves the system compiler.
#   scripts/setup.sh [BUILD_DIR [TARGET...]]     (default: build, every target)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$root/build}"
targets=("${@:2}")

packages=(
  g++ cmake make ninja-build pkg-config
  libeigen3-dev libfftw3-dev nlohmann-json3-dev          # runtime library
  libcli11-dev libnlopt-cxx-dev libembree-dev libtinyobjloader-dev  # offline tool
  libopenexr-dev libstb-dev zlib1g-dev libzstd-dev       # offline tool: images, input CRCs, spz splats
  libtinygltf-dev                                        # offline tool: glTF meshes
  libopenmpi-dev openmpi-bin                             # fit-zh --mpi (optional at build time)
  libgtest-dev libbenchmark-dev                          # tests and benchmarks
  glslang-tools spirv-tools libvulkan-dev mesa-vulkan-drivers  # shader tests (lavapipe: a CPU Vulkan device)
  clang libclang-rt-14-dev                               # fuzz targets (libFuzzer), sanitizers
  python3 python3-jsonschema python3-numpy               # schema checks, numpy reader test
  python3-dev pybind11-dev python3-pybind11 python3-scipy python3-pytest python3-venv  # Python module and its tests
  chromium                                               # page tests: headless WebGL2 on SwiftShader
)
# The engine checks run three.js and Babylon.js in node (npm installs them into the
# build folder at test time). A machine image's own Node.js is used as it is: Debian's
# npm conflicts with it, so Debian's nodejs and npm are installed only when node is absent.
if ! command -v node >/dev/null 2>&1; then packages+=(nodejs npm); fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing missing Debian packages: ${missing[*]}" >&2
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
fi

# Ninja, where the tree is new: it compiles a target's objects while the libraries they
# link are still being built, so both cores stay busy (an existing tree keeps its generator).
export CMAKE_GENERATOR="${CMAKE_GENERATOR:-Ninja}"
# The Debian interpreter: the one the packages above (jsonschema, numpy) belong to.
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE=/usr/bin/python3 >/dev/null
cmake --build "$build" -j "$(nproc)" ${targets[@]:+--target "${targets[@]}"}
