#!/usr/bin/python3
"""Independent PNG reader for the tests: zlib and struct only, no libpng.

Usage: read_png.py FILE [--checksum]
Prints JSON {width, height, bit_depth, color_type, text: {key: value},
pixels: [samples...]} with samples row-major (RGB as r, g, b per pixel,
RGBA as r, g, b, a).
--checksum replaces pixels with sample_count and sample_sum (large images).
Checks the signature, every chunk CRC, IHDR fields and the IEND chunk, and
exits 1 with a message on anything it does not understand.
"""
import json
import struct
import sys
import zlib

SIGNATURE = b"\x89PNG\r\n\x1a\n"
CHANNELS = {0: 1, 2: 3, 6: 4}  # greyscale, RGB, RGBA (the only types voxd writes)


def fail(msg):
    print("read_png: " + msg, file=sys.stderr)
    sys.exit(1)


def paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    if pa <= pb and pa <= pc:
        return a
    return b if pb <= pc else c


def unfilter(raw, height, stride, bpp):
    out = bytearray()
    prev = bytearray(stride)
    pos = 0
    for _ in range(height):
        ftype = raw[pos]
        line = bytearray(raw[pos + 1:pos + 1 + stride])
        pos += 1 + stride
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if ftype == 0:
                pred = 0
            elif ftype == 1:
                pred = a
            elif ftype == 2:
                pred = b
            elif ftype == 3:
                pred = (a + b) // 2
            elif ftype == 4:
                pred = paeth(a, b, c)
            else:
                fail("unknown filter type %d" % ftype)
            line[i] = (line[i] + pred) & 0xFF
        out += line
        prev = line
    if pos != len(raw):
        fail("%d bytes of image data left over" % (len(raw) - pos))
    return out


def main():
    if len(sys.argv) < 2:
        fail("usage: read_png.py FILE [--checksum]")
    data = open(sys.argv[1], "rb").read()
    if data[:8] != SIGNATURE:
        fail("not a PNG signature")
    pos = 8
    header = None
    idat = bytearray()
    text = {}
    saw_end = False
    while pos < len(data):
        if pos + 8 > len(data):
            fail("truncated chunk header")
        length, ctype = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        (crc,) = struct.unpack(">I", data[pos + 8 + length:pos + 12 + length])
        if zlib.crc32(ctype + body) & 0xFFFFFFFF != crc:
            fail("bad CRC in chunk %r" % ctype)
        pos += 12 + length
        if ctype == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif ctype == b"IDAT":
            idat += body
        elif ctype == b"tEXt":
            key, value = body.split(b"\0", 1)
            text[key.decode("latin-1")] = value.decode("latin-1")
        elif ctype == b"IEND":
            saw_end = True
            break
    if header is None or not saw_end:
        fail("missing IHDR or IEND")
    width, height, depth, ctype, comp, filt, interlace = header
    if ctype not in CHANNELS or depth not in (8, 16) or comp or filt or interlace:
        fail("unsupported IHDR %r" % (header,))
    sample_bytes = depth // 8
    bpp = CHANNELS[ctype] * sample_bytes
    raw = zlib.decompress(bytes(idat))
    pixels = unfilter(raw, height, width * bpp, bpp)
    if sample_bytes == 2:
        samples = list(struct.unpack(">%dH" % (len(pixels) // 2), bytes(pixels)))
    else:
        samples = list(pixels)
    result = {"width": width, "height": height, "bit_depth": depth, "color_type": ctype, "text": text}
    if "--checksum" in sys.argv[2:]:
        result["sample_count"] = len(samples)
        result["sample_sum"] = sum(samples)
    else:
        result["pixels"] = samples
    print(json.dumps(result))


main()
