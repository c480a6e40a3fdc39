#!/usr/bin/python3
"""Independent reader of voxd's RLE stream, written from proto-schemas/rle-format.md
alone (it shares no code with the C++ reader), used by tests/core/volume_format_test.cpp
to check that the C++ writer follows the specification.

usage: read_rle.py STREAM OUT

Writes the decoded voxels to OUT in x-fastest, then y, then z order, one value per
voxel, little-endian (bit: one byte 0/1; rgba8: 4 bytes r, g, b, a), and prints a
JSON summary of the header and the voxels on stdout. Exits non-zero on any
violation of the specification.
"""
import json
import struct
import sys

import numpy as np

MAGIC = b"VOXDRLE"
VERSION = 1
SLAB_TAG = 0x53
END_TAG = 0x45
VALUE_DTYPES = {
    "u8": np.dtype("<u1"),
    "u16": np.dtype("<u2"),
    "f32": np.dtype("<f4"),
    "rgba8": np.dtype((np.uint8, (4,))),
}


class SpecError(Exception):
    pass


def read_varint(buf, pos, end):
    """Unsigned LEB128 ending before `end`; returns (value, next position)."""
    value = 0
    for shift in range(0, 70, 7):
        if pos >= end:
            raise SpecError("varint runs past its block at byte %d" % pos)
        byte = buf[pos]
        pos += 1
        value |= (byte & 0x7F) << shift
        if byte < 0x80:
            if value >= 1 << 64:
                raise SpecError("varint exceeds 64 bits")
            return value, pos
    raise SpecError("varint longer than 10 bytes")


def decode_bit_slab(buf, pos, end, slab_voxels):
    lengths = []
    while pos < end:
        length, pos = read_varint(buf, pos, end)
        lengths.append(length)
    values = (np.arange(len(lengths)) % 2).astype(np.uint8)  # 0s first, alternating
    return np.repeat(values, np.array(lengths, dtype=np.int64))


def decode_value_slab(buf, pos, end, dtype):
    lengths, raw = [], bytearray()
    while pos < end:
        length, pos = read_varint(buf, pos, end)
        if pos + dtype.itemsize > end:
            raise SpecError("run value cut by the end of the slab payload")
        lengths.append(length)
        raw += buf[pos:pos + dtype.itemsize]
        pos += dtype.itemsize
    values = np.frombuffer(bytes(raw), dtype=dtype)
    return np.repeat(values, np.array(lengths, dtype=np.int64), axis=0)


def decode(buf):
    if buf[:7] != MAGIC:
        raise SpecError("bad magic")
    if buf[7] != VERSION:
        raise SpecError("unsupported version %d" % buf[7])
    (header_length,) = struct.unpack_from("<I", buf, 8)
    header = json.loads(buf[12:12 + header_length].decode("utf-8"))
    if header["axis_order"] != "xyz":
        raise SpecError("axis_order must be xyz")
    nx, ny, nz = header["dims"]
    value_type = header["value_type"]
    slab_voxels = nx * ny
    pos = 12 + header_length
    slabs = []
    for k in range(nz):
        if buf[pos] != SLAB_TAG:
            raise SpecError("expected a slab block at byte %d" % pos)
        index, pos = read_varint(buf, pos + 1, len(buf))
        if index != k:
            raise SpecError("slab index %d where %d was expected" % (index, k))
        length, pos = read_varint(buf, pos, len(buf))
        end = pos + length
        if end > len(buf):
            raise SpecError("slab %d payload is truncated" % k)
        if value_type == "bit":
            slab = decode_bit_slab(buf, pos, end, slab_voxels)
        else:
            slab = decode_value_slab(buf, pos, end, VALUE_DTYPES[value_type])
        if slab.shape[0] != slab_voxels:
            raise SpecError("slab %d runs cover %d of %d voxels" % (k, slab.shape[0], slab_voxels))
        slabs.append(slab)
        pos = end
    if buf[pos] != END_TAG:
        raise SpecError("expected the end block at byte %d" % pos)
    count, pos = read_varint(buf, pos + 1, len(buf))
    if count != nz:
        raise SpecError("end block counts %d slabs, header %d" % (count, nz))
    if pos != len(buf):
        raise SpecError("%d bytes after the end block" % (len(buf) - pos))
    return header, np.stack(slabs)


def main():
    stream_path, out_path = sys.argv[1], sys.argv[2]
    with open(stream_path, "rb") as f:
        buf = f.read()
    header, voxels = decode(buf)
    with open(out_path, "wb") as f:
        f.write(voxels.tobytes())  # slab k, then y, then x fastest
    nonzero = voxels.reshape(voxels.shape[0] * voxels.shape[1], -1).any(axis=1)
    summary = {
        "dims": header["dims"],
        "origin": header["origin"],
        "voxel_size": header["voxel_size"],
        "value_type": header["value_type"],
        "nonzero_voxels": int(nonzero.sum()),
    }
    print(json.dumps(summary))


if __name__ == "__main__":
    try:
        main()
    except (SpecError, KeyError, ValueError, IndexError) as e:
        print("read_rle.py: %s" % e, file=sys.stderr)
        sys.exit(1)
