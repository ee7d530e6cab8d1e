"""Hostile Minecraft and MagicaVoxel files (issue 26), written byte by byte like
mcfiles.py and voxfiles.py: each is small on disk and was, before the budgets, minutes
of decoding or gigabytes of memory (the numbers are main's, measured on the files
these functions write with their defaults)."""
from __future__ import annotations

import gzip
import struct
import zlib

import numpy as np

from . import mcfiles as mc
from . import voxfiles as vf

MIB = 1 << 20


# ---- NBT pieces -------------------------------------------------------------------
def named(tag: int, name: str) -> bytes:
    b = name.encode()
    return bytes([tag]) + struct.pack(">H", len(b)) + b


def chunk_head(version=3953) -> bytes:
    """The start of a chunk's root compound (left open): DataVersion and Status."""
    return (b"\x0a\x00\x00" + named(3, "DataVersion") + struct.pack(">i", version)
            + named(8, "Status") + struct.pack(">H", 14) + b"minecraft:full")


def empty_compounds(name: str, n: int) -> bytes:
    """A named list of n empty compounds: one byte and one tag each."""
    return named(9, name) + b"\x0a" + struct.pack(">i", n) + bytes(n)


def deep(name: str, depth: int) -> bytes:
    """A named compound holding compounds `depth` levels down."""
    return named(10, name) + b"\x0a\x00\x00" * (depth - 1) + b"\x00" * depth


def tag_bomb(n=30_000_000, key="sections") -> bytes:
    """A chunk whose `key` lists n empty compounds (30 MB: 2.4 GB on main when built)."""
    return chunk_head() + empty_compounds(key, n) + b"\x00"


def deep_chunk(depth: int, key="Heightmaps") -> bytes:
    return chunk_head() + named(9, "sections") + b"\x0a" + struct.pack(">i", 0) \
        + deep(key, depth) + b"\x00"


def big_nbt(size=32 * MIB - 4096) -> bytes:
    """A valid chunk of `size` bytes: a byte array nobody keeps (124 s on main, listed
    1,024 times)."""
    head = chunk_head() + named(9, "sections") + b"\x0a" + struct.pack(">i", 0)
    pad = size - len(head) - 1 - len(named(7, "x")) - 4
    return head + named(7, "x") + struct.pack(">i", pad) + bytes(pad) + b"\x00"


# ---- compressed payloads ----------------------------------------------------------
def zlib_bomb(n=256 * MIB, wbits=15) -> bytes:
    c = zlib.compressobj(9, zlib.DEFLATED, wbits)
    zero = bytes(MIB)
    return b"".join([c.compress(zero) for _ in range(n // MIB)] + [c.flush()])


def slow_lz4(n=300_000) -> bytes:
    """lz4-java framing around one block of n four-byte matches (each a Python loop
    turn in the pure decoder: 519 s on main, listed 1,024 times)."""
    body = b"\x10a\x01\x00" + b"\x00\x01\x00" * (n - 1) + b"\x10b"
    size = 1 + 4 * n + 1
    return (b"LZ4Block" + struct.pack("<BiiI", 0x20, len(body), size, 0) + body
            + b"LZ4Block" + struct.pack("<BiiI", 0x10, 0, 0, 0))


def lz4_bomb(blocks=16, size=16 * MIB) -> bytes:
    """lz4-java blocks of `size` zeros each (one literal, then one long match)."""
    e = size - 25   # 1 literal, a match of 4 + 15 + e, 5 literals to end the block
    body = b"\x1f\x00\x01\x00" + b"\xff" * (e // 255) + bytes([e % 255]) + b"\x50" + bytes(5)
    one = b"LZ4Block" + struct.pack("<BiiI", 0x20, len(body), size, 0) + body
    return one * blocks + b"LZ4Block" + struct.pack("<BiiI", 0x10, 0, 0, 0)


# ---- region files -----------------------------------------------------------------
def blob(payload: bytes, kind: int) -> bytes:
    b = struct.pack(">iB", len(payload) + 1, kind) + payload
    return b + bytes(-len(b) % 4096)


def aliased(payload: bytes, kind: int) -> bytes:
    """A region whose 1,024 header entries all point at one payload's sectors."""
    b = blob(payload, kind)
    count = len(b) // 4096
    assert count < 256
    return ((2 << 8 | count).to_bytes(4, "big") * 1024) + bytes(4096) + b


def single(payload: bytes, kind: int) -> bytes:
    """A region of one chunk (0, 0) holding an already compressed payload."""
    b = blob(payload, kind)
    return (2 << 8 | len(b) // 4096).to_bytes(4, "big") + bytes(8188) + b


def one_chunk(nbt: bytes, kind: int = 2) -> bytes:
    return mc.region({(0, 0): nbt}, kind)


def good_chunk() -> bytes:
    return mc.chunk_nbt(0, 0, {0: np.full((16, 16, 16), "minecraft:stone", object)})


def level_bomb(n=60_000_000) -> bytes:
    """A level.dat listing n empty compounds before Data (64 KB: over 3 GB on main)."""
    raw = b"\x0a\x00\x00" + empty_compounds("x", n) + named(10, "Data") \
        + named(3, "DataVersion") + struct.pack(">i", 3953) + b"\x00\x00"
    return gzip.compress(raw, 9)


# ---- .vox scene graphs ------------------------------------------------------------
def cube_model(side=16) -> bytes:
    """A SIZE and an XYZI chunk: a full cube of side^3 voxels (colours 1..200)."""
    g = np.stack(np.meshgrid(*[np.arange(side)] * 3, indexing="ij"), -1).reshape(-1, 3)
    xyzi = np.concatenate([g, 1 + (g[:, :1] + g[:, 1:2]) % 200], 1).astype(np.uint8)
    return (vf.chunk(b"SIZE", struct.pack("<3i", side, side, side))
            + vf.chunk(b"XYZI", struct.pack("<i", len(xyzi)) + xyzi.tobytes()))


def wide_group(children=130_000, side=4) -> bytes:
    """One group whose children all name one shape (over 3 GB on main)."""
    return vf.file(cube_model(side) + vf.trn(0, 1) + vf.grp(1, [2] * children)
                   + vf.trn(2, 3) + vf.shp(3, 0))


def binary_tree(levels=16, side=4) -> bytes:
    """Groups of two children, both the same node, 16 levels: 65,536 placements."""
    body = cube_model(side) + vf.trn(0, 1)
    for i in range(levels):
        body += vf.grp(1 + i, [2 + i, 2 + i])
    return vf.file(body + vf.trn(1 + levels, 2 + levels) + vf.shp(2 + levels, 0))


def cycle() -> bytes:
    return vf.file(cube_model(4) + vf.trn(0, 1) + vf.grp(1, [2, 4]) + vf.trn(2, 1)
                   + vf.trn(4, 5) + vf.shp(5, 0))


def instances(n=30_000, side=10) -> bytes:
    """n distinct nTRN/nSHP pairs placing one model of side^3 voxels side by side (a
    tree, legal; 30k of 1,000 voxels: over 3 GB on main)."""
    parts = [cube_model(side), vf.trn(0, 1), vf.grp(1, [2 + 2 * i for i in range(n)])]
    for i in range(n):
        parts.append(vf.trn(2 + 2 * i, 3 + 2 * i, (side * (i % 100), side * (i // 100), 8)))
        parts.append(vf.shp(3 + 2 * i, 0))
    return vf.file(b"".join(parts))


def shapes(n: int) -> bytes:
    """A group of n nSHP nodes placing one 1-voxel model (no nTRN each)."""
    parts = [vf.model((1, 1, 1), [(0, 0, 0, 1)]), vf.trn(0, 1), vf.grp(1, list(range(2, n + 2)))]
    parts += [vf.shp(2 + i, 0) for i in range(n)]
    return vf.file(b"".join(parts))
