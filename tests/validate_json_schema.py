#!/usr/bin/env python3
"""Validates JSON documents against one of the schemas in schemas/.

Usage: validate_json_schema.py SCHEMA INSTANCE [INSTANCE...]
An INSTANCE is a JSON file, '-' for stdin, or a binary shtool table (its JSON header is
validated). "$ref"s to sibling files ("table-header.schema.json") resolve against the
schema's own folder. Exit 0: all valid; 1: some instance invalid (each error printed
with its JSON path); 2: usage, I/O or schema error.
"""
import json
import pathlib
import struct
import sys
import warnings

import jsonschema

MAGIC = b"\x89SHT\r\n\x1a\n"


def load_instance(arg):
    raw = sys.stdin.buffer.read() if arg == "-" else pathlib.Path(arg).read_bytes()
    if raw[:8] == MAGIC:
        (header_len,) = struct.unpack_from("<Q", raw, 8)
        raw = raw[24:24 + header_len]
    return json.loads(raw)


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    try:
        schema_path = pathlib.Path(argv[1]).resolve()
        schema = json.loads(schema_path.read_text())
        cls = jsonschema.validators.validator_for(schema)
        cls.check_schema(schema)
        store = {p.as_uri(): json.loads(p.read_text())
                 for p in schema_path.parent.glob("*.schema.json")}
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            resolver = jsonschema.RefResolver(base_uri=schema_path.as_uri(), referrer=schema,
                                              store=store)
        validator = cls(schema, resolver=resolver)
        instances = [(arg, load_instance(arg)) for arg in argv[2:]]
    except (OSError, ValueError, jsonschema.exceptions.SchemaError) as e:
        print(f"validate_json_schema.py: error: {e}", file=sys.stderr)
        return 2
    status = 0
    for name, instance in instances:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            errors = sorted(validator.iter_errors(instance), key=lambda e: list(e.absolute_path))
        for e in errors:
            where = "/".join(str(p) for p in e.absolute_path) or "(root)"
            print(f"{name}: {where}: {e.message}")
        if errors:
            status = 1
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv))
