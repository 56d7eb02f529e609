#!/usr/bin/env bash
# The main job on defaults: builds, then runs every shtool job that exists on the
# bundled mesh and default orders, writing tables into out/ (or $1), and prints a summary.
#   scripts/demo.sh [OUT_DIR]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${1:-$root/out}"
"$root/scripts/setup.sh" "$root/build" >/dev/null
shtool="$root/build/shtool"
mkdir -p "$out"
echo "shtool demo: tables in $out"
echo "- SH values at (0,0,1), order 3:"
"$shtool" eval --order 3 --dir 0,0,1
