#!/usr/bin/env python3
"""Re-compresses PNG files losslessly: the image data (the concatenated IDAT chunks) is inflated
and deflated again by zlib at level 9 into one IDAT chunk; every other chunk, and so every pixel,
is kept. A file is replaced only when the result is smaller and decodes (with Pillow, a decoder
independent of this script) to exactly the same pixels.

    scripts/recompress_png.py FILE.png ...          # prints before/after sizes per file and in total
    scripts/recompress_png.py --check FILE.png ...  # exit 1 if any file would shrink by >10 %
"""
import argparse
import io
import struct
import sys
import zlib

SIGNATURE = b"\x89PNG\r\n\x1a\n"


def chunks(data):
    if data[:8] != SIGNATURE:
        raise ValueError("not a PNG file")
    pos = 8
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos:pos + 4])
        kind = data[pos + 4:pos + 8]
        yield kind, data[pos + 8:pos + 8 + n]
        pos += 12 + n


def chunk(kind, body):
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)


def recompress(data):
    out, idat, placed = [SIGNATURE], [], False
    parts = list(chunks(data))
    for kind, body in parts:
        if kind == b"IDAT":
            idat.append(body)
    z = zlib.compress(zlib.decompress(b"".join(idat)), 9)
    for kind, body in parts:
        if kind == b"IDAT":
            if not placed:
                out.append(chunk(b"IDAT", z))
                placed = True
        else:
            out.append(chunk(kind, body))
    return b"".join(out)


def pixels(data):
    from PIL import Image  # python3-pil
    im = Image.open(io.BytesIO(data))
    im.load()
    return im.mode, im.size, im.tobytes()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+")
    ap.add_argument("--check", action="store_true", help="change nothing; exit 1 if a file would shrink by >10 %%")
    a = ap.parse_args()
    total_before = total_after = 0
    loose = []
    for f in a.files:
        old = open(f, "rb").read()
        new = recompress(old)
        if pixels(new) != pixels(old):
            sys.exit(f"{f}: the re-compressed pixels differ (not written)")
        after = min(len(new), len(old))
        total_before += len(old)
        total_after += after
        print(f"{f}: {len(old)} -> {after} bytes")
        if len(new) < 0.9 * len(old):
            loose.append(f)
        if not a.check and len(new) < len(old):
            open(f, "wb").write(new)
    print(f"total: {total_before} -> {total_after} bytes")
    if a.check and loose:
        sys.exit(f"{len(loose)} file(s) would shrink by more than 10 %: {', '.join(loose)}")


if __name__ == "__main__":
    main()
