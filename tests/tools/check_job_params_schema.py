#!/usr/bin/env python3
"""Independent check of the published job-params schema (python3-jsonschema):
the schema is valid draft 2020-12, its examples validate, and documents that
voxd refuses are refused by the schema too (the contract and the code agree)."""
import json
import sys

import jsonschema

schema_path = sys.argv[1]
schema = json.load(open(schema_path))
jsonschema.Draft202012Validator.check_schema(schema)
validator = jsonschema.Draft202012Validator(schema)

for example in schema["examples"]:
    validator.validate(example)

invalid = [
    {"grid": {"resolution": 0}},
    {"grid": {"resolution": 64, "voxel_size": 1}},
    {"grid": {"voxel_size": 1, "origin": [0, 0, 0]}},
    {"grid": {"voxel_size": -1}},
    {"mode": "solidd"},
    {"inside": "raycast"},
    {"colour": "red"},
    {"rotation": {"axis": [0, 0, 1]}},
    {"orient": "sideways"},
    {"mode": "grey"},
    {"sdf": {"band": 3}},
    {"mode": "sdf", "coverage": {"rays": 2}},
    {"mode": "sdf", "sdf": {"band": "wide"}},
    {"mode": "sdf", "sdf": {"band": 0}},
    {"mode": "sdf", "sdf": {"units": "mm"}},
    {"mode": "coverage", "coverage": {"rays": 65}},
    {"mode": "coverage", "coverage": {"threshold": 0}},
    {"mode": "coverage", "coverage": {"seed": -1}},
    {"mode": "coverage", "inside": "winding"},
    {"mode": "coverage", "coverage": {"points": 8}},
    {"mode": "coverage", "coverage": {"sampling": "exact", "seed": 3}},
    {"mode": "coverage", "coverage": {"threshold": 0.5, "values": "f32"}},
]
for doc in invalid:
    if validator.is_valid(doc):
        print("schema accepts a document voxd refuses:", json.dumps(doc))
        sys.exit(1)
print(f"job-params schema: {len(schema['examples'])} examples valid, {len(invalid)} invalid documents refused")
