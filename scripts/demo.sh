#!/usr/bin/env bash
# The main job on defaults: builds, then runs every shtool job that exists so far on
# default orders, writes the tables into out/ (or $1) and prints a short summary.
#   scripts/demo.sh [OUT_DIR]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${1:-$root/out}"
"$root/scripts/setup.sh" "$root/build" >/dev/null
shtool="$root/build/shtool"
mkdir -p "$out"

echo "== shtool demo -> $out"
echo "-- gen-tensors (default order)"
"$shtool" gen-tensors --out "$out"
for table in "$out"/*.shtb; do
  "$shtool" inspect "$table" | head -n 3
done

echo "-- rotate: the order-3 lobe y_1^0 (along +z) turned 90 degrees about x, auto method"
"$shtool" rotate --order 3 --quat 0.7071067811865476,0.7071067811865476,0,0 \
  --coeffs 0,0,1,0,0,0,0,0,0 --tables "$out/rotation-helpers.shtb"

echo "-- eval: the 9 SH values of order 3 at (0.3, -0.5, 0.8)"
"$shtool" eval --order 3 --dir 0.3,-0.5,0.8
echo "== done: $(ls "$out" | wc -l) tables in $out"
