#!/usr/bin/env python3
"""Writes a unit sphere tessellated in latitude and longitude as OBJ, for size tests of
fit-zh (how much memory and time a bake of millions of vertices takes):

    python3 scripts/make_sphere.py ROWS COLS OUT.obj

ROWS - 1 rings of COLS vertices between the two poles: 2 + (ROWS - 1) * COLS vertices and
2 * (ROWS - 1) * COLS triangles, counter-clockwise seen from outside; 1000 x 2000 gives
1,998,002 vertices. Written line by line, so the script holds no mesh in memory.
"""
import math
import sys


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    rows, cols, out = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
    if rows < 2 or cols < 3:
        sys.exit("ROWS must be at least 2 and COLS at least 3")
    with open(out, "w") as f:
        f.write("v 0 0 1\n")
        for i in range(1, rows):
            theta = math.pi * i / rows
            z, r = math.cos(theta), math.sin(theta)
            f.write("".join("v %.7f %.7f %.7f\n" % (r * math.cos(2 * math.pi * j / cols),
                                                    r * math.sin(2 * math.pi * j / cols), z)
                            for j in range(cols)))
        f.write("v 0 0 -1\n")
        south = 2 + (rows - 1) * cols  # 1-based, like every OBJ index

        def ring(i, j):  # 1-based index of vertex j of ring i (1..rows-1)
            return 2 + (i - 1) * cols + j % cols

        f.write("".join("f 1 %d %d\n" % (ring(1, j), ring(1, j + 1)) for j in range(cols)))
        for i in range(1, rows - 1):
            f.write("".join("f %d %d %d\nf %d %d %d\n" % (ring(i, j), ring(i + 1, j), ring(i + 1, j + 1),
                                                            ring(i, j), ring(i + 1, j + 1), ring(i, j + 1))
                            for j in range(cols)))
        f.write("".join("f %d %d %d\n" % (south, ring(rows - 1, j + 1), ring(rows - 1, j)) for j in range(cols)))


if __name__ == "__main__":
    main()
