"""Procedural 16×16 pixel-art block textures (SPEC F12): the project's own, no texture pack.

    texture_array()  -> (layers, 16, 16, 4) uint8 RGBA, layers in
                        REGISTRY.texture_names order, row 0 = top of the image
    glow_array()     -> (layers, 16, 16) uint8 glow mask, same order
    mipmaps(arr)     -> [level0 (L,16,16,C), level1 (L,8,8,C), … (L,1,1,C)]
    layer(name)      -> index of a texture name
    image(name)      -> (rgba, glow) of one texture
    save_png(name, path, scale=1) / save_sheet(path, scale=8)

Alpha semantics follow the block's render class: for `alpha_test` blocks alpha is
coverage (cut at 0.5), for `blend` blocks it is opacity, opaque blocks are 255.
Glow is a separate mask (not alpha) so glowing cut-outs stay possible: a pixel's
self-emission is albedo × glow/255 × the block's `glow` factor (core.blocks).
Uploading to GL (v = 0 at the bottom): flip rows, i.e. `arr[:, ::-1]`, or pass
`origin="bottom"`. Side faces have the image top toward +z.
"""
from __future__ import annotations

import zlib
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..core.blocks import REGISTRY
from . import built, paint

SIZE = paint.N
SEED = 2019
PAINTERS = {**paint.PAINTERS, **built.PAINTERS}  # every texture name -> its painter


def _rng(seed: int, name: str):
    return np.random.default_rng([seed, zlib.crc32(name.encode())])


@lru_cache(maxsize=None)
def image(name: str, seed: int = SEED) -> tuple[np.ndarray, np.ndarray]:
    """(rgba (16,16,4), glow (16,16)) of one texture; read-only, cached."""
    rng = _rng(seed, name)
    fn = PAINTERS.get(name)
    rgba, glow = fn(rng) if fn else paint.fallback(rng, name)
    rgba.setflags(write=False)
    glow.setflags(write=False)
    return rgba, glow


def layer(name: str) -> int:
    return REGISTRY.texture_names.index(name)


def _stack(k: int, seed: int, origin: str) -> np.ndarray:
    if origin not in ("top", "bottom"):
        raise ValueError("origin must be 'top' or 'bottom'")
    a = np.stack([image(n, seed)[k] for n in REGISTRY.texture_names])
    return np.ascontiguousarray(a[:, ::-1]) if origin == "bottom" else a


def texture_array(seed: int = SEED, origin: str = "top") -> np.ndarray:
    """(layers, 16, 16, 4) uint8 RGBA in REGISTRY.texture_names order."""
    return _stack(0, seed, origin)


def glow_array(seed: int = SEED, origin: str = "top") -> np.ndarray:
    """(layers, 16, 16) uint8 glow mask in REGISTRY.texture_names order."""
    return _stack(1, seed, origin)


def mipmaps(arr: np.ndarray) -> list[np.ndarray]:
    """Box-filtered mip chain down to 1×1 for (L, S, S, 4) RGBA or (L, S, S) masks.

    RGBA colours are averaged weighted by alpha, so transparent texels do not bleed
    black into the fringes of leaves and plants.
    """
    levels = [arr]
    a = arr.astype(np.float32)
    while a.shape[1] > 1:
        q = a.reshape(a.shape[0], a.shape[1] // 2, 2, a.shape[2] // 2, 2, *a.shape[3:])
        if a.ndim == 4:
            w = q[..., 3:4]
            wsum = w.sum(axis=(2, 4))
            rgb = np.where(wsum > 0, (q[..., :3] * w).sum(axis=(2, 4)) / np.maximum(wsum, 1e-6),
                           q[..., :3].mean(axis=(2, 4)))
            a = np.concatenate([rgb, q[..., 3:4].mean(axis=(2, 4))], axis=-1)
        else:
            a = q.mean(axis=(2, 4))
        levels.append(np.clip(np.rint(a), 0, 255).astype(np.uint8))
    return levels


def png_bytes(rgba: np.ndarray) -> bytes:
    """A minimal RGBA8 PNG encoder (no Pillow needed inside Blender or out)."""
    import struct
    h, w = rgba.shape[:2]
    raw = b"".join(b"\x00" + np.ascontiguousarray(rgba[y], np.uint8).tobytes() for y in range(h))

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def save_png(name: str, path, scale: int = 1, seed: int = SEED) -> Path:
    rgba = image(name, seed)[0]
    if scale > 1:
        rgba = rgba.repeat(scale, 0).repeat(scale, 1)
    path = Path(path)
    path.write_bytes(png_bytes(rgba))
    return path


def sheet(scale: int = 8, cols: int = 7, seed: int = SEED) -> np.ndarray:
    """All textures on a checkerboard (shows alpha) with their glow masks below each."""
    names = REGISTRY.texture_names
    s = SIZE * scale
    rows = -(-len(names) // cols)
    pad = 4
    out = np.zeros((rows * (2 * s + 3 * pad), cols * (s + pad) + pad, 4), np.uint8)
    out[..., 3] = 255
    out[..., :3] = 40
    ck = ((np.indices((s, s)) // max(scale, 1)).sum(0) % 2)[..., None]
    check = np.where(ck, 200, 150).astype(np.float32)
    for i, n in enumerate(names):
        rgba, glow = image(n, seed)
        big = rgba.repeat(scale, 0).repeat(scale, 1).astype(np.float32)
        a = big[..., 3:4] / 255
        tile = big[..., :3] * a + check * (1 - a)
        r, c = divmod(i, cols)
        y, x = pad + r * (2 * s + 3 * pad), pad + c * (s + pad)
        out[y:y + s, x:x + s, :3] = tile
        g = glow.repeat(scale, 0).repeat(scale, 1)
        out[y + s + pad:y + 2 * s + pad, x:x + s, :3] = g[..., None]
    return out


def save_sheet(path, scale: int = 8, seed: int = SEED) -> Path:
    path = Path(path)
    path.write_bytes(png_bytes(sheet(scale, seed=seed)))
    return path
