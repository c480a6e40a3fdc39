#!/usr/bin/python3
"""Independent binvox reader, written from the format description at
https://www.patrickmin.com/binvox/binvox.html the way common readers (binvox_rw)
do it, used by tests/core/volume_format_test.cpp to check the C++ writer.

usage: read_binvox.py FILE OUT

Writes the D^3 voxel values to OUT in x-fastest, then y, then z order (one byte
per voxel) and prints a JSON summary on stdout, including the model-space centre
of the first set voxel in that order, computed as ((i + 0.5) / D) * scale + translate.
"""
import json
import sys

import numpy as np


def read_binvox(buf):
    pos = 0

    def next_line():
        nonlocal pos
        end = buf.index(b"\n", pos)
        line = buf[pos:end].decode("ascii").strip()
        pos = end + 1
        return line

    first = next_line().split()
    if first[0] != "#binvox" or first[1] not in ("1", "2"):
        raise ValueError("not a binvox file")
    version = int(first[1])
    dims, translate, scale = None, [0.0, 0.0, 0.0], 1.0
    while True:
        words = next_line().split()
        if not words:
            continue
        if words[0] == "dim":
            dims = [int(w) for w in words[1:4]]
        elif words[0] == "translate":
            translate = [float(w) for w in words[1:4]]
        elif words[0] == "scale":
            scale = float(words[1])
        elif words[0] == "data":
            break
    d = dims[0]
    if dims != [d, d, d]:
        raise ValueError("non-cubic dims")
    data = np.frombuffer(buf[pos:], dtype=np.uint8)
    values, counts = data[0::2], data[1::2]
    values = values[:counts.size]
    voxels = np.repeat(values, counts.astype(np.int64))
    if voxels.size < d ** 3:
        raise ValueError("data covers %d of %d voxels" % (voxels.size, d ** 3))
    # index = x * D * D + z * D + y: the array is [x][z][y]
    xzy = voxels[:d ** 3].reshape(d, d, d)
    xyz = xzy.transpose(0, 2, 1)
    return version, d, translate, scale, xyz


def main():
    path, out_path = sys.argv[1], sys.argv[2]
    with open(path, "rb") as f:
        buf = f.read()
    version, d, translate, scale, xyz = read_binvox(buf)
    zyx = np.ascontiguousarray(xyz.transpose(2, 1, 0))
    with open(out_path, "wb") as f:
        f.write(zyx.tobytes())  # x fastest, then y, then z
    summary = {"version": version, "dim": d, "translate": translate, "scale": scale,
               "nonzero_voxels": int(np.count_nonzero(xyz))}
    set_voxels = np.argwhere(zyx != 0)
    if set_voxels.size:
        k, j, i = (int(v) for v in set_voxels[0])
        summary["first_set_voxel"] = [i, j, k]
        summary["first_set_center"] = [(c + 0.5) / d * scale + t for c, t in zip((i, j, k), translate)]
    print(json.dumps(summary))


if __name__ == "__main__":
    try:
        main()
    except (ValueError, IndexError, KeyError) as e:
        print("read_binvox.py: %s" % e, file=sys.stderr)
        sys.exit(1)
