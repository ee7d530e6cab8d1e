"""Chunk geometry (SPEC §3) and the in-memory chunk.

Arrays are (16, 16, 256) indexed [lx, ly, z] and Fortran-ordered, so their memory
order is the file's linear index i = lx + 16*ly + 256*z. Wider regions follow the
same rule: (W, H, 256) arrays, x fastest, and kernels index x + W*(y + H*z).
"""
from __future__ import annotations

import time

import numpy as np

from .errors import VoxelError
from .packed import Packed, pack, pack_layers, scratch, unpack_layers  # noqa: F401 (chunk.*)

SIZE = 16
HEIGHT = 256
HOT_S = 2.0  # seconds unused before compact() packs a chunk's blocks
VOLUME = SIZE * SIZE * HEIGHT
SHAPE = (SIZE, SIZE, HEIGHT)


def empty(dtype=np.uint16, width: int = SIZE, depth: int = SIZE) -> np.ndarray:
    """A zeroed (width, depth, 256) array in the canonical (x fastest) order."""
    return np.zeros((width, depth, HEIGHT), dtype=dtype, order="F")


def from_linear(buf, dtype=np.uint16) -> np.ndarray:
    """Bytes or a flat array in linear-index order -> (16, 16, 256) view."""
    flat = np.frombuffer(buf, dtype=np.dtype(dtype).newbyteorder("<")) \
        if isinstance(buf, (bytes, bytearray, memoryview)) else np.asarray(buf)
    if flat.size != VOLUME:
        raise ValueError(f"chunk array has {flat.size} values, expected {VOLUME}")
    return flat.astype(dtype, copy=False).reshape(SHAPE, order="F")


def to_linear(arr: np.ndarray) -> bytes:
    """(16, 16, 256) array -> little-endian bytes in linear-index order."""
    return np.asarray(arr, dtype="<u2").tobytes(order="F")


def paste(pieces, cx0: int, cy0: int, cx1: int, cy1: int, dtype=np.uint16) -> np.ndarray:
    """The one way to lay chunks side by side: a (16w, 16h, 256) array of chunks
    [cx0, cx1) x [cy0, cy1) from ((cx, cy), (16, 16, 256) array) pairs; chunks outside
    are skipped, missing ones stay 0 (air)."""
    out = empty(dtype, SIZE * (cx1 - cx0), SIZE * (cy1 - cy0))
    for (cx, cy), a in pieces:
        if cx0 <= cx < cx1 and cy0 <= cy < cy1:
            x, y = (cx - cx0) * SIZE, (cy - cy0) * SIZE
            out[x:x + SIZE, y:y + SIZE] = a
    return out


def cut(area: np.ndarray, cx0: int, cy0: int) -> dict:
    """paste's inverse: {(cx, cy): (16, 16, 256) view} of an array of whole chunks
    whose first chunk is (cx0, cy0)."""
    w, h = area.shape[0] // SIZE, area.shape[1] // SIZE
    return {(cx0 + i, cy0 + j): area[SIZE * i:SIZE * i + SIZE, SIZE * j:SIZE * j + SIZE]
            for j in range(h) for i in range(w)}


def key_of(x: int, y: int) -> tuple[int, int]:
    """Chunk key holding block column (x, y)."""
    return (x >> 4, y >> 4)


def check_z(z: int) -> None:
    if not 0 <= z < HEIGHT:
        raise VoxelError(f"z={z} is outside the world (0..{HEIGHT - 1})")


# Block columns x, y lie in [-REACH, REACH): generation computes positions in int32
# (the kernels' and NumPy's alike), with room left for rings, far tiles and models
# placed from there; further out a position would wrap (or not fit SQLite's int64).
REACH = 1 << 30


def check_xy(*values) -> None:
    """A VoxelError for the first horizontal block coordinate outside the world."""
    for v in values:
        if not -REACH <= v < REACH:
            raise VoxelError(f"x, y = {v} is outside the world (-{REACH}..{REACH - 1})")


class Chunk:
    """Block ids plus lazily allocated small data and large data (thesis §4.1).

    `data` stays None while all zero. `large` maps a small-data index to any Python
    object (e.g. a chest's contents). Blocks and light are kept packed (Packed: ~3 KB
    each for generated terrain, of 128 KB) until read, and packed again by compact()
    (issue 29); a stream batch's load keeps blocks as read until the batch packs
    them (unread/packed: one pack, no decode).
    """

    __slots__ = ("key", "_blocks", "_bpack", "_bhot", "data", "large", "_light", "_lpack",
                 "_lsame", "mesh", "dirty", "last_use", "__weakref__")

    def __init__(self, key, blocks=None, data=None, hot: bool = False):
        self.key = tuple(key)
        if hot and isinstance(blocks, np.ndarray) and blocks.shape == SHAPE and \
                blocks.dtype == np.uint16:
            # a stream batch's load: kept as read (no other reference: the file's
            # decode) until its snapshot copied it, then packed once (unread():
            # packing then decoding every reloaded chunk was ~1/3 of a reload)
            self._blocks, self._bpack, self._bhot = blocks, None, 0.0
        elif blocks is None:
            self._blocks, self._bpack, self._bhot = None, Packed.uniform(SHAPE, np.uint16), 0.0
        elif isinstance(blocks, Packed):  # a save's snapshot (World._fetch): never changes
            self._blocks, self._bpack, self._bhot = None, blocks, 0.0
        elif getattr(blocks, "shape", None) == SHAPE and blocks.dtype in (np.uint16, np.uint8):
            # born packed (a generated or loaded chunk is read once by its light and
            # mesh, through blocks_into): 128 KB less for each until something reads it
            self._blocks, self._bpack, self._bhot = None, pack(blocks), 0.0
        else:
            self.blocks = blocks
        self.data = data
        self.large: dict[int, object] = {}
        self._light = self._lpack = None  # final light (see .light), filled by the world layer
        self._lsame = False  # _lpack holds _light's values and nothing may write into it
        self.mesh = None   # its mesh with the neighbour ring, likewise
        self.dirty = False
        self.last_use = time.monotonic()

    @property
    def blocks(self) -> np.ndarray:
        """Block ids (16, 16, 256). Kept packed until read; a read rebuilds the array
        and keeps it hot (callers may write into it) until compact() finds it unread
        for HOT_S seconds."""
        a = self._blocks
        if a is None:
            a = self._blocks = self._bpack.unpack()  # (_bpack stays, as _lpack)
            self._bhot = time.monotonic()
        elif self._bhot == 0.0:  # loaded hot, read now: it may be written (see unread)
            self._bhot = time.monotonic()
        return a

    def unread(self) -> np.ndarray | None:
        """The blocks of a hot load (Chunk(hot=True)) that nothing has read through
        .blocks since (so nothing writes into them): pack them outside the world's
        lock and hand the result to packed(); else None."""
        a = self._blocks
        return a if a is not None and self._bpack is None and self._bhot == 0.0 else None

    def packed(self, a: np.ndarray, p: "Packed") -> bool:
        """Keep P (pack(a), a from unread()) in place of the array when the blocks
        are still A unread (call with the world's lock held); whether it did."""
        if self._blocks is not a or self._bhot != 0.0:
            return False
        self._bpack, self._blocks = p, None
        return True

    def blocks_copy(self) -> np.ndarray:
        """A new array of the blocks (a save's snapshot) that leaves cold ones cold:
        rebuilt from their layers, not rebuilt, kept and copied."""
        a = self._blocks
        return self._bpack.unpack() if a is None else a.copy(order="F")

    def blocks_into(self, out: np.ndarray, xs: slice, ys: slice, z0: int, z1: int,
                    keep: bool = False, zeroed: bool = False) -> None:
        """out[...] = blocks[xs, ys, z0:z1] leaving cold blocks cold (a batch's
        snapshot reads each chunk once), or with `keep` rebuilt and kept hot as a
        read of .blocks (an edit reads its neighbours' windows several times).
        ZEROED: out holds 0 already, so the air above the terrain is not written
        (issue 29: ~60 % of a chunk; the snapshot's copy was its largest cost)."""
        a = self.blocks if keep else self._blocks
        if a is None:
            self._bpack.into(out, xs, ys, z0, z1, zeroed)
            return
        if zeroed:
            z1 = max(z0, min(z1, self.air_from(z0)))
            out = out[:, :, :z1 - z0]
        out[...] = a[xs, ys, z0:z1]

    def air_from(self, z0: int = 0) -> int:
        """A layer >= z0 from which the blocks are air up to the world's top (an edit's
        window need not copy those): from the packed sections' values, else by
        counting hot blocks from there (a packed copy kept beside hot blocks may be
        stale: a hint) or a section at a time from the top."""
        a, p = self._blocks, self._bpack
        i = None if p is None else p.air_from()
        if a is None:
            if i is not None:
                return max(z0, i)
            a = p.body
        if not a.flags.f_contiguous:
            return a.shape[2]
        f, n, S = a.reshape(-1, order="F"), a.shape[0] * a.shape[1], Packed.SECTION
        if i is not None and not np.count_nonzero(f[max(i, z0) * n:]):
            return max(i, z0)
        i = a.shape[2]
        while i > z0 and not np.count_nonzero(f[max(i - S, z0) * n:i * n]):
            i = max(i - S, z0)
        return i

    @blocks.setter
    def blocks(self, value) -> None:
        self._blocks, self._bpack, self._bhot = value, None, time.monotonic()

    @property
    def light(self) -> np.ndarray | None:
        """Final light (16, 16, 256) or None. Kept as a full array ("hot": set or
        read since the last compact(); callers may write into one they just set,
        under the world's lock) or, after compact(), packed; a read then rebuilds
        the array (same values) and keeps it hot."""
        a = self._light
        if a is None and self._lpack is not None:
            # _lpack stays: a compact() racing this read then still finds the light
            a = self._light = self._lpack.unpack()
        self._lsame = False  # (the caller may write into it)
        return a

    @property
    def has_light(self) -> bool:
        """Whether final light is known (without rebuilding a compacted one)."""
        return self._light is not None or self._lpack is not None

    def light_into(self, out: np.ndarray, xs: slice, ys: slice, z0: int, z1: int,
                   keep: bool = False) -> None:
        """out[...] = light[xs, ys, z0:z1] without rebuilding a compacted light, or
        with `keep` rebuilt and kept (as a read of .light) until the next compact()."""
        a = self.light if keep else self._light
        if a is not None or self._lpack is None:
            out[...] = 0 if a is None else a[xs, ys, z0:z1]
            return
        self._lpack.into(out, xs, ys, z0, z1)

    def light_out(self) -> np.ndarray | None:
        """The final light for a reader that keeps it (a payload): the hot array
        itself, or one rebuilt from the packed light that the chunk does not keep,
        so the next compact() has nothing to pack again (a reloaded chunk's light was
        packed on load). Arrays handed out are never written in place (edit.py
        copies before it writes): a later write into .light leaves this one."""
        a = self._light
        return a if a is not None or self._lpack is None else self._lpack.unpack()

    def light_copy(self) -> np.ndarray | None:
        """A new array of the final light for a writer that sets it back (an edit):
        the hot one copied, a packed one rebuilt (not kept, not copied again), into
        a spare() array."""
        a = self._light
        if a is not None:
            out = spare()
            out[...] = a
            return out
        return None if self._lpack is None else self._lpack.unpack(spare())

    def light_kept(self) -> np.ndarray | None:
        """.light with a packed one rebuilt into a spare() array (an edit's payload
        of a chunk it remeshed but did not relight)."""
        if self._light is None and self._lpack is not None:
            self._light = self._lpack.unpack(spare())
        return self.light

    def saved(self) -> tuple:
        """(blocks, light) for a save's snapshot: values no later change of the
        chunk touches and that cost no decode under the world's lock: the Packed
        ones (never changed: a pack replaces them), a copy of hot blocks, hot light
        as is (arrays handed out are replaced, never written in place). Chunk()
        and .light take them back (World._fetch)."""
        b = self._bpack if self._blocks is None else self._blocks.copy(order="F")
        return b, self._lpack if self._light is None else self._light

    @light.setter
    def light(self, value) -> None:
        self._lsame = False
        if isinstance(value, Packed):
            self._light, self._lpack = None, value
            return
        self._light, self._lpack = value, None

    def light_read(self, a: np.ndarray, p: "Packed") -> None:
        """Light read from a file: the array A (hot: a stream batch hands it to its
        payloads) and P, the stored frame it was decoded from, kept when compact()
        comes (issue 29: no pack), unless something read A through .light meanwhile."""
        self._light, self._lpack, self._lsame = a, p, True

    def hot_light(self) -> np.ndarray | None:
        """The light array compact() would pack (None: none, packed already, or its
        packed twin kept: light_read): pack it outside the world's lock and hand the
        result to light_packed()."""
        return None if self._lsame else self._light

    def light_packed(self, a: np.ndarray, p: "Packed") -> bool:
        """Keep P (pack(a), a from hot_light()) in place of the light array when it
        is still A (call with the world's lock held: light arrays are replaced, never
        written in place once handed out); whether it did."""
        if self._light is not a:
            return False
        self._lpack, self._light, self._lsame = p, None, False
        return True

    def compact(self) -> None:
        """Pack the light, and the blocks when cold (not read or set for HOT_S
        seconds). Call with the world's lock held."""
        a = self._light
        if a is not None:
            self._lpack, self._light = self._lpack if self._lsame else pack(a), None
            self._lsame = False
        b = self._blocks
        if b is not None and b.shape == SHAPE and time.monotonic() - self._bhot > HOT_S:
            self._bpack, self._blocks = pack(b), None

    @property
    def origin(self) -> tuple[int, int]:
        return (self.key[0] * SIZE, self.key[1] * SIZE)

    def get(self, lx: int, ly: int, z: int) -> int:
        return int(self.blocks[lx, ly, z])

    def set(self, lx: int, ly: int, z: int, block: int, data: int = 0) -> None:
        """put() and mark the chunk changed, its light and mesh stale."""
        self.data = put(self.blocks, self.data, lx, ly, z, block, data)
        self.dirty = True
        self.light = self.mesh = None  # stale now

    def nbytes(self) -> int:
        n = 0
        for a in (self._blocks, self._bpack, self.data, self._light, self._lpack):
            if a is not None:
                n += a.nbytes
        return n


# Spare (16, 16, 256) uint16 arrays with their pages faulted in, for an edit's new
# light arrays (issue 29): a fresh 128 KB array is ~32 page faults when first
# written, ~80 us of the click in a big process (an edit makes one to nine). The
# world's writer thread makes them again after each edit's write (make_spares).
_SPARES: list = []
SPARES = 12  # a lamp's 3x3 and a click or two (1.5 MB)


def spare() -> np.ndarray:
    """A new (16, 16, 256) uint16 array (Fortran order, values unset) that no one
    else holds: a spare one when there is one, else np.empty."""
    try:
        return _SPARES.pop()
    except IndexError:
        return np.empty(SHAPE, np.uint16, order="F")


def make_spares(n: int = SPARES) -> None:
    """Make the spares up to N, their pages written (off the click: after a write)."""
    while len(_SPARES) < n:
        a = np.empty(SHAPE, np.uint16, order="F")
        a.fill(0)
        _SPARES.append(a)


def put(blocks, data, lx: int, ly: int, z: int, block: int, value: int):
    """The one place that writes voxels' block ids and small data (scalars, or index
    arrays and values): `data` is allocated on the first non-zero value (None while
    all zero); returns it."""
    blocks[lx, ly, z] = block
    if data is not None or np.any(value):
        if data is None:
            data = empty()
        data[lx, ly, z] = value
    return data
