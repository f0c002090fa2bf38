#!/usr/bin/env python3
"""Decodes a greyscale PNG with two decoders independent of lsmbs's writer, Pillow and a minimal
one here (struct + zlib, every PNG filter type), and compares the pixels with the raw bytes that
were drawn. Usage: png_check.py IMAGE.png DRAWN.raw WIDTH HEIGHT; exit 0 when all agree."""
import struct
import sys
import zlib


def decode(data):
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "PNG signature"
    pos, idat, ihdr = 8, b"", None
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]
        (crc,) = struct.unpack(">I", data[pos + 8 + n:pos + 12 + n])
        assert zlib.crc32(kind + body) & 0xFFFFFFFF == crc, f"CRC of {kind}"
        if kind == b"IHDR":
            ihdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    w, h, depth, color, _, _, interlace = ihdr
    assert depth == 8 and color == 0 and interlace == 0, ihdr
    raw, out, prev = zlib.decompress(idat), bytearray(), bytearray(w)
    for y in range(h):
        f, line = raw[y * (w + 1)], bytearray(raw[y * (w + 1) + 1:(y + 1) * (w + 1)])
        for x in range(w):
            a = line[x - 1] if x else 0
            b, c = prev[x], prev[x - 1] if x else 0
            if f == 1:
                line[x] = (line[x] + a) & 255
            elif f == 2:
                line[x] = (line[x] + b) & 255
            elif f == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
            else:
                assert f == 0, f"filter {f}"
        out += line
        prev = line
    return w, h, bytes(out)


png, drawn, w, h = open(sys.argv[1], "rb").read(), open(sys.argv[2], "rb").read(), int(sys.argv[3]), int(sys.argv[4])
W, H, px = decode(png)
assert (W, H) == (w, h), ((W, H), (w, h))
assert px == drawn, "struct+zlib decoder: pixels differ from the drawn ones"
try:
    from PIL import Image
    im = Image.open(sys.argv[1])
    assert im.mode == "L" and im.size == (w, h), (im.mode, im.size)
    assert im.tobytes() == drawn, "Pillow: pixels differ from the drawn ones"
    print("Pillow and struct+zlib decoders: pixels equal")
except ImportError:
    print("struct+zlib decoder: pixels equal (Pillow not installed)")
