"""Chunk blob codecs. zstd is the default where `zstandard` is installed: on generated
terrain it decodes ~3-4x faster than zlib at a similar size (bench: storage area)."""
from __future__ import annotations

import threading
import zlib

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


def encode(codec: str, raw: bytes) -> bytes:
    if codec == "zlib":
        return zlib.compress(raw, 6)
    if codec == "zstd":
        if _zstd is None:
            raise VoxelError("zstd codec needs the 'zstandard' package")
        return _zstd_pair()[0].compress(raw)
    raise VoxelError(f"unknown codec {codec!r}")


def decode(codec: str, blob: bytes, size: int) -> bytes:
    """Decompress; raises ValueError on damaged data or a wrong size."""
    if codec == "zlib":
        try:
            raw = zlib.decompress(blob)
        except zlib.error as e:
            raise ValueError(str(e)) from None
    elif codec == "zstd":
        if _zstd is None:
            raise VoxelError("this world uses zstd; install the 'zstandard' package")
        try:
            raw = _zstd_pair()[1].decompress(blob, max_output_size=size)
        except _zstd.ZstdError as e:
            raise ValueError(str(e)) from None
    else:
        raise ValueError(f"unknown codec {codec!r}")
    if len(raw) != size:
        raise ValueError(f"decoded {len(raw)} bytes, expected {size}")
    return raw
