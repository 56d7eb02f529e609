#!/usr/bin/env python3
"""Writes data/sky.hdr, the procedural environment of the README demo (CC0).

A 256 x 128 equirect in shtool's mapping (row 0 at +z, the image centre facing +x, the
azimuth growing to the left): a blue sky brightening towards the horizon, a warm sun of
radiance 2e3 and 3 degrees across at (elevation 35, azimuth 60 degrees), and a grey-green
ground. Flat (not run-length encoded) Radiance RGBE, so the file is exactly
reproducible: `python3 scripts/make_demo_sky.py data/sky.hdr`.
"""
import math
import struct
import sys

W, H = 256, 128
SUN_ELEVATION, SUN_AZIMUTH, SUN_RADIUS = math.radians(35), math.radians(60), math.radians(1.5)
sun = (math.cos(SUN_ELEVATION) * math.cos(SUN_AZIMUTH), math.cos(SUN_ELEVATION) * math.sin(SUN_AZIMUTH),
       math.sin(SUN_ELEVATION))


def radiance(w):
    z = w[2]
    if sum(a * b for a, b in zip(w, sun)) >= math.cos(SUN_RADIUS):
        return (2000.0, 1800.0, 1500.0)
    if z < 0:
        return (0.12, 0.13, 0.10)
    haze = (1 - z) ** 3
    return (0.25 + 0.9 * haze, 0.45 + 0.8 * haze, 1.0 + 0.5 * haze)


def rgbe(c):
    m = max(c)
    if m < 1e-32:
        return bytes(4)
    mant, exp = math.frexp(m)
    scale = mant * 256.0 / m
    return bytes([int(c[0] * scale), int(c[1] * scale), int(c[2] * scale), exp + 128])


def main(path):
    out = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (H, W))
    for y in range(H):
        t = math.pi * (y + 0.5) / H
        for x in range(W):
            p = math.pi - 2 * math.pi * (x + 0.5) / W
            w = (math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t))
            out += rgbe(radiance(w))
    with open(path, "wb") as f:
        f.write(out)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "data/sky.hdr")
