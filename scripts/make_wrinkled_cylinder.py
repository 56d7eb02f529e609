#!/usr/bin/env python3
"""Writes [4] Fig. 6ab's wrinkle setup: a smooth open cylinder (OBJ) and the groove
coordinates of `shtool render --shading wrinkle --wrinkle-map` (JSON), the groove
position a function of the angle around the cylinder:

    python3 scripts/make_wrinkled_cylinder.py OUT.obj OUT.json [--grooves 12] [--rows 64]
        [--cols 384] [--radius 0.5] [--length 2] [--depth 0,1]

The cylinder's axis is z (so `scripts/pose_mesh.py --bend k` bends it), z in
[-length/2, length/2]; ROWS + 1 rings of COLS vertices, the seam shared (no duplicate
vertices), no caps, triangles counter-clockwise seen from outside. Per vertex at angle
phi = atan2(y, x) and height z:
    x = grooves * phi / (2 pi)  (x grows counter-clockwise about +z; a whole number of
                                 grooves, so x is continuous modulo 1 across the seam)
    d = d0 + (d1 - d0) (z / length + 1/2)  (depth grows linearly along the axis)
so the grooves run along the axis. COLS / grooves vertices per period (32 by default):
the renderer shades per vertex, so fewer blur the groove, and 2 or fewer make x's
direction ambiguous.
"""
import argparse
import json
import math


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("obj")
    p.add_argument("json")
    p.add_argument("--grooves", type=int, default=12)
    p.add_argument("--rows", type=int, default=64)
    p.add_argument("--cols", type=int, default=384)
    p.add_argument("--radius", type=float, default=0.5)
    p.add_argument("--length", type=float, default=2.0)
    p.add_argument("--depth", default="0,1", help="d0,d1: depth at z = -length/2 and at z = +length/2, in periods")
    a = p.parse_args()
    d0, d1 = (float(t) for t in a.depth.split(","))
    if a.grooves < 1 or a.rows < 1 or a.cols < 3 or a.radius <= 0 or a.length <= 0:
        p.error("need grooves >= 1, rows >= 1, cols >= 3, positive radius and length")
    if a.cols <= 2 * a.grooves:
        p.error("--cols must exceed 2 x --grooves (more than two vertices per groove period)")
    if min(d0, d1) < 0:
        p.error("--depth: depths must not be negative")
    xs, ds, lines = [], [], []
    for i in range(a.rows + 1):
        t = i / a.rows
        z = a.length * (t - 0.5)
        for j in range(a.cols):
            phi = 2 * math.pi * j / a.cols
            lines.append("v %.9f %.9f %.9f\n" % (a.radius * math.cos(phi), a.radius * math.sin(phi), z))
            xs.append(a.grooves * j / a.cols)
            ds.append(d0 + (d1 - d0) * t)

    def vid(i, j):  # 1-based OBJ index of ring i, column j (the seam wraps)
        return 1 + i * a.cols + j % a.cols

    for i in range(a.rows):
        for j in range(a.cols):
            lines.append("f %d %d %d\n" % (vid(i, j), vid(i, j + 1), vid(i + 1, j + 1)))
            lines.append("f %d %d %d\n" % (vid(i, j), vid(i + 1, j + 1), vid(i + 1, j)))
    with open(a.obj, "w") as f:
        f.write("# make_wrinkled_cylinder.py: %d grooves, %d x %d vertices\n" % (a.grooves, a.rows + 1, a.cols))
        f.writelines(lines)
    with open(a.json, "w") as f:
        json.dump({"x": xs, "d": ds}, f)


if __name__ == "__main__":
    main()
