"""A PNG decoder of our own (zlib + NumPy: the extension ships no imaging library):
every colour type, bit depths 1–16 (16 read as its high byte), tRNS, Adam7 refused. Sizes are checked before
anything is allocated; decompression stops at the expected size."""
from __future__ import annotations

import struct
import zlib

import numpy as np

from ..core.errors import VoxelError

SIG = b"\x89PNG\r\n\x1a\n"
MAX_PIXELS = 1 << 24         # 4096 × 4096
_CHANNELS = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}


def _unfilter(raw: bytes, h: int, stride: int, bpp: int) -> np.ndarray:
    out = np.zeros((h, stride), np.uint8)
    prev = np.zeros(stride, np.int32)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = np.frombuffer(raw, np.uint8, stride, y * (stride + 1) + 1).astype(np.int32)
        if f == 0:
            cur = line
        elif f == 2:
            cur = (line + prev) & 0xFF
        elif f == 1:       # Sub: a running sum per byte of a pixel
            cur = np.cumsum(line.reshape(-1, bpp) if stride % bpp == 0 else
                            np.pad(line, (0, -stride % bpp)).reshape(-1, bpp), axis=0)
            cur = (cur.reshape(-1)[:stride]) & 0xFF
        elif f in (3, 4):  # Average, Paeth: each byte needs the one decoded before it
            a = bytearray(stride)
            p = prev.tolist()
            ln = line.tolist()
            for i in range(stride):
                left = a[i - bpp] if i >= bpp else 0
                if f == 3:
                    a[i] = (ln[i] + ((left + p[i]) >> 1)) & 0xFF
                else:
                    ul = p[i - bpp] if i >= bpp else 0
                    est = left + p[i] - ul
                    pa, pb, pc = abs(est - left), abs(est - p[i]), abs(est - ul)
                    pr = left if pa <= pb and pa <= pc else (p[i] if pb <= pc else ul)
                    a[i] = (ln[i] + pr) & 0xFF
            cur = np.frombuffer(bytes(a), np.uint8).astype(np.int32)
        else:
            raise VoxelError(f"PNG: unknown row filter {f}")
        out[y] = cur
        prev = cur
    return out


def decode(data: bytes, name: str = "PNG") -> np.ndarray:
    """(h, w, 4) uint8 RGBA, row 0 at the top (as the file)."""
    if not data.startswith(SIG):
        raise VoxelError(f"{name}: not a PNG")
    pos, idat, plte, trns, head = 8, [], None, None, None
    try:
        while pos < len(data):
            n, tag = struct.unpack_from(">I4s", data, pos)
            body = data[pos + 8:pos + 8 + n]
            if len(body) != n:
                raise VoxelError(f"{name}: truncated PNG")
            pos += 12 + n
            if tag == b"IHDR":
                head = struct.unpack(">IIBBBBB", body)
            elif tag == b"PLTE":
                plte = np.frombuffer(body, np.uint8).reshape(-1, 3)
            elif tag == b"tRNS":
                trns = body
            elif tag == b"IDAT":
                idat.append(body)
            elif tag == b"IEND":
                break
    except struct.error:
        raise VoxelError(f"{name}: truncated PNG") from None
    if head is None:
        raise VoxelError(f"{name}: PNG without IHDR")
    w, h, depth, ctype, _, _, interlace = head
    if ctype not in _CHANNELS or depth not in (1, 2, 4, 8, 16) or not 0 < w * h <= MAX_PIXELS:
        raise VoxelError(f"{name}: unsupported PNG ({w}×{h}, type {ctype}, depth {depth})")
    if interlace:
        raise VoxelError(f"{name}: interlaced PNGs are not supported")
    ch = _CHANNELS[ctype]
    bits = ch * depth
    stride = (w * bits + 7) // 8
    want = h * (stride + 1)
    z = zlib.decompressobj()
    try:
        raw = z.decompress(b"".join(idat), want)
    except zlib.error as e:
        raise VoxelError(f"{name}: bad PNG data ({e})") from None
    if len(raw) < want:
        raise VoxelError(f"{name}: truncated PNG data")
    rows = _unfilter(raw, h, stride, max(1, bits // 8))
    if depth == 16:
        vals = rows.reshape(h, -1)[:, :w * ch * 2].reshape(h, w * ch, 2)[..., 0]   # high bytes
        full = 0xFFFF
    elif depth == 8:
        vals = rows[:, :w * ch]
        full = 0xFF
    else:
        vals = np.unpackbits(rows, axis=1)[:, :w * ch * depth].reshape(h, w * ch, depth)
        vals = (vals * (1 << np.arange(depth - 1, -1, -1))).sum(axis=2).astype(np.uint8)
        full = (1 << depth) - 1
    px = vals.reshape(h, w, ch).astype(np.uint16 if depth != 16 else np.uint8)
    out = np.empty((h, w, 4), np.uint8)
    if ctype == 3:
        if plte is None:
            raise VoxelError(f"{name}: palette PNG without PLTE")
        idx = np.minimum(px[..., 0], len(plte) - 1)
        out[..., :3] = plte[idx]
        alpha = np.full(256, 255, np.uint8)
        if trns:
            alpha[:len(trns)] = np.frombuffer(trns[:256], np.uint8)
        out[..., 3] = alpha[idx]
        return out
    scale = (lambda v: v) if depth in (8, 16) else (lambda v: (v * 255 // full).astype(np.uint8))
    if ctype in (0, 4):
        g = scale(px[..., 0])
        out[..., 0] = out[..., 1] = out[..., 2] = g
        out[..., 3] = scale(px[..., 1]) if ctype == 4 else 255
        if ctype == 0 and trns and len(trns) >= 2 and depth <= 8:   # a grey that is clear
            out[..., 3] = np.where(px[..., 0] == struct.unpack(">H", trns[:2])[0], 0, 255)
    else:
        out[..., :3] = scale(px[..., :3])
        out[..., 3] = scale(px[..., 3]) if ctype == 6 else 255
        if ctype == 2 and trns and len(trns) >= 6 and depth == 8:
            key = np.array(struct.unpack(">HHH", trns[:6]))
            out[..., 3] = np.where((px[..., :3] == key).all(axis=2), 0, 255)
    return out
