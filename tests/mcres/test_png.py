"""The PNG decoder against Pillow (the oracle: Pillow is a test tool, never shipped)
on images whose rows make the encoder use every filter, in every colour type."""
from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

from voxel_addon.core.errors import VoxelError
from voxel_addon.mcres import png


def picture(rng, h=23, w=37) -> np.ndarray:
    """Gradients, noise and flat runs: the encoder's adaptive filtering picks None,
    Sub, Up, Average and Paeth on different rows."""
    y, x = np.mgrid[0:h, 0:w]
    a = np.stack([x * 7, y * 11, (x * y) % 256, 255 - x * 3], axis=-1) % 256
    a[h // 3: h // 2] = rng.integers(0, 256, (h // 2 - h // 3, w, 4))
    a[-3:] = 77
    return a.astype(np.uint8)


def encode(img: Image.Image, **kw) -> bytes:
    buf = io.BytesIO()
    img.save(buf, "PNG", **kw)
    return buf.getvalue()


def filtered_png(rgba: np.ndarray) -> bytes:
    """An RGBA8 PNG whose row y uses filter y % 5 (None, Sub, Up, Average, Paeth),
    encoded here from the specification."""
    import struct
    import zlib
    h, w = rgba.shape[:2]
    rows = rgba.reshape(h, w * 4).astype(np.int64)
    raw = b""
    for y in range(h):
        cur = rows[y]
        up = rows[y - 1] if y else np.zeros_like(cur)
        left = np.concatenate([np.zeros(4, np.int64), cur[:-4]])
        ul = np.concatenate([np.zeros(4, np.int64), up[:-4]])
        f = y % 5
        if f == 4:
            p = left + up - ul
            pa, pb, pc = abs(p - left), abs(p - up), abs(p - ul)
            pred = np.where((pa <= pb) & (pa <= pc), left, np.where(pb <= pc, up, ul))
        else:
            pred = [0 * cur, left, up, (left + up) // 2][f]
        raw += bytes([f]) + ((cur - pred) % 256).astype(np.uint8).tobytes()

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))
    return (png.SIG + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


@pytest.mark.parametrize("mode", ["RGBA", "RGB", "L", "LA", "P", "1", "I;16"])
def test_every_colour_type_reads_as_pillow_reads_it(mode):
    rng = np.random.default_rng(5)
    src = Image.fromarray(picture(rng), "RGBA")
    img = src.convert("RGB").quantize(16) if mode == "P" else src.convert(mode)
    kw = {"transparency": 3} if mode == "P" else {}
    data = encode(img, **kw)
    got = png.decode(data)
    want = np.asarray(Image.open(io.BytesIO(data)).convert("RGBA"))
    if mode == "I;16":    # Pillow clips 16-bit grey to 255, we take the high byte
        want = np.asarray(Image.open(io.BytesIO(data)))
        g = (want.astype(np.int64) >> 8).astype(np.uint8)
        want = np.stack([g, g, g, np.full_like(g, 255)], axis=-1)
    assert got.shape == want.shape and np.array_equal(got, want)


def test_all_five_filters():
    """Each row filter, written from the specification, reads back pixel for pixel
    (noise too: Paeth's ties between its predictors happen there)."""
    a = picture(np.random.default_rng(5))
    assert np.array_equal(png.decode(filtered_png(a)), a)
    b = np.random.default_rng(6).integers(0, 256, (40, 40, 4), dtype=np.uint8)
    assert np.array_equal(png.decode(filtered_png(b)), b)


@pytest.mark.parametrize("bad, msg", [
    (b"GIF89a", "not a PNG"),
    (png.SIG + b"\x00\x00\x00\x0dIHDR" + (1 << 20).to_bytes(4, "big") * 2 + b"\x08\x06\0\0\0" + b"CRC!",
     "unsupported PNG"),
    (png.SIG + b"\x00\x00\x00\x0dIHDR\x00\x00", "truncated"),
])
def test_hostile_files_are_one_line_errors(bad, msg):
    with pytest.raises(VoxelError, match=msg):
        png.decode(bad + b"\0" * 20)


def test_truncated_pixel_data_is_refused():
    data = encode(Image.fromarray(picture(np.random.default_rng(1)), "RGBA"))
    i = data.index(b"IDAT")
    n = int.from_bytes(data[i - 4:i], "big")
    cut = data[:i - 4] + (n // 2).to_bytes(4, "big") + b"IDAT" + data[i + 4:i + 4 + n // 2] \
        + b"\0\0\0\0" + data[-12:]
    with pytest.raises(VoxelError, match="truncated|bad PNG"):
        png.decode(cut)
