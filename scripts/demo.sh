#!/usr/bin/env bash
# The main job on defaults: builds, then runs every shtool job on the bundled data
# (data/sky.hdr, data/spot.obj) and default orders, writes the tables into out/ (or $1)
# and prints a short summary.
#   scripts/demo.sh [OUT_DIR]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${1:-$root/out}"
# Its own tree, build-demo/, compiled with clang: GCC 12 spends minutes in its alias
# analysis on the generated rotation kernels (one translation unit takes 87 s of CPU;
# clang takes 9 s), and the `shtool` target builds in about 2 minutes instead of 5.5 on
# 2 cores. clang builds are what the instrumented test tree compiles and tests;
# scripts/test.sh builds the Release tree build/ with the system compiler.
CXX=clang++ "$root/scripts/setup.sh" "$root/build-demo" shtool >/dev/null
shtool="$root/build-demo/shtool"
mkdir -p "$out"

echo "== shtool demo -> $out"
echo "-- project-env: the sky of data/sky.hdr as order-3 radiance and irradiance (exact texel integrals);"
echo "   sky.source.png is the image, sky.back.png its order-3 reconstruction (the sun rings), sky.back.auto.png"
echo "   the same windowed (--window auto), all three with one tone map"
"$shtool" project-env "$root/data/sky.hdr" --order 3 --json "$out/sky.json" --out "$out/sky.shtb" \
  --render-back "$out/sky.back.png" --render-source "$out/sky.source.png"
"$shtool" project-env "$root/data/sky.hdr" --order 3 --window auto --json "$out/sky.auto.json" \
  --render-back "$out/sky.back.auto.png"
"$shtool" project-env "$root/data/sky.hdr" --order 3 --quantity irradiance --json "$out/sky.irradiance.json"
echo "-- light: its sun alone, as a cone of 1.5 degrees (the analytic closed form)"
"$shtool" light --type cone --dir 0.409576,0.709406,0.573576 --half-angle 1.5 --color 2000,1800,1500 --order 3 \
  --json "$out/sun.json"

echo "-- fit-zh: shadowed PRT transfer on data/spot.obj, order 6, 4 ZH lobes per vertex"
"$shtool" fit-zh "$root/data/spot.obj" --out "$out/spot.zh.shtb" --json "$out/spot.zh.json" \
  --ply "$out/spot.zh.ply"

echo "-- render: spot from the front, shaded by its ZH fit under the sky at order 6, windowed (spot.zh.png)"
"$shtool" project-env "$root/data/sky.hdr" --order 6 --window auto --json "$out/sky6.json"
"$shtool" render "$root/data/spot.obj" --fit "$out/spot.zh.shtb" --light "$out/sky6.json" --out "$out/spot.zh.png"

echo "-- fit-glossy: glossy (Cook-Torrance) transfer on data/spot.obj, order 4, and its render (spot.glossy.png)"
"$shtool" fit-glossy "$root/data/spot.obj" --out "$out/spot.glossy.shtb" --json "$out/spot.glossy.json"
"$shtool" project-env "$root/data/sky.hdr" --order 4 --window auto --json "$out/sky4.json"
"$shtool" render "$root/data/spot.obj" --fit "$out/spot.glossy.shtb" --light "$out/sky4.json" --exposure -1 \
  --out "$out/spot.glossy.png"

echo "-- gen-shader: GLSL and HLSL of SH evaluation and zxzxz rotation, order 3"
"$shtool" gen-shader --lang glsl --what sh-eval --order 3 --out "$out/sh_eval.glsl"
"$shtool" gen-shader --lang hlsl --what zxzxz-rotate --order 3 --out "$out/zxzxz_rotate.hlsl"

echo "-- search-lobes: sparse ZHF lobes shared across bands, order 4"
"$shtool" search-lobes --shared --order 4 --seed 1 --quiet --out "$out/zhf-shared-N4.shtb"

echo "-- gen-tensors: rotation helpers, tripling tensor, SH<->Fourier tensors (order 8)"
"$shtool" gen-tensors --out "$out"

echo "-- rotate: the sky's red channel turned 90 degrees about z (the sun moves from azimuth 60 to 150)"
red="$(/usr/bin/python3 -c 'import json, sys; print(",".join(repr(r[0]) for r in json.load(open(sys.argv[1]))["coefficients"]))' \
  "$out/sky.json")"
"$shtool" rotate --order 3 --quat 0.7071067811865476,0,0,0.7071067811865476 --coeffs "$red" \
  --tables "$out/rotation-helpers.shtb"

echo "-- tables written (each verified by shtool inspect):"
for table in "$out"/*.shtb; do
  "$shtool" inspect --json "$table" >/dev/null
  printf '   %-28s %s\n' "$(basename "$table")" "$("$shtool" inspect "$table" | sed -n 2p)"
done
echo "== done"
