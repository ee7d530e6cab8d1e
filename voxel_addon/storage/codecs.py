"""Chunk blob codecs. zstd is the default where `zstandard` is installed: on generated
terrain it decodes ~3-4x faster than zlib at a similar size (bench: storage area)."""
from __future__ import annotations

import struct
import sys
import threading
import zlib

import numpy as np

from ..core.errors import VoxelError

try:
    import zstandard as _zstd
except ImportError:  # the extension still works, with zlib
    _zstd = None

CODECS = ("zstd", "zlib")
_local = threading.local()


def default() -> str:
    return "zstd" if _zstd else "zlib"


def _zstd_pair():
    # Compressor objects are not thread-safe; one pair per thread.
    pair = getattr(_local, "pair", None)
    if pair is None:
        pair = _local.pair = (_zstd.ZstdCompressor(level=3), _zstd.ZstdDecompressor())
    return pair


def encode(codec: str, raw) -> bytes:
    """Compress `raw` (bytes or a byte memoryview). A zstd frame of whole 2 KiB slabs
    (a chunk's uint16 values in linear order) whose trailing zeros (the air above the
    terrain, ~60 % of a chunk's blocks) fill whole slabs ends with them as a block of
    their own: one byte repeated (an RLE block), which decodes as a memset. Left to
    the compressor they are one long match at whatever small offset the parse had
    at hand: 8-byte copies, and at an offset of 9-15 bytes each copy waits on the
    one before it (a chunk then decodes in ~75 us instead of ~21, issue 29). Still
    one plain zstd frame declaring its size (SPEC's blob; any zstd reader reads it)."""
    if codec == "zlib":
        return zlib.compress(raw, 6)
    if codec != "zstd":
        raise VoxelError(f"unknown codec {codec!r}")
    if _zstd is None:
        raise VoxelError("zstd codec needs the 'zstandard' package")
    n = len(raw)
    if n % SLAB or not 0 < n <= 1 << 17 or raw[-2:] != b"\0\0":  # light: daylight on top
        return _zstd_pair()[0].compress(raw)
    # where the zeros start, in slabs of 2 KiB (4 layers): OR of each slab's words
    words = np.frombuffer(raw, np.uint64).reshape(-1, SLAB // 8)
    used = np.flatnonzero(np.bitwise_or.reduce(words.T, axis=0))
    top = 0 if used.size == 0 else (int(used[-1]) + 1) * SLAB
    if top in (0, n):  # a frame's first block is never RLE: nothing to gain
        return _zstd_pair()[0].compress(raw)
    return _with_zeros(_zstd_pair()[0].compress(raw[:top]), n) or \
        _zstd_pair()[0].compress(raw)


SLAB = 2048
_MAGIC = b"\x28\xb5\x2f\xfd"


def _with_zeros(frame: bytes, total: int) -> bytes | None:
    """The zstd frame `frame` (RFC 8878) followed by zero bytes up to `total` bytes
    as one RLE block (at most 128 KiB), under a single-segment header declaring
    `total`; None when the frame is not the plain kind our compressor writes (then
    the caller compresses the whole)."""
    fhd = frame[4]
    if frame[:4] != _MAGIC or fhd & 0x07:  # checksum or dictionary: not ours
        return None
    single = fhd >> 5 & 1
    pos = 5 + (0 if single else 1) + ((1 if single else 0), 2, 4, 8)[fhd >> 6]
    start = pos
    while pos + 3 <= len(frame):  # block headers: bit 0 last, bits 1-2 type, 3-23 size
        h = int.from_bytes(frame[pos:pos + 3], "little")
        end = pos + 3 + (1 if h >> 1 & 3 == 1 else h >> 3)
        if h & 1:
            break
        pos = end
    else:
        return None
    if end != len(frame):
        return None
    zeros = total - _zstd.frame_content_size(frame)  # -1 (undeclared): too many, None
    if not 0 < zeros <= 1 << 17 or zeros > total:
        return None
    return b"".join((_HEAD, total.to_bytes(4, "little"),  # 4-byte size, single
                     frame[start:pos], (h & ~1).to_bytes(3, "little"), frame[pos + 3:end],
                     (1 | 1 << 1 | zeros << 3).to_bytes(3, "little"), b"\0"))


def zero_tail(blob) -> int:
    """How many zero bytes end what the zstd frame `blob` decodes to, read from its
    shape alone: encode()'s frames (a 4-byte size, one compressed block, then the
    RLE block of 0 that ends it) say it in their last block; 0 for any other shape.
    Trust it only of a blob that decoded to the size it declares: the decoder read
    the same headers, and one frame that is all there (as here) it decodes whole or
    refuses (tests/storage/test_bombs.py). The block-id check skips those zeros."""
    n = len(blob)
    if n < 16:
        return 0
    head, h = _FIRST.unpack_from(blob)
    t = _LAST.unpack_from(blob, n - 4)[0]  # the last block's header and its byte
    if head != _HEAD or h & 0xFFFFFF != (n - 16) << 3 | 4 or t >> 24 or t & 7 != 3:
        return 0  # not (compressed, not last, up to the last 4 bytes), (RLE of 0, last)
    return (t & 0xFFFFFF) >> 3


_HEAD = _MAGIC + b"\xa0"  # single segment, a 4-byte content size, no checksum
_FIRST, _LAST = struct.Struct("<5s4xI"), struct.Struct("<I")
_SIZED = struct.Struct("<5sII")  # _FIRST with the content size


def _read_into(blob, out: np.ndarray, size: int) -> None:
    """A whole zstd frame of `size` bytes decoded into OUT (this thread's context);
    ValueError when it is damaged or holds another size."""
    try:
        d = _local.d
    except AttributeError:
        d = _local.d = _zstd_pair()[1]
    try:  # zstd stops at the size the frame declares
        n = d.stream_reader(blob).readinto(out)
    except _zstd.ZstdError as e:
        raise ValueError(str(e)) from None
    if n != size:
        raise ValueError(f"decoded {n} bytes, expected {size}")


def decode_ours(blob, count: int, out: np.ndarray) -> int:
    """decode_u16 into OUT and zero_tail in one, for a frame with encode()'s header
    declaring 2 * `count` bytes (every chunk this program writes): the zero bytes it
    ends with, or -1 for any other blob (nothing written: decode_u16 decides). Its
    frame_content_size, the second header read and three calls cost ~0.4 of a
    chunk read's ~16 us (issue 29). Raises ValueError on a damaged frame."""
    if type(blob) is not bytes or len(blob) < 16 or not _WHOLE:
        return -1
    head, size, h = _SIZED.unpack_from(blob)
    if head != _HEAD or size != 2 * count:
        return -1
    _read_into(blob, out, size)
    t = _LAST.unpack_from(blob, len(blob) - 4)[0]  # as zero_tail: the last block
    if h & 0xFFFFFF != (len(blob) - 16) << 3 | 4 or t >> 24 or t & 7 != 3:
        return 0
    return (t & 0xFFFFFF) >> 3


def decode_u16(codec: str, blob, count: int, out: np.ndarray | None = None) -> np.ndarray:
    """decode() of `count` little-endian uint16 values into a new writable flat array,
    or into OUT (a C-contiguous uint16 array of `count` values: a new chunk's, a
    reader's scratch); no copy of the decoded bytes where zstd writes into the
    array. (Every chunk read runs this: its Python is kept to a few calls, issue 29.)"""
    if codec == "zstd" and _WHOLE and isinstance(blob, _BUFFERS):
        try:  # a frame declaring another size takes the general path (and fails there)
            whole = _zstd.frame_content_size(blob) == 2 * count
        except _zstd.ZstdError:
            whole = False
        if whole:
            if out is None:
                out = np.empty(count, np.uint16)
            _read_into(blob, out, 2 * count)
            return out
    got = np.frombuffer(decode(codec, blob, 2 * count), "<u2")
    if out is None:
        return got.astype(np.uint16)
    out.reshape(-1)[...] = got
    return out


def framed(codec: str, blob, size: int) -> bool:
    """Whether BLOB is a zstd frame declaring `size` bytes that this machine's
    arrays can take as is (zstd installed, little-endian): what decode_u16 writes
    straight into an array, and what a chunk may keep in memory as read
    (core.chunk.Packed.frame) once it decoded."""
    if codec != "zstd" or not _WHOLE or not isinstance(blob, _BUFFERS):
        return False
    try:
        return _zstd.frame_content_size(blob) == size
    except _zstd.ZstdError:
        return False


LITTLE = sys.byteorder == "little"
_WHOLE = _zstd is not None and LITTLE  # zstd may write straight into our arrays
_BUFFERS = (bytes, bytearray, memoryview)


def decode(codec: str, blob: bytes, size: int) -> bytes:
    """Decompress exactly `size` bytes; raises ValueError on damaged data or a wrong
    size. Hostile input: never more than `size` + 1 bytes are inflated (a 65 KB zstd
    frame can declare 2 GiB of zeros, a zlib stream 1000x its size)."""
    if not isinstance(blob, (bytes, bytearray, memoryview)):  # SQLite columns are untyped
        raise ValueError(f"a {type(blob).__name__} where a blob belongs")
    if codec == "zlib":
        return inflate(blob, size)
    if codec == "zstd":
        if _zstd is None:
            raise VoxelError("this world uses zstd; install the 'zstandard' package")
        return unzstd(blob, size)
    raise ValueError(f"unknown codec {codec!r}")


def inflate(blob, size: int, wbits: int = zlib.MAX_WBITS) -> bytes:
    """zlib (or with wbits 31 gzip) data that must hold exactly `size` bytes."""
    d = zlib.decompressobj(wbits)
    try:
        raw = d.decompress(blob, size + 1)
    except zlib.error as e:
        raise ValueError(str(e)) from None
    if len(raw) != size or not d.eof:
        raise ValueError(f"decoded {len(raw)}{'' if d.eof else '+'} bytes, expected {size}")
    return raw


def unzstd(blob, size: int) -> bytes:
    """One zstd frame that must hold exactly `size` bytes. A frame declaring another
    size is refused before decoding (python-zstandard allocates what the header says
    and ignores max_output_size then); one declaring none is decoded into `size` + 1."""
    try:
        declared = _zstd.frame_content_size(blob)
        if declared not in (-1, size):
            raise ValueError(f"frame declares {declared} bytes, expected {size}")
        raw = _zstd_pair()[1].decompress(blob, max_output_size=size + 1)
    except _zstd.ZstdError as e:
        raise ValueError(str(e)) from None
    if len(raw) != size:
        raise ValueError(f"decoded {len(raw)} bytes, expected {size}")
    return raw
