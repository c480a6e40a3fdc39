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
    {"device": "cuda"},
    {"mode": "surface", "device": "cuda"},
    {"mode": "palette", "device": "cuda"},
    {"mode": "slice", "slice": {"function": "rock"}, "device": "gpu"},
]
# Palette and slice jobs voxd accepts; the schema must too.
valid = [
    {"mode": "palette"},
    {"mode": "palette", "palette": {}},
    {"mode": "palette", "palette": {"elements": 2, "metric": "inner", "rays": 256, "points": 16, "seed": 18446744073709551615}},
    {"mode": "palette", "palette": {"elements": 10, "voxel_aspect": [0.5, 1000, 1]}},
    {"grid": {"voxel_size": 1, "origin": [0, 0, 0], "dims": [8, 8, 8]}, "mode": "palette", "palette": {"voxel_aspect": [1, 1, 1]}},
    {"mode": "palette", "palette": {"elements": [{"name": "empty", "pieces": []}, {"name": "full", "pieces": [[]]},
                                                 {"name": "slab", "pieces": [[[0, 0, 1, 0.25], [0, 0, -1, 0]]], "complement": False},
                                                 {"name": "not-slab", "pieces": [[[0, 0, 1, 0.25], [0, 0, -1, 0]]], "complement": True},
                                                 {"name": "two-corners", "pieces": [[[1, 1, 1, 1]], [[-1, -1, -1, -2]]]}]}},
    {"mode": "palette", "palette": {"elements": 46, "render": {"full": [{"object": "brick"}],
                                                               "tetra-x0y1z0": [{"object": "corner", "min_similarity": 0.9},
                                                                                {"object": "brick", "min_similarity": 0.5}]}}},
    {"mode": "slice", "slice": {"function": "single_color"}},
    {"mode": "slice", "slice": {"function": "rock"}, "device": "cuda"},
    {"mode": "coverage", "device": "cuda"},
    {"mode": "sdf", "device": "cuda"},
    {"mode": "solid", "device": "cpu"},
    {"device": "auto"},
    {"mode": "slice", "inside": "vote", "slice": {"function": "single_color", "color": [10, 20, 30]}},
    {"mode": "slice", "slice": {"function": "single_color", "color": [10, 20, 30, 1]}},
    {"mode": "slice", "slice": {"function": "single_color", "color": "#A0b0C0"}},
    {"mode": "slice", "slice": {"function": "single_color", "color": "#a0b0c001"}},
    {"mode": "slice", "slice": {"function": "single_color", "color": "#a0b0c010"}},
    {"mode": "slice", "slice": {"function": "color_ramp", "axis": [1, 1, 0], "ramp": [{"position": 0, "color": "#000000"}, {"position": 0.5, "color": [255, 0, 0]}, {"position": 0.5, "color": [0, 255, 0]}, {"position": 1, "color": "#ffffffff"}]}},
    {"mode": "slice", "slice": {"function": "interpolated_colors", "corners": [[255, 0, 0], [0, 255, 0], [0, 0, 255], "#ffffff"]}},
    {"mode": "slice", "slice": {"function": "checker", "checker_colors": [[0, 0, 0], [255, 255, 255]], "checker_size": 0.5}},
    {"mode": "slice", "slice": {"function": "marble", "seed": 0, "noise_scale": 1, "octaves": 16, "period": 2, "turbulence": 0, "noise_colors": ["#ffffff", "#808080", "#202020"]}},
    {"mode": "slice", "slice": {"function": "rock", "seed": 3, "noise_scale": 0.1, "octaves": 1, "noise_colors": [[90, 90, 90], [200, 200, 190]]}},
    {"mode": "slice", "slice": {"function": "custom", "lookup": {"dims": [2, 1, 1], "colors": ["#ff0000", [0, 0, 255, 128]]}}},
]
for doc in valid:
    errors = list(validator.iter_errors(doc))
    if errors:
        print("schema refuses a document voxd accepts:", json.dumps(doc), "-", errors[0].message)
        sys.exit(1)

invalid += [
    {"mode": "palette", "palette": {"metric": "closest"}},
    {"mode": "palette", "palette": {"rays": 0}},
    {"mode": "palette", "palette": {"rays": 257}},
    {"mode": "palette", "palette": {"points": 65}},
    {"mode": "palette", "palette": {"seed": -1}},
    {"mode": "palette", "palette": {"elements": 45}},
    {"mode": "palette", "palette": {"elements": []}},
    {"mode": "palette", "palette": {"elements": "46"}},
    {"mode": "palette", "palette": {"elements": [{"pieces": []}]}},
    {"mode": "palette", "palette": {"elements": [{"name": "x"}]}},
    {"mode": "palette", "palette": {"elements": [{"name": "", "pieces": []}]}},
    {"mode": "palette", "palette": {"elements": [{"name": "x", "pieces": [[[0, 0, 1]]]}]}},
    {"mode": "palette", "palette": {"elements": [{"name": "x", "pieces": [[[0, 0, 0, 1]]]}]}},
    {"mode": "palette", "palette": {"elements": [{"name": "x", "pieces": [], "complement": "yes"}]}},
    {"mode": "palette", "palette": {"elements": [{"name": "x", "pieces": [], "colour": "red"}]}},
    {"mode": "palette", "palette": {"voxel_aspect": [1, 1, 0]}},
    {"mode": "palette", "palette": {"voxel_aspect": [1, 1, 1001]}},
    {"mode": "palette", "palette": {"voxel_aspect": [1, 1]}},
    {"grid": {"voxel_size": 1, "origin": [0, 0, 0], "dims": [8, 8, 8]}, "mode": "palette", "palette": {"voxel_aspect": [1, 1, 0.5]}},
    {"mode": "palette", "palette": {"render": {"full": []}}},
    {"mode": "palette", "palette": {"render": {"full": [{"min_similarity": 0.5}]}}},
    {"mode": "palette", "palette": {"render": {"full": [{"object": "brick", "min_similarity": 1.5}]}}},
    {"mode": "palette", "palette": {"render": {"full": [{"object": "brick"}] * 17}}},
    {"mode": "palette", "palette": {"threshold": 0.5}},
    {"mode": "palette", "inside": "parity"},
    {"mode": "palette", "inside": "winding"},
    {"palette": {"elements": 2}},
    {"mode": "solid", "palette": {"elements": 2}},
    {"mode": "slice"},
    {"mode": "slice", "slice": {}},
    {"mode": "slice", "slice": {"function": "plasma"}},
    {"mode": "slice", "slice": {"function": "single_color", "axis": [0, 0, 0]}},
    {"mode": "slice", "slice": {"function": "color_ramp", "ramp": [{"position": 0, "color": [0, 0, 0]}]}},
    {"mode": "slice", "slice": {"function": "color_ramp", "ramp": [{"position": 0, "color": [0, 0, 0]}, {"position": 1.5, "color": [9, 9, 9]}]}},
    {"mode": "slice", "slice": {"function": "color_ramp", "ramp": [{"position": 0}, {"position": 1, "color": [9, 9, 9]}]}},
    {"mode": "slice", "slice": {"function": "single_color", "color": [1, 2, 3, 0]}},
    {"mode": "slice", "slice": {"function": "single_color", "color": "#01020300"}},
    {"mode": "slice", "slice": {"function": "single_color", "color": [1, 2, 256]}},
    {"mode": "slice", "slice": {"function": "single_color", "color": [1, 2]}},
    {"mode": "slice", "slice": {"function": "single_color", "color": [1, 2, 3, 4, 5]}},
    {"mode": "slice", "slice": {"function": "single_color", "color": "#12345"}},
    {"mode": "slice", "slice": {"function": "single_color", "color": "red"}},
    {"mode": "slice", "slice": {"function": "marble", "color": [1, 2, 3]}},
    {"mode": "slice", "slice": {"function": "single_color", "ramp": [{"position": 0, "color": [0, 0, 0]}, {"position": 1, "color": [9, 9, 9]}]}},
    {"mode": "slice", "slice": {"function": "checker", "corners": [[1, 1, 1], [2, 2, 2], [3, 3, 3], [4, 4, 4]]}},
    {"mode": "slice", "slice": {"function": "interpolated_colors", "corners": [[1, 1, 1], [2, 2, 2], [3, 3, 3]]}},
    {"mode": "slice", "slice": {"function": "wood", "checker_size": 2}},
    {"mode": "slice", "slice": {"function": "checker", "checker_size": 0}},
    {"mode": "slice", "slice": {"function": "checker", "checker_colors": [[0, 0, 0]]}},
    {"mode": "slice", "slice": {"function": "single_color", "seed": 3}},
    {"mode": "slice", "slice": {"function": "color_ramp", "noise_scale": 1}},
    {"mode": "slice", "slice": {"function": "rock", "period": 1}},
    {"mode": "slice", "slice": {"function": "custom"}},
    {"mode": "slice", "slice": {"function": "custom", "lookup": {"dims": [1, 1, 65], "colors": [[1, 2, 3]]}}},
    {"mode": "slice", "slice": {"function": "marble", "lookup": {"dims": [1, 1, 1], "colors": [[1, 2, 3]]}}},
    {"mode": "slice", "slice": {"function": "rock", "turbulence": 1}},
    {"mode": "slice", "slice": {"function": "wood", "octaves": 0}},
    {"mode": "slice", "slice": {"function": "wood", "octaves": 17}},
    {"mode": "slice", "slice": {"function": "wood", "turbulence": -1}},
    {"mode": "slice", "slice": {"function": "marble", "noise_colors": [[1, 1, 1]]}},
    {"mode": "slice", "slice": {"function": "marble", "noise_colors": [[1, 1, 1], [2, 2, 2], [3, 3, 3], [4, 4, 4]]}},
    {"mode": "slice", "slice": {"function": "rock", "noise_colors": [[1, 1, 1], [2, 2, 2, 0]]}},
    {"slice": {"function": "single_color"}},
    {"mode": "solid", "slice": {"function": "single_color"}},
    {"mode": "palette", "slice": {"function": "single_color"}},
    {"mode": "slice", "palette": {}, "slice": {"function": "single_color"}},
]
for doc in invalid:
    if validator.is_valid(doc):
        print("schema accepts a document voxd refuses:", json.dumps(doc))
        sys.exit(1)
print(f"job-params schema: {len(schema['examples'])} examples and {len(valid)} documents valid, {len(invalid)} invalid documents refused")
