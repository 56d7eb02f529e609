#!/usr/bin/env python3
"""Reads a binary shtool table with numpy alone (plus the standard library).

The function between the "doc example" markers is printed verbatim in
docs/table-format.md; test_table checks that the two agree and runs this script on a
table written by the C++ writer, so the documented reader cannot rot.

Usage: read_table_numpy.py TABLE
Prints one JSON object: {"header": {...}, "arrays": {name: {"dtype", "shape", "values"}}},
values flattened row-major; Python's json writes floats with round-trip precision.
"""
import sys

# --- begin doc example ---
import json
import struct
import zlib

import numpy as np

MAGIC = b"\x89SHT\r\n\x1a\n"
DTYPES = {"f64": "<f8", "f32": "<f4", "i32": "<i4", "u32": "<u4",
          "i64": "<i8", "u64": "<u8", "u8": "u1"}


def read_table(path):
    """Returns (header dict, {name: numpy array}) of a binary shtool table."""
    with open(path, "rb") as f:
        buf = f.read()
    if len(buf) < 24 or buf[:8] != MAGIC:
        raise ValueError(f"{path}: not a binary shtool table (magic {buf[:8]!r})")
    header_len, header_crc, _reserved = struct.unpack_from("<QII", buf, 8)
    header_bytes = buf[24:24 + header_len]
    if len(header_bytes) != header_len or zlib.crc32(header_bytes) != header_crc:
        raise ValueError(f"{path}: header truncated or corrupted")
    header = json.loads(header_bytes)
    if header["format_version"].split(".")[0] != "1":
        raise ValueError(f"{path}: unsupported format {header['format_version']}")
    data_start = (24 + header_len + 63) // 64 * 64
    arrays = {}
    for a in header["arrays"]:
        begin = data_start + a["offset"]
        raw = buf[begin:begin + a["nbytes"]]
        if len(raw) != a["nbytes"] or zlib.crc32(raw) != a["crc32"]:
            raise ValueError(f"{path}: array {a['name']!r} truncated or corrupted")
        arrays[a["name"]] = np.frombuffer(raw, dtype=DTYPES[a["dtype"]]).reshape(a["shape"])
    return header, arrays
# --- end doc example ---


def main(argv):
    if len(argv) != 2:
        print("usage: read_table_numpy.py TABLE", file=sys.stderr)
        return 2
    try:
        header, arrays = read_table(argv[1])
    except (OSError, ValueError, KeyError) as e:
        print(f"read_table_numpy.py: error: {e}", file=sys.stderr)
        return 1
    out = {"header": header, "arrays": {}}
    for name, a in arrays.items():
        out["arrays"][name] = {"dtype": str(a.dtype), "shape": list(a.shape),
                               "values": a.ravel().tolist()}
    print(json.dumps(out, allow_nan=False))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
