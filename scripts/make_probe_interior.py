#!/usr/bin/env python3
"""An interior for bake-probes benchmarks: a closed room (walls, floor, ceiling facing in)
with rows of pillars and a grid of boxes on the floor, tessellated to about TRIANGLES
triangles, written as OBJ (z up: bake with --up z) with a .mtl: white walls, coloured
boxes, one emissive ceiling panel.

Usage: make_probe_interior.py OUT.obj [TRIANGLES]   (default 250000)
"""
import pathlib
import sys


def main():
    out = pathlib.Path(sys.argv[1])
    target = int(sys.argv[2]) if len(sys.argv) > 2 else 250000
    vertices, faces = [], []  # faces: (material, [v0, v1, v2, v3]) quads, 1-based

    def quad_grid(origin, u, v, n, material):
        """An n x n grid of quads spanning origin + s u + t v, s, t in [0, 1] (front: u x v)."""
        base = len(vertices)
        for j in range(n + 1):
            for i in range(n + 1):
                s, t = i / n, j / n
                vertices.append(tuple(origin[k] + s * u[k] + t * v[k] for k in range(3)))
        for j in range(n):
            for i in range(n):
                a = base + j * (n + 1) + i + 1
                faces.append((material, [a, a + 1, a + n + 2, a + n + 1]))

    def box(lo, hi, n, material, inward=False):
        x0, y0, z0 = lo
        x1, y1, z1 = hi
        dx, dy, dz = x1 - x0, y1 - y0, z1 - z0
        sides = [  # outward: u x v points out
            ((x0, y0, z0), (0, 0, dz), (0, dy, 0)),  # -x
            ((x1, y0, z0), (0, dy, 0), (0, 0, dz)),  # +x
            ((x0, y0, z0), (dx, 0, 0), (0, 0, dz)),  # -y
            ((x0, y1, z0), (0, 0, dz), (dx, 0, 0)),  # +y
            ((x0, y0, z0), (0, dy, 0), (dx, 0, 0)),  # -z
            ((x0, y0, z1), (dx, 0, 0), (0, dy, 0)),  # +z
        ]
        for origin, u, v in sides:
            if inward:
                u, v = v, u
            quad_grid(origin, u, v, n, material)

    # The room: 16 x 8 x 4 (x, y, z up); each quad is two triangles.
    room_n = 40
    box((0, 0, 0), (16, 8, 4), room_n, "wall", inward=True)
    quad_grid((7, 3.5, 3.99), (0, 1, 0), (2, 0, 0), 1, "lamp")  # facing down
    used = 2 * len(faces)
    # Boxes and pillars until the target: each unit 6 n^2 quads.
    n = 6
    per = 2 * 6 * n * n
    count = max(0, (target - used) // per)
    cols = max(1, int((count * 2) ** 0.5))
    for k in range(count):
        i, j = k % cols, k // cols
        x = 0.5 + 15.0 * (i + 0.5) / cols
        y = 0.5 + 7.0 * (j + 0.5) / max(1, (count + cols - 1) // cols)
        h = 0.3 + 3.0 * ((k * 0.618034) % 1.0)
        s = 0.6 * 15.0 / cols / 2
        box((x - s / 2, y - s / 2, 0.0), (x + s / 2, y + s / 2, min(h, 3.9)), n, "box%d" % (k % 3))

    mtl = out.with_suffix(".mtl")
    mtl.write_text("newmtl wall\nKd 0.8 0.8 0.8\n"
                   "newmtl lamp\nKd 0 0 0\nKe 40 38 34\n"
                   "newmtl box0\nKd 0.7 0.2 0.2\nnewmtl box1\nKd 0.2 0.6 0.2\nnewmtl box2\nKd 0.2 0.3 0.7\n")
    lines = ["mtllib " + mtl.name]
    lines += ["v %.6f %.6f %.6f" % v for v in vertices]
    current = None
    for material, q in faces:
        if material != current:
            lines.append("usemtl " + material)
            current = material
        lines.append("f %d %d %d %d" % tuple(q))
    out.write_text("\n".join(lines) + "\n")
    print("%s: %d vertices, %d triangles" % (out, len(vertices), 2 * len(faces)))


if __name__ == "__main__":
    main()
