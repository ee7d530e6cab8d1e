"""Minecraft Java region files (.mca): 32 x 32 chunks, an 8 KiB header of sector
offsets and timestamps, each chunk a length, a compression type and NBT. Types: 1
gzip, 2 zlib, 3 none, 4 LZ4 (lz4-java blocks); the high bit means the chunk lies in
an external c.X.Z.mcc file, which is reported, not read.

Hostile input: a header whose chunks share sectors, or point into the header or
past the end of the file, refuses the whole file (RegionError from Region(): one
payload listed 1,024 times would be decoded 1,024 times); a chunk's length is checked
against its sectors, and no payload inflates past MAX_NBT bytes nor past what the
import's budget.Budget has left (a damaged chunk is a RegionError for that chunk only,
a spent budget a budget.Exceeded for the whole import).
"""
from __future__ import annotations

import re
import struct
import zlib
from pathlib import Path

from ..core.chunk import REACH
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


def header(path, head, n: int) -> dict:
    """{(cx, cz): (first sector, sector count)} of a region file `path` of `n` bytes
    whose first 8 KiB are `head`; RegionError unless every chunk's sectors lie after
    the header, inside the file (its last sector may be short) and belong to it alone."""
    path = Path(path)
    name = path.name
    pos = position(path)
    if pos is None:
        raise RegionError(f"{name}: not a region file name (r.X.Z.mca)")
    if not all(-REACH <= 512 * v < REACH for v in pos):  # Minecraft's own end at 30M
        raise RegionError(f"{name}: a region outside the world (blocks within "
                          f"+-{REACH}); a damaged or hostile region file")
    if n == 0:
        return {}
    if n < 2 * SECTOR:
        raise RegionError(f"{name}: shorter than a region header ({n} bytes)")
    rx, rz = pos
    entries = {}
    for i in range(1024):
        off = int.from_bytes(head[4 * i:4 * i + 3], "big")
        count = head[4 * i + 3]
        if off or count:
            entries[(32 * rx + (i & 31), 32 * rz + (i >> 5))] = (off, count)
    end = -(-n // SECTOR)
    last, owner = 2, None
    for (off, count), key in sorted((v, k) for k, v in entries.items()):
        if off < 2:
            raise RegionError(f"{name}: chunk {key} points into the region header "
                              f"(sector {off}); a damaged or hostile region file")
        if off + count > end:
            raise RegionError(f"{name}: chunk {key} lies past the end of the file "
                              f"(sectors {off}+{count} of {end}); a damaged or hostile "
                              "region file")
        if count and off < last:
            raise RegionError(f"{name}: chunks {owner} and {key} share sector {off}; "
                              "a damaged or hostile region file")
        if count:
            last, owner = off + count, key
    return entries


def check(path) -> None:
    """Refuse a region file whose header is damaged (see header()) reading only it."""
    path = Path(path)
    with open(path, "rb") as f:
        head = f.read(SECTOR)
        n = f.seek(0, 2)
    header(path, head, n)


class Region:
    """One .mca file: its header read when made, each chunk's sectors when asked for
    (a folder of regions is never all in memory). `chunks()` lists the present
    (cx, cz) in Minecraft chunk coordinates, `payload(cx, cz)` gives its decompressed
    NBT; `stored` is the bytes its chunks' sectors hold (what a budget scales with)."""

    def __init__(self, path, data: bytes | None = None):
        self.path = Path(path)
        if position(self.path) is None:
            raise RegionError(f"{self.path.name}: not a region file name (r.X.Z.mca)")
        self.data = data
        if data is None:
            with open(self.path, "rb") as f:
                head = f.read(SECTOR)
                n = f.seek(0, 2)
        else:
            head, n = memoryview(data)[:SECTOR], len(data)
        self.entries = header(self.path, head, n)
        self.stored = min(n, SECTOR * sum(c for _, c in self.entries.values()))

    def chunks(self) -> list[tuple[int, int]]:
        return sorted(self.entries, key=lambda k: (k[1], k[0]))

    def _sectors(self, off: int, count: int):
        if self.data is not None:
            return memoryview(self.data)[off * SECTOR:(off + count) * SECTOR]
        with open(self.path, "rb") as f:
            f.seek(off * SECTOR)
            return memoryview(f.read(count * SECTOR))

    def payload(self, cx: int, cz: int, budget=None) -> bytes:
        """The chunk's NBT bytes; RegionError when it cannot be had, budget.Exceeded
        when `budget` (a budget.Budget, charged) has not that much left."""
        return unpack(self.path.name, cx, cz, *self.raw(cx, cz), budget)

    def raw(self, cx: int, cz: int) -> tuple[int, memoryview]:
        """(compression type, compressed body) of the chunk, its place and length
        checked (sectors read on demand): what `unpack` turns into NBT elsewhere
        (a cluster worker)."""
        off, count = self.entries[(cx, cz)]
        where = f"{self.path.name} chunk ({cx}, {cz})"
        if count == 0:
            raise RegionError(f"{where}: sectors {off}+{count} lie outside the file")
        try:
            raw = self._sectors(off, count)
        except OSError as e:
            raise RegionError(f"{where}: cannot be read ({e.strerror})") from None
        if len(raw) < 5:
            raise RegionError(f"{where}: sectors lie outside the file")
        length, kind = _LEN.unpack_from(raw, 0)
        if length < 1 or length - 1 > count * SECTOR or 4 + length > len(raw):
            raise RegionError(f"{where}: length {length} does not fit its {count} sectors")
        if kind & 0x80:
            raise External(f"{where}: stored in an external .mcc file (not read)")
        return kind, raw[5:4 + length]


def unpack(name: str, cx: int, cz: int, kind: int, body, budget=None) -> bytes:
    """Region.raw's answer decompressed, never past MAX_NBT (a worker decodes with
    that per-chunk limit too) nor past what `budget` has left (charged);
    RegionError naming the chunk, budget.Exceeded when the budget is spent."""
    where = f"{name} chunk ({cx}, {cz})"
    left = MAX_NBT if budget is None else min(MAX_NBT, max(budget.bytes, 0))
    try:
        out = decompress(kind, body, left)
    except _Over:
        if left < MAX_NBT:
            budget.spend_bytes(left + 1)   # raises Exceeded
        raise RegionError(f"{where}: NBT larger than {MAX_NBT >> 20} MiB") from None
    except ValueError as e:
        raise RegionError(f"{where}: {e}") from None
    if budget is not None:
        budget.spend_bytes(len(out))
    return out


class _Over(ValueError):
    pass


def decompress(kind: int, body, limit: int = MAX_NBT) -> bytes:
    """A chunk payload of compression type `kind`: never more than `limit` + 1 bytes
    are inflated, and a larger one is a ValueError."""
    if kind in (1, 2):
        d = zlib.decompressobj(31 if kind == 1 else 15)
        try:
            out = d.decompress(body, limit + 1)
        except zlib.error as e:
            raise ValueError(f"damaged {'gzip' if kind == 1 else 'zlib'} data ({e})") from None
        if len(out) > limit:
            raise _Over(f"NBT larger than {limit} bytes")
        if not d.eof:
            raise ValueError("compressed data ends early")
        return out
    if kind == 3:
        if len(body) > limit:
            raise _Over(f"NBT larger than {limit} bytes")
        return bytes(body)
    if kind == 4:
        try:
            return lz4.decode_stream(body, limit)
        except lz4.TooLarge as e:
            raise _Over(str(e)) from None
    raise ValueError(f"unknown compression type {kind}")
