"""A small, bounded reader of Minecraft's NBT:
big-endian named tags. Hostile input: every length is checked against the bytes
left before anything is allocated, nesting stops at 512 levels, and a parse never
reads past its buffer; any fault is an NbtError (a ValueError) with the offset.

`parse(buf, keep)` returns the root compound as a dict; `keep` ({name: sub-keep or
None for all of it}) limits a compound, or each compound of a list, to those
entries and skips the rest without building them (a chunk's entities, heightmaps,
light and block properties cost most of a full parse). Lists of
numbers and the array tags come back as NumPy arrays (big-endian dtypes), other
lists as Python lists, strings as str (modified UTF-8 read as UTF-8, errors
replaced).
"""
from __future__ import annotations

import struct

import numpy as np

END, BYTE, SHORT, INT, LONG, FLOAT, DOUBLE, BYTES, STRING, LIST, COMPOUND, INTS, LONGS = range(13)
MAX_DEPTH = 512
_FIXED = {BYTE: ">i1", SHORT: ">i2", INT: ">i4", LONG: ">i8", FLOAT: ">f4", DOUBLE: ">f8"}
_SIZE = {t: np.dtype(d).itemsize for t, d in _FIXED.items()}
_ARRAY = {BYTES: ">i1", INTS: ">i4", LONGS: ">i8"}
_SCALAR = {t: struct.Struct(d.replace("i1", "b").replace("i2", "h").replace("i4", "i")
                            .replace("i8", "q").replace("f4", "f").replace("f8", "d"))
           for t, d in _FIXED.items()}
_U16 = struct.Struct(">H")
_I32 = struct.Struct(">i")


class NbtError(ValueError):
    pass


class _Reader:
    __slots__ = ("buf", "n")

    def __init__(self, buf):
        self.buf = bytes(buf)
        self.n = len(self.buf)

    def need(self, pos: int, k: int) -> int:
        if k < 0 or pos + k > self.n:
            raise NbtError(f"NBT ends early at byte {pos} (wants {k} more)")
        return pos + k

    def string(self, pos):
        if pos + 2 > self.n:
            raise NbtError(f"NBT ends early at byte {pos}")
        stop = pos + 2 + (self.buf[pos] << 8 | self.buf[pos + 1])
        if stop > self.n:
            raise NbtError(f"a string runs past the NBT at byte {pos}")
        return self.buf[pos + 2:stop].decode("utf-8", "replace"), stop

    def length(self, pos, size):
        end = self.need(pos, 4)
        (k,) = _I32.unpack_from(self.buf, pos)
        if k < 0:
            raise NbtError(f"negative length {k} at byte {pos}")
        self.need(end, k * size)  # before anything is allocated
        return k, end

    def value(self, tag, pos, depth, keep=None):
        if depth > MAX_DEPTH:
            raise NbtError("NBT nested deeper than 512 levels")
        s = _SCALAR.get(tag)
        if s is not None:
            end = self.need(pos, s.size)
            return s.unpack_from(self.buf, pos)[0], end
        if tag == STRING:
            return self.string(pos)
        if tag in _ARRAY:
            dt = np.dtype(_ARRAY[tag])
            k, pos = self.length(pos, dt.itemsize)
            return np.frombuffer(self.buf, dt, k, pos), pos + k * dt.itemsize
        if tag == LIST:
            end = self.need(pos, 1)
            item = self.buf[pos]
            k, pos = self.length(end, _SIZE.get(item, 1 if item != END else 0))
            if item in _FIXED:
                dt = np.dtype(_FIXED[item])
                return np.frombuffer(self.buf, dt, k, pos), pos + k * dt.itemsize
            if item == END:
                return [], pos
            if item > LONGS:
                raise NbtError(f"unknown list item tag {item} at byte {end}")
            out = []
            for _ in range(k):
                v, pos = self.value(item, pos, depth + 1, keep)
                out.append(v)
            return out, pos
        if tag == COMPOUND:
            return self.compound(pos, depth + 1, keep)
        raise NbtError(f"unknown tag {tag} at byte {pos}")

    def skip(self, tag, pos, depth):
        if depth > MAX_DEPTH:
            raise NbtError("NBT nested deeper than 512 levels")
        if tag in _SIZE:
            return self.need(pos, _SIZE[tag])
        if tag == STRING:
            end = self.need(pos, 2)
            return self.need(end, _U16.unpack_from(self.buf, pos)[0])
        if tag in _ARRAY:
            size = np.dtype(_ARRAY[tag]).itemsize
            k, pos = self.length(pos, size)
            return pos + k * size
        if tag == LIST:
            end = self.need(pos, 1)
            item = self.buf[pos]
            k, pos = self.length(end, _SIZE.get(item, 1 if item != END else 0))
            if item in _SIZE:
                return pos + k * _SIZE[item]
            if item > LONGS:
                raise NbtError(f"unknown list item tag {item} at byte {end}")
            for _ in range(k):
                pos = self.skip(item, pos, depth + 1)
            return pos
        if tag == COMPOUND:
            while True:
                end = self.need(pos, 1)
                t = self.buf[pos]
                if t == END:
                    return end
                e2 = self.need(end, 2)
                pos = self.skip(t, self.need(e2, _U16.unpack_from(self.buf, end)[0]), depth + 1)
        raise NbtError(f"unknown tag {tag} at byte {pos}")

    def compound(self, pos, depth, keep):
        out = {}
        while True:
            end = self.need(pos, 1)
            t = self.buf[pos]
            if t == END:
                return out, end
            name, pos = self.string(end)
            if keep is None:
                out[name], pos = self.value(t, pos, depth)
            elif name in keep:
                out[name], pos = self.value(t, pos, depth, keep[name])
            else:
                pos = self.skip(t, pos, depth)


def parse(buf, keep=None) -> dict:
    """The root compound of an NBT document (its name dropped)."""
    r = _Reader(buf)
    if r.n < 3 or r.buf[0] != COMPOUND:
        raise NbtError("not NBT (the root is not a compound)")
    _, pos = r.string(1)
    out, _ = r.compound(pos, 0, keep)
    return out
