#!/usr/bin/env python3
"""Writes the seed corpora of fuzz_gltf, fuzz_ply and fuzz_engine_lights.

    python3 tests/fuzz/make_seeds.py [--shtool build-rel/shtool]

glTF and PLY seeds are built here byte by byte (standard library only, deterministic).
The engine-light seeds are what `shtool export-light` writes for a directional light, one
file per format, and data/sky.hdr as an order-4 raw file: they need a built shtool, and are
skipped without --shtool.
"""
import argparse
import base64
import json
import math
import os
import struct
import subprocess
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
CORPUS = os.path.join(HERE, "corpus")

FLOAT, UBYTE, USHORT, UINT = 5126, 5121, 5123, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963


class Gltf:
    """A glTF document with one buffer, grown view by view."""

    def __init__(self):
        self.bin = bytearray()
        self.doc = {"asset": {"version": "2.0", "generator": "shtool tests/fuzz/make_seeds.py"},
                    "buffers": [], "bufferViews": [], "accessors": [], "meshes": [], "nodes": [],
                    "scenes": [], "scene": 0}

    def view(self, data, target=None, stride=None):
        while len(self.bin) % 4:
            self.bin.append(0)
        v = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if target:
            v["target"] = target
        if stride:
            v["byteStride"] = stride
        self.bin += data
        self.doc["bufferViews"].append(v)
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, view, ctype, count, type_, offset=0, minmax=None):
        a = {"bufferView": view, "componentType": ctype, "count": count, "type": type_}
        if offset:
            a["byteOffset"] = offset
        if minmax:
            a["min"], a["max"] = minmax
        self.doc["accessors"].append(a)
        return len(self.doc["accessors"]) - 1

    def floats(self, rows, type_, target=ARRAY_BUFFER):
        data = b"".join(struct.pack("<%df" % len(r), *r) for r in rows)
        mm = None
        if type_ == "VEC3":
            mm = ([min(r[i] for r in rows) for i in range(3)], [max(r[i] for r in rows) for i in range(3)])
        return self.accessor(self.view(data, target), FLOAT, len(rows), type_, minmax=mm)

    def indices(self, idx, ctype):
        fmt = {UBYTE: "B", USHORT: "H", UINT: "I"}[ctype]
        return self.accessor(self.view(struct.pack("<%d%s" % (len(idx), fmt), *idx), ELEMENT_ARRAY_BUFFER),
                             ctype, len(idx), "SCALAR")

    def gltf_text(self, indent=1):
        doc = json.loads(json.dumps(self.doc))
        doc["buffers"] = [{"byteLength": len(self.bin),
                           "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(self.bin)).decode()}]
        return (json.dumps(doc, indent=indent) + "\n").encode()

    def glb(self):
        doc = json.loads(json.dumps(self.doc))
        doc["buffers"] = [{"byteLength": len(self.bin)}]
        js = json.dumps(doc, separators=(",", ":")).encode()
        js += b" " * (-len(js) % 4)
        bn = bytes(self.bin) + b"\0" * (-len(self.bin) % 4)
        body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(bn), 0x004E4942) + bn
        return b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body


def triangle():
    g = Gltf()
    pos = g.floats([(0, 0, 0), (1, 0, 0), (0, 1, 0)], "VEC3")
    g.doc["meshes"] = [{"primitives": [{"attributes": {"POSITION": pos}}]}]
    g.doc["nodes"] = [{"mesh": 0}]
    g.doc["scenes"] = [{"nodes": [0]}]
    return g


def quad():
    # Positions and normals interleaved (byteStride 24), TEXCOORD_0 as floats, uint16 indices.
    g = Gltf()
    verts = [(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)]
    inter = b"".join(struct.pack("<6f", *v, 0, 1, 0) for v in verts)
    view = g.view(inter, ARRAY_BUFFER, stride=24)
    pos = g.accessor(view, FLOAT, 4, "VEC3", minmax=([-1, 0, -1], [1, 0, 1]))
    nrm = g.accessor(view, FLOAT, 4, "VEC3", offset=12)
    uv = g.floats([(0, 1), (1, 1), (1, 0), (0, 0)], "VEC2")
    idx = g.indices([0, 2, 1, 0, 3, 2], USHORT)
    g.doc["meshes"] = [{"primitives": [{"attributes": {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv},
                                        "indices": idx, "mode": 4}]}]
    g.doc["nodes"] = [{"mesh": 0}]
    g.doc["scenes"] = [{"nodes": [0]}]
    return g


def hierarchy():
    # A tetrahedron (uint8 indices) three levels down: a matrix (column-major), T R S, then
    # the mesh; a mirrored strip (uint32 indices, unsigned-byte UVs) and a line primitive
    # (skipped) beside it; a second scene the default one is not.
    g = Gltf()
    tet = g.floats([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)], "VEC3")
    tet_idx = g.indices([0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3], UBYTE)
    strip = g.floats([(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0), (0, 2, 0)], "VEC3")
    strip_uv = g.accessor(g.view(bytes([0, 0, 255, 0, 0, 128, 255, 128, 0, 255]) + b"\0\0", ARRAY_BUFFER),
                          UBYTE, 5, "VEC2")
    g.doc["accessors"][strip_uv]["normalized"] = True
    strip_idx = g.indices([0, 1, 2, 3, 4], UINT)
    g.doc["meshes"] = [
        {"name": "tetrahedron", "primitives": [{"attributes": {"POSITION": tet}, "indices": tet_idx}]},
        {"name": "strip", "primitives": [{"attributes": {"POSITION": strip, "TEXCOORD_0": strip_uv},
                                          "indices": strip_idx, "mode": 5},
                                         {"attributes": {"POSITION": strip}, "mode": 1}]},
    ]
    c, s = math.cos(0.5), math.sin(0.5)
    g.doc["nodes"] = [
        {"name": "root", "children": [1, 3],
         "matrix": [2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 0.5, -1, 3, 1]},
        {"name": "arm", "children": [2], "translation": [1, 0, 0], "rotation": [0, s, 0, c], "scale": [1, 0.5, 1]},
        {"name": "tet", "mesh": 0},
        {"name": "mirror", "mesh": 1, "scale": [-1, 1, 1]},
        {"name": "elsewhere", "mesh": 0, "translation": [0, 5, 0]},
    ]
    g.doc["scenes"] = [{"nodes": [0]}, {"nodes": [4]}]
    return g


def deep():
    # A triangle whose extras nest 56 arrays deep: below the loader's bound of 64 levels,
    # which mutations cross.
    g = triangle()
    g.doc["extras"] = json.loads("[" * 56 + "1" + "]" * 56)
    return g


def glb_buffer_length_zero():
    # fuzz_gltf's finding: a buffer of byteLength 0 beside a BIN chunk, which tinygltf
    # copied from data.at(0) of an empty vector (now refused with InputError).
    js = json.dumps({"asset": {"version": "2.0"}, "buffers": [{"byteLength": 0}]}, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", 4, 0x004E4942) + b"\0" * 4
    return b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body


def write(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data)


def gltf_seeds():
    d = os.path.join(CORPUS, "gltf")
    for name, make in [("triangle", triangle), ("quad_normals_uv", quad), ("hierarchy", hierarchy)]:
        g = make()
        write(os.path.join(d, name + ".gltf"), g.gltf_text())
        write(os.path.join(d, name + ".glb"), g.glb())
    write(os.path.join(d, "deep_extras.gltf"), deep().gltf_text(indent=None))
    write(os.path.join(d, "glb_buffer_length_zero.glb"), glb_buffer_length_zero())


# 3D Gaussian Splatting's vertex properties (as its training code writes them).
def splat_properties(degree):
    names = ["x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"]
    names += ["f_rest_%d" % k for k in range(3 * ((degree + 1) ** 2 - 1))]
    return names + ["opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"]


def splat_values(names, i):
    out = []
    for k, n in enumerate(names):
        if n.startswith("rot_"):
            out.append(1.0 if n == "rot_0" else 0.0)
        elif n.startswith("scale_"):
            out.append(-3.5 + 0.25 * i)
        elif n[0] == "n":
            out.append(0.0)
        else:
            out.append(round(0.1 * (k + 1) * (1 if i % 2 == 0 else -1) + i, 6))
    return out


def ply(fmt, degree, count, extra_header="", extra_props=(), extra_element=None, crlf=False):
    names = splat_properties(degree)
    lines = ["ply", "format %s 1.0" % fmt, "comment made by shtool tests/fuzz/make_seeds.py"]
    if extra_header:
        lines.append(extra_header)
    lines.append("element vertex %d" % count)
    lines += ["property float %s" % n for n in names]
    lines += ["property %s %s" % (t, n) for t, n in extra_props]
    if extra_element:
        lines.append("element %s %d" % (extra_element[0], extra_element[1]))
        lines += ["property %s %s" % (t, n) for t, n in extra_element[2]]
    lines.append("end_header")
    eol = "\r\n" if crlf else "\n"
    head = (eol.join(lines) + eol).encode()
    codes = {"float": "f", "double": "d", "uchar": "B", "short": "h", "int": "i", "uint": "I", "char": "b",
             "ushort": "H"}
    rows = []
    for i in range(count):
        vals = [("float", v) for v in splat_values(names, i)] + [(t, (i + 1) * 3) for t, _ in extra_props]
        rows.append(vals)
    if extra_element:
        for i in range(extra_element[1]):
            rows.append([(t, i + 0.5 if t in ("float", "double") else i + 1) for t, _ in extra_element[2]])
    if fmt == "ascii":
        body = "".join(" ".join(repr(v) if isinstance(v, float) else str(v) for _, v in r) + eol for r in rows)
        return head + body.encode()
    order = "<" if fmt == "binary_little_endian" else ">"
    return head + b"".join(struct.pack(order + "".join(codes[t] for t, _ in r), *[v for _, v in r]) for r in rows)


def ply_seeds():
    d = os.path.join(CORPUS, "ply")
    write(os.path.join(d, "splats_deg0_ascii.ply"), ply("ascii", 0, 3))
    write(os.path.join(d, "splats_deg1_ascii_crlf.ply"), ply("ascii", 1, 2, crlf=True, extra_props=[("uchar", "red")]))
    write(os.path.join(d, "splats_deg0_le.ply"), ply("binary_little_endian", 0, 4))
    write(os.path.join(d, "splats_deg1_le.ply"),
          ply("binary_little_endian", 1, 2, extra_header="obj_info trained 30000 iterations"))
    write(os.path.join(d, "splats_deg1_be.ply"),
          ply("binary_big_endian", 1, 2, extra_props=[("double", "weight"), ("ushort", "id")],
              extra_element=("camera", 1, [("float", "fx"), ("int", "width")])))


FORMATS = ["threejs", "filament", "filament-radiance", "unity", "gltf", "gltf-khr", "babylon", "godot", "raw"]
EXTENSION = {"threejs": "json", "filament": "txt", "filament-radiance": "txt", "unity": "json", "gltf": "gltf",
             "gltf-khr": "gltf", "babylon": "json", "godot": "json", "raw": "json"}


def light_seeds(shtool):
    d = os.path.join(CORPUS, "engine_lights")
    os.makedirs(d, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        light = os.path.join(tmp, "l.json")
        subprocess.run([shtool, "light", "--type", "directional", "--dir", "0.3,0.4,0.866", "--json", light],
                       check=True)
        for f in FORMATS:
            subprocess.run([shtool, "export-light", light, "--format", f, "--out",
                            os.path.join(d, "%s.%s" % (f, EXTENSION[f]))], check=True)
        # data/sky.hdr as order-4 irradiance: a raw file with a band the engine formats drop.
        sky = os.path.join(tmp, "sky.json")
        subprocess.run([shtool, "project-env", os.path.join(HERE, "..", "..", "data", "sky.hdr"), "--order", "4",
                        "--quantity", "irradiance", "--json", sky, "--threads", "1"], check=True)
        subprocess.run([shtool, "export-light", sky, "--format", "raw", "--norm", "schmidt",
                        "--out", os.path.join(d, "raw_sky_order4_schmidt.json")], check=True)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--shtool", help="a built shtool, for the engine-light seeds")
    a = p.parse_args()
    gltf_seeds()
    ply_seeds()
    if a.shtool:
        light_seeds(a.shtool)


if __name__ == "__main__":
    main()
