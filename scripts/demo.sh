#!/usr/bin/env bash
# The main job on defaults: builds, then runs every shtool job on the bundled mesh
# (data/spot.obj) and default orders, writes the tables into out/ (or $1) and prints a
# short summary.
#   scripts/demo.sh [OUT_DIR]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${1:-$root/out}"
"$root/scripts/setup.sh" "$root/build" >/dev/null
shtool="$root/build/shtool"
mkdir -p "$out"

echo "== shtool demo -> $out"
echo "-- fit-zh: shadowed PRT transfer on data/spot.obj, order 6, 4 ZH lobes per vertex"
"$shtool" fit-zh "$root/data/spot.obj" --out "$out/spot.zh.shtb" --json "$out/spot.zh.json" \
  --ply "$out/spot.zh.ply"

echo "-- search-lobes: sparse ZHF lobes shared across bands, order 4"
"$shtool" search-lobes --shared --order 4 --seed 1 --quiet --out "$out/zhf-shared-N4.shtb"

echo "-- gen-tensors: rotation helpers, tripling tensor, SH<->Fourier tensors (order 8)"
"$shtool" gen-tensors --out "$out"

echo "-- rotate: the order-3 lobe y_1^0 (along +z) turned 90 degrees about x"
"$shtool" rotate --order 3 --quat 0.7071067811865476,0.7071067811865476,0,0 \
  --coeffs 0,0,1,0,0,0,0,0,0 --tables "$out/rotation-helpers.shtb"

echo "-- tables written (each verified by shtool inspect):"
for table in "$out"/*.shtb; do
  "$shtool" inspect --json "$table" >/dev/null
  printf '   %-28s %s\n' "$(basename "$table")" "$("$shtool" inspect "$table" | sed -n 2p)"
done
echo "== done"
