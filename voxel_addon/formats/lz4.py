"""LZ4 as Minecraft writes it (chunk compression type 4, since 24w04a): lz4-java's
LZ4BlockOutputStream framing around LZ4 blocks. Each block: the magic "LZ4Block",
a token byte (method: 0x10 raw, 0x20 LZ4; low 4 bits the level), compressed and
decompressed lengths (little-endian int32) and a checksum (not checked: the NBT
and the size checks catch damage); a block of length 0 ends the stream.

Uses the `lz4` package for the block format where it is installed; otherwise a
small pure-Python decoder (LZ4 blocks are a few hundred sequences per chunk, so
~1 ms each). Both stop at `limit` bytes of output.
"""
from __future__ import annotations

import struct

MAGIC = b"LZ4Block"
_HEAD = struct.Struct("<BiiI")


class TooLarge(ValueError):
    """The stream decodes to more than its limit."""


try:
    from lz4 import block as _block
except ImportError:
    _block = None


def decode_block(src, size: int) -> bytes:
    """One raw LZ4 block that must decode to exactly `size` bytes."""
    if _block is not None:
        try:
            out = _block.decompress(bytes(src), uncompressed_size=size)
        except Exception as e:  # lz4.block.LZ4BlockError
            raise ValueError(f"damaged LZ4 block ({e})") from None
        if len(out) != size:
            raise ValueError(f"LZ4 block decoded {len(out)} bytes, expected {size}")
        return out
    return _decode(src, size)


def _more(src: bytes, i: int, k: int) -> tuple[int, int]:
    """A length of 15 continues in bytes of 255 and a last one below: (length, next i)."""
    n = len(src)
    while True:
        if i >= n:
            raise ValueError("LZ4 block ends inside a length")
        b = src[i]
        i += 1
        k += b
        if b != 255:
            return k, i


def _decode(src, size: int) -> bytes:
    src = bytes(src)
    out = bytearray()
    i, n = 0, len(src)
    while i < n:
        token = src[i]
        i += 1
        k = token >> 4
        if k == 15:
            k, i = _more(src, i, k)
        if i + k > n or len(out) + k > size:
            raise ValueError("LZ4 literals run past the block or the expected size")
        out += src[i:i + k]
        i += k
        if i == n:
            break  # the last sequence has literals only
        if i + 2 > n:
            raise ValueError("LZ4 block ends inside an offset")
        off = src[i] | src[i + 1] << 8
        i += 2
        m = token & 15
        if m == 15:
            m, i = _more(src, i, m)
        m += 4
        if off == 0 or off > len(out):
            raise ValueError(f"LZ4 match offset {off} outside the output")
        if len(out) + m > size:
            raise ValueError("LZ4 block decodes past the expected size")
        start = len(out) - off
        if off >= m:
            out += out[start:start + m]
        else:  # overlapping: the last `off` bytes repeat
            pat = bytes(out[start:])
            out += (pat * (m // off + 1))[:m]
    if len(out) != size:
        raise ValueError(f"LZ4 block decoded {len(out)} bytes, expected {size}")
    return bytes(out)


def decode_stream(data, limit: int) -> bytes:
    """An lz4-java block stream, at most `limit` bytes of output."""
    data = memoryview(data)
    out = bytearray()
    pos = 0
    while True:
        if pos == len(data) and out:  # a stream cut after a whole block: no end mark
            return bytes(out)
        if bytes(data[pos:pos + 8]) != MAGIC or pos + 8 + _HEAD.size > len(data):
            raise ValueError("not an LZ4Block stream (no magic where a block should start)")
        token, clen, dlen, _ = _HEAD.unpack_from(data, pos + 8)
        pos += 8 + _HEAD.size
        method = token & 0xF0
        if clen < 0 or dlen < 0 or pos + clen > len(data):
            raise ValueError("LZ4Block lengths run past the data")
        if clen == 0 and dlen == 0:
            return bytes(out)
        if len(out) + dlen > limit:
            raise TooLarge(f"LZ4 data larger than {limit} bytes")
        body = data[pos:pos + clen]
        if method == 0x10:
            if clen != dlen:
                raise ValueError("raw LZ4Block with two lengths")
            out += body
        elif method == 0x20:
            out += decode_block(body, dlen)
        else:
            raise ValueError(f"unknown LZ4Block method {method:#x}")
        pos += clen
