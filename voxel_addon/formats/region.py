"""Minecraft Java region files (.mca): 32 x 32 chunks, an 8 KiB header of sector
offsets and timestamps, each chunk a length, a compression type and NBT. Types: 1
gzip, 2 zlib, 3 none, 4 LZ4 (lz4-java blocks); the high bit means the chunk lies in
an external c.X.Z.mcc file, which is reported, not read.

Hostile input: offsets and lengths are checked against the file, and no payload
inflates past MAX_NBT bytes (a damaged chunk is a RegionError for that chunk only).
"""
from __future__ import annotations

import re
import struct
import zlib
from pathlib import Path

from . import lz4

SECTOR = 4096
MAX_NBT = 32 << 20   # a chunk's NBT; real ones are tens to hundreds of KB
NAME = re.compile(r"^r\.(-?\d+)\.(-?\d+)\.mca$")
_LEN = struct.Struct(">iB")


class RegionError(ValueError):
    """One chunk (or the whole file) cannot be read; the message says why."""


class External(RegionError):
    """The chunk lives in an external .mcc file (not read)."""


def position(path) -> tuple[int, int] | None:
    """(rx, rz) from a file name r.X.Z.mca, or None."""
    m = NAME.match(Path(path).name)
    return (int(m.group(1)), int(m.group(2))) if m else None


class Region:
    """One .mca file read into memory. `chunks()` lists the present (cx, cz) in
    Minecraft chunk coordinates, `payload(cx, cz)` gives its decompressed NBT."""

    def __init__(self, path, data: bytes | None = None):
        self.path = Path(path)
        pos = position(self.path)
        if pos is None:
            raise RegionError(f"{self.path.name}: not a region file name (r.X.Z.mca)")
        self.rx, self.rz = pos
        self.data = self.path.read_bytes() if data is None else data
        n = len(self.data)
        if n == 0:
            self.entries = {}
            return
        if n < 2 * SECTOR:
            raise RegionError(f"{self.path.name}: shorter than a region header ({n} bytes)")
        self.entries = {}
        head = memoryview(self.data)[:SECTOR]
        for i in range(1024):
            off = int.from_bytes(head[4 * i:4 * i + 3], "big")
            count = head[4 * i + 3]
            if off == 0 and count == 0:
                continue
            cx, cz = 32 * self.rx + (i & 31), 32 * self.rz + (i >> 5)
            self.entries[(cx, cz)] = (off, count)

    def chunks(self) -> list[tuple[int, int]]:
        return sorted(self.entries, key=lambda k: (k[1], k[0]))

    def payload(self, cx: int, cz: int) -> bytes:
        """The chunk's NBT bytes; RegionError when it cannot be had."""
        return unpack(self.path.name, cx, cz, *self.raw(cx, cz))

    def raw(self, cx: int, cz: int) -> tuple[int, memoryview]:
        """(compression type, compressed body) of the chunk, its place checked:
        what `unpack` turns into NBT elsewhere (a cluster worker)."""
        off, count = self.entries[(cx, cz)]
        where = f"{self.path.name} chunk ({cx}, {cz})"
        if off < 2 or count == 0 or (off + count) * SECTOR > len(self.data) + SECTOR:
            raise RegionError(f"{where}: sectors {off}+{count} lie outside the file")
        start = off * SECTOR
        if start + 5 > len(self.data):
            raise RegionError(f"{where}: sectors lie outside the file")
        length, kind = _LEN.unpack_from(self.data, start)
        if length < 1 or length - 1 > count * SECTOR or start + 4 + length > len(self.data):
            raise RegionError(f"{where}: length {length} does not fit its {count} sectors")
        if kind & 0x80:
            raise External(f"{where}: stored in an external .mcc file (not read)")
        return kind, memoryview(self.data)[start + 5:start + 4 + length]


def unpack(name: str, cx: int, cz: int, kind: int, body) -> bytes:
    """Region.raw's answer decompressed; RegionError naming the chunk."""
    try:
        return decompress(kind, body)
    except ValueError as e:
        raise RegionError(f"{name} chunk ({cx}, {cz}): {e}") from None


def decompress(kind: int, body) -> bytes:
    """A chunk payload of compression type `kind`, bounded by MAX_NBT."""
    if kind in (1, 2):
        d = zlib.decompressobj(31 if kind == 1 else 15)
        try:
            out = d.decompress(body, MAX_NBT + 1)
        except zlib.error as e:
            raise ValueError(f"damaged {'gzip' if kind == 1 else 'zlib'} data ({e})") from None
        if len(out) > MAX_NBT:
            raise ValueError(f"NBT larger than {MAX_NBT >> 20} MiB")
        if not d.eof:
            raise ValueError("compressed data ends early")
        return out
    if kind == 3:
        if len(body) > MAX_NBT:
            raise ValueError(f"NBT larger than {MAX_NBT >> 20} MiB")
        return bytes(body)
    if kind == 4:
        return lz4.decode_stream(body, MAX_NBT)
    raise ValueError(f"unknown compression type {kind}")
