#!/usr/bin/env python3
"""The small images `tests/scene_fuzz.rs` mutates (beside tests/data/texture/): one per decoder
path that file set leaves out. Writes tests/data/fuzz-images/:

    palette.png      6 x 5, 8-bit palette (expanded to RGB by the decoder)
    rgba.png         5 x 4, 8-bit RGBA (alpha dropped)
    grey16.png       4 x 3, 16-bit grey
    adam7.png        9 x 7, 8-bit RGB, Adam7-interlaced (written here: Pillow writes none)
    progressive.jpg  16 x 16, progressive JPEG
    grey.jpg         16 x 8, greyscale JPEG
    half-zip.exr     8 x 6, half R, G, B, ZIP compression
    tiled-piz.exr    8 x 8, float R, G, B in 4 x 4 tiles, PIZ compression
    y-rle.exr        7 x 5, a lone half Y channel, RLE compression
    rle.hdr          16 x 4, Radiance RGBE with run-length scanlines (Mitsuba's writer: `#?RGBE`)

Every texel is finite and non-negative, so each file loads unmutated. Usage (the venv with the
pip packages mitsuba 3.9, numpy, Pillow and OpenEXR): python scripts/fuzz-images.py
"""
import struct
import zlib
from pathlib import Path

import mitsuba as mi
import numpy as np
import OpenEXR
from PIL import Image

OUT = Path(__file__).resolve().parent.parent / "tests" / "data" / "fuzz-images"


def ramp(w, h, c, scale=1.0):
    """A smooth, non-negative test pattern of shape (h, w, c)."""
    y, x, k = np.mgrid[0:h, 0:w, 0:c]
    return scale * (0.5 + 0.45 * np.sin(0.9 * x + 0.6 * y + 1.7 * k))


def png_chunk(kind, body):
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))


def adam7_png(w, h):
    px = (ramp(w, h, 3) * 255).round().astype(np.uint8)
    passes = [(0, 0, 8, 8), (4, 0, 8, 8), (0, 4, 4, 8), (2, 0, 4, 4), (0, 2, 2, 4), (1, 0, 2, 2), (0, 1, 1, 2)]
    raw = b""
    for x0, y0, dx, dy in passes:
        sub = px[y0::dy, x0::dx]
        if sub.size:
            raw += b"".join(b"\0" + row.tobytes() for row in sub)
    ihdr = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 1)
    return b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", ihdr) + png_chunk(b"IDAT", zlib.compress(raw, 9)) + png_chunk(b"IEND", b"")


def exr(path, channels, dtype, compression, tiles=None):
    header = {"compression": compression, "type": OpenEXR.scanlineimage}
    if tiles:
        header["type"] = OpenEXR.tiledimage
        t = OpenEXR.TileDescription()
        t.xSize, t.ySize, t.mode = tiles, tiles, OpenEXR.ONE_LEVEL
        header["tiles"] = t
    with OpenEXR.File(header, {k: v.astype(dtype) for k, v in channels.items()}) as f:
        f.write(str(path))


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    rgb = (ramp(6, 5, 3) * 255).round().astype(np.uint8)
    Image.fromarray(rgb).quantize(8).save(OUT / "palette.png", optimize=True)
    rgba = (ramp(5, 4, 4) * 255).round().astype(np.uint8)
    Image.fromarray(rgba, "RGBA").save(OUT / "rgba.png", optimize=True)
    grey16 = (ramp(4, 3, 1)[:, :, 0] * 65535).round().astype(np.uint16)
    Image.fromarray(grey16).save(OUT / "grey16.png")
    (OUT / "adam7.png").write_bytes(adam7_png(9, 7))
    Image.fromarray((ramp(16, 16, 3) * 255).round().astype(np.uint8)).save(
        OUT / "progressive.jpg", progressive=True, quality=60)
    Image.fromarray((ramp(16, 8, 1)[:, :, 0] * 255).round().astype(np.uint8)).save(OUT / "grey.jpg", quality=60)
    c = ramp(8, 6, 3, 2.0)
    exr(OUT / "half-zip.exr", {"R": c[..., 0], "G": c[..., 1], "B": c[..., 2]}, np.float16,
        OpenEXR.ZIP_COMPRESSION)
    c = ramp(8, 8, 3, 3.0)
    exr(OUT / "tiled-piz.exr", {"R": c[..., 0], "G": c[..., 1], "B": c[..., 2]}, np.float32,
        OpenEXR.PIZ_COMPRESSION, tiles=4)
    exr(OUT / "y-rle.exr", {"Y": ramp(7, 5, 1)[..., 0]}, np.float16, OpenEXR.RLE_COMPRESSION)
    mi.set_variant("scalar_rgb")
    mi.Bitmap(ramp(16, 4, 3, 4.0).astype(np.float32)).write(str(OUT / "rle.hdr"))
    for p in sorted(OUT.iterdir()):
        print(f"{p.name}: {p.stat().st_size} bytes")


if __name__ == "__main__":
    main()
