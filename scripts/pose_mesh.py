#!/usr/bin/env python3
"""Poses of an OBJ mesh for `shtool deform` and `render --pose`, same topology.

  scripts/pose_mesh.py IN.obj OUT.obj --rotate ax,ay,az,angle   rigid rotation (radians)
  scripts/pose_mesh.py IN.obj OUT.obj --bend k                  Barr's bend along z, towards +y

The bend (A. H. Barr, Global and Local Deformations of Solid Primitives, SIGGRAPH 1984)
with curvature k (1/units): theta = k z, y' = R - (R - y) cos(theta),
z' = (R - y) sin(theta), R = 1 / k, x unchanged; lines along z become arcs about the axis
(x, y = R, z = 0). Only "v" and "vn" lines change (normals rotate with --rotate; with
--bend they are dropped, so that shtool computes them from the bent surface); every other
line is copied as it is.
"""
import argparse
import math


def rotation(ax, ay, az, angle):
    n = math.sqrt(ax * ax + ay * ay + az * az)
    x, y, z = ax / n, ay / n, az / n
    c, s = math.cos(angle), math.sin(angle)
    return [[c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
            [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s],
            [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)]]


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("input")
    p.add_argument("output")
    g = p.add_mutually_exclusive_group(required=True)
    g.add_argument("--rotate", help="ax,ay,az,angle")
    g.add_argument("--bend", type=float, help="curvature k")
    a = p.parse_args()
    if a.bend is not None and a.bend == 0:
        p.error("--bend: the curvature must not be 0 (0 is the rest pose)")
    r = rotation(*[float(t) for t in a.rotate.split(",")]) if a.rotate else None
    out = []
    with open(a.input) as f:
        for line in f:
            if line.startswith("v ") or line.startswith("vn "):
                tag, *vals = line.split()
                v = [float(t) for t in vals[:3]]
                if r:
                    v = [sum(r[i][j] * v[j] for j in range(3)) for i in range(3)]
                elif tag == "vn":
                    continue
                else:
                    x, y, z = v
                    radius = 1.0 / a.bend
                    theta = a.bend * z
                    v = [x, radius - (radius - y) * math.cos(theta), (radius - y) * math.sin(theta)]
                out.append("%s %.9g %.9g %.9g\n" % (tag, v[0], v[1], v[2]))
            elif line.startswith("f ") and not r:
                # The normals are dropped with --bend: so are the faces' references to them.
                out.append("f " + " ".join(c.split("/")[0] + ("/" + c.split("/")[1] if c.count("/") and c.split("/")[1] else "")
                                           for c in line.split()[1:]) + "\n")
            else:
                out.append(line)
    with open(a.output, "w") as f:
        f.write("".join(out))


if __name__ == "__main__":
    main()
