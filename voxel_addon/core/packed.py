"""Chunk arrays as kept in memory: Packed (LZ4 sections, or the file's own zstd
frame), pack(), the viewport's layer packing (pack_layers), per-thread scratch."""
from __future__ import annotations

import threading

import numpy as np

from .errors import VoxelError

try:  # in the venv and every extension zip; without it packed layers stay arrays
    from lz4 import block as _lz4
except ImportError:  # pragma: no cover
    _lz4 = None


def pack_layers(a: np.ndarray) -> tuple:
    """(16, 16, 256) array -> (shape, lo, hi, bottom value, top value, a[:, :, lo:hi]):
    the layers below lo all hold the bottom value, those from hi up the top value
    (the viewport keeps payload light so: unpacking it costs a copy; chunks keep
    theirs as Packed)."""
    f = a.reshape(-1, a.shape[2], order="F") if a.flags.f_contiguous \
        else np.asfortranarray(a).reshape(-1, a.shape[2], order="F")
    mn = f.min(0)
    bot, top = mn[0], mn[-1]
    same = mn == f.max(0)
    odd = np.flatnonzero(~same | (mn != top))
    hi = int(odd[-1]) + 1 if odd.size else 0
    odd = np.flatnonzero(~same[:hi] | (mn[:hi] != bot))
    lo = int(odd[0]) if odd.size else hi
    return a.shape, lo, hi, bot, top, a[:, :, lo:hi].copy(order="F")


def unpack_layers(shape, lo, hi, bot, top, slab) -> np.ndarray:
    out = np.empty(shape, getattr(bot, "dtype", slab.dtype), order="F")
    out[:, :, :lo] = bot
    out[:, :, lo:hi] = slab
    out[:, :, hi:] = top
    return out


class Packed:
    """A chunk array as kept in memory (issue 29): LZ4-compressed in sections of
    SECTION layers (generated terrain's blocks and light: ~3 KB of 128 KB each).
    Sections keep every decode a small allocation (a fresh 128 KB buffer costs page
    faults: ~80 us in a big process) and let a window (an edit's: a few columns
    over some layers) decode only the sections it reads. Without the lz4 package
    the array itself is kept. A chunk read from a world file keeps the file's zstd
    frame instead (Packed.frame: no repacking, and ~1-2 KB where LZ4 took 2.7-3.9)."""

    __slots__ = ("shape", "dtype", "body", "top")
    SECTION = 32

    @classmethod
    def frame(cls, blob: bytes, shape, dtype, top: int) -> "Packed":
        """The values as one zstd frame of their bytes in linear (Fortran) order, as
        a world file stores them (issue 29: a reloaded chunk's blocks and light were
        decoded into a fresh array, then LZ4-packed: ~40 and ~25 us a chunk, and the
        array's page faults). The caller checked that it decodes to exactly the
        array (the file's reader, which decoded it once). TOP: the layer from which
        every value is 0 (the frame's zero tail), or shape[2]."""
        p = cls()
        p.shape, p.dtype, p.body, p.top = tuple(shape), np.dtype(dtype), bytes(blob), int(top)
        return p

    @classmethod
    def uniform(cls, shape, dtype, value=0) -> "Packed":
        return pack(np.full(shape, value, dtype, order="F"))

    @property
    def nbytes(self) -> int:
        b = self.body
        if isinstance(b, bytes):
            return len(b)
        return b.nbytes if isinstance(b, np.ndarray) else \
            sum(len(x) if isinstance(x, bytes) else x.nbytes for x in b)

    def unpack(self, out: np.ndarray | None = None) -> np.ndarray:
        """A new (writable, Fortran-ordered) array of the packed values, or `out`
        (Fortran-ordered, of the shape and dtype) filled with them: a save encodes
        every chunk from one reused buffer (storage/rows.py), as a fresh 128 KB
        costs page faults in a big process (~30 us)."""
        if isinstance(self.body, np.ndarray):
            if out is None:
                return self.body.copy(order="F")
            out[...] = self.body
            return out
        if out is None:
            out = np.empty(self.shape, self.dtype, order="F")
        if isinstance(self.body, bytes):
            _unframe(self.body, out)
            return out
        # section by section into the flat array: no joined copy of the decoded
        # runs (a fresh 128 KB for each: page faults; a save unpacks every chunk)
        flat = out.reshape(-1, order="F")
        w, h, z = self.shape
        n, k = w * h * self.SECTION, w * h * self.dtype.itemsize
        for t, v in enumerate(self.body):
            a = t * n
            if isinstance(v, bytes):
                m = min(self.SECTION, z - t * self.SECTION)
                flat[a:a + w * h * m] = np.frombuffer(
                    _lz4.decompress(v, uncompressed_size=k * m), self.dtype)
            else:
                flat[a:a + n] = v
        return out

    def air_from(self) -> int | None:
        """The layer from which every section holds 0 (None without sections)."""
        b = self.body
        if isinstance(b, np.ndarray):
            return None
        if isinstance(b, bytes):
            return self.top
        i = len(b)
        while i and type(b[i - 1]) is not bytes and not b[i - 1]:
            i -= 1
        return min(i * self.SECTION, self.shape[2])

    def into(self, out, xs: slice, ys: slice, z0: int, z1: int, zeroed: bool = False) -> None:
        """out[...] = unpack()[xs, ys, z0:z1], decoding only the sections it reads;
        ZEROED: out holds 0 already (sections of 0 are not written)."""
        b = self.body
        if isinstance(b, np.ndarray):
            out[...] = b[xs, ys, z0:z1]
            return
        if isinstance(b, bytes):  # the whole frame into this thread's one buffer
            if zeroed:
                z1 = max(z0, min(z1, self.top))
                out = out[:, :, :z1 - z0]
            if z1 > z0:
                out[...] = _unframe(b, scratch(self.shape, self.dtype))[xs, ys, z0:z1]
            return
        S = self.SECTION
        # part of the columns: an edit's windows, which read the same sections of
        # a 3x3 of chunks several times (light, then the mesher's ring): remembered
        memo = xs != _ALL or ys != _ALL
        i, last = z0 // S, -(-z1 // S)
        while i < last:  # runs of packed sections (one decode), of one value (a fill)
            v, j = b[i], i + 1
            if isinstance(v, bytes):
                while j < last and isinstance(b[j], bytes):
                    j += 1
                v = self._run(i, j, memo)
            else:
                while j < last and not isinstance(b[j], bytes) and b[j] == v:
                    j += 1
            za, ze = max(z0, i * S), min(z1, j * S)
            if zeroed and v.ndim == 0 and not v:
                i = j
                continue
            out[:, :, za - z0:ze - z0] = v if v.ndim == 0 else v[xs, ys, za - i * S:ze - i * S]
            i = j

    def _run(self, i: int, j: int, memo: bool) -> np.ndarray:
        """Packed sections [i, j) decoded, as a (w, h, layers) array (read-only)."""
        if memo:
            d = getattr(_memo, "d", None)
            if d is None:
                d = _memo.d = {}
            got = d.pop((self, i, j), None)
            if got is not None:
                d[(self, i, j)] = got  # the most recent last
                return got
        w, h, z = self.shape
        S, k = self.SECTION, w * h * self.dtype.itemsize
        n = min(z, j * S) - i * S
        raws = [_lz4.decompress(self.body[t], uncompressed_size=k * min(S, z - t * S))
                for t in range(i, j)]
        got = np.frombuffer(raws[0] if j == i + 1 else b"".join(raws),
                            self.dtype).reshape((w, h, n), order="F")
        if memo:
            if len(d) >= MEMO:
                del d[next(iter(d))]  # the least recently used
            d[(self, i, j)] = got
        return got


def _unframe(blob: bytes, out: np.ndarray) -> np.ndarray:
    """Decode a zstd frame (Packed.frame's) into OUT (Fortran order) in place."""
    d = getattr(_memo, "zstd", None)
    if d is None:
        import zstandard  # lazily: only chunks read from a zstd world file get here
        d = _memo.zstd = zstandard.ZstdDecompressor()
    n = d.stream_reader(blob).readinto(out.reshape(-1, order="F"))
    if n != out.nbytes:  # checked when read from the file: never expected
        raise VoxelError(f"a packed chunk array decoded to {n} bytes, expected {out.nbytes}")
    return out


def scratch(shape, dtype) -> np.ndarray:
    """This thread's one scratch array of SHAPE and DTYPE (a fresh 128 KB each time
    costs page faults), valid until the thread's next call."""
    k = (shape, dtype)
    b = getattr(_memo, "bufs", None)
    if b is None:
        b = _memo.bufs = {}
    a = b.get(k)
    if a is None:
        a = b[k] = np.empty(shape, dtype, order="F")
    return a


_ALL = slice(None)
MEMO = 32  # decoded runs of sections a thread remembers for windows
_memo = threading.local()


def pack(a: np.ndarray) -> Packed:
    """A (w, h, z) array -> Packed (its values, shape and dtype exactly; block ids
    need no narrowing: LZ4 takes their zero high bytes to nearly nothing)."""
    p = Packed()
    p.shape, p.dtype, p.top = a.shape, a.dtype, None
    if _lz4 is None or not a.size:
        p.body = np.array(a, order="F")
        return p
    f = a if a.flags.f_contiguous else np.asfortranarray(a)
    S, body = Packed.SECTION, []
    if a.shape[2] % S == 0:
        # whole sections: which hold one value, from each one's min and max at once
        # (issue 29: LZ4 and its check on every section of air or daylight cost
        # more than the terrain's own; a stream packs every chunk's blocks and light)
        secs = f.reshape(-1, order="F").reshape(a.shape[2] // S, -1)
        first, same = secs[:, 0], secs.min(1) == secs.max(1)
        p.body = tuple(first[i] if same[i] else _lz4.compress(secs[i], store_size=False)
                       for i in range(len(secs)))
        return p
    for z in range(0, a.shape[2], S):
        sec = f[:, :, z:z + S].reshape(-1, order="F")
        c = _lz4.compress(sec, store_size=False)
        # LZ4 is deterministic: the same bytes as the section filled with its first
        # value means it holds that value only (kept as the value: no decode)
        if len(c) < 128 and c == _uniform(sec[0], sec.size):
            c = sec[0]
        body.append(c)
    p.body = tuple(body)
    return p


def _uniform(v, n: int) -> bytes:
    """LZ4 of n copies of v (remembered: a few values recur: air, daylight, dark)."""
    k = (v.dtype.str, v.tobytes(), n)
    c = _UNIFORM.get(k)
    if c is None:
        c = _lz4.compress(np.full(n, v, v.dtype), store_size=False)
        if len(_UNIFORM) < 4096:
            _UNIFORM[k] = c
    return c


_UNIFORM: dict = {}
