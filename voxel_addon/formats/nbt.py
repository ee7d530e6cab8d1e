"""A small, bounded reader of Minecraft's NBT:
big-endian named tags. Hostile input: every length is checked against the bytes
left before anything is allocated, nesting stops at 512 levels (an explicit stack,
no recursion), a parse reads at most `limit` tags (arrays and lists of numbers count
as one, they are views) and never past its buffer. A fault is an NbtError (a
ValueError) with the offset; too many tags or levels is a Hostile (an NbtError and a
budget.Exceeded: callers refuse the whole file).

`parse(buf, keep)` returns the root compound as a dict; `keep` ({name: sub-keep or
None for all of it}) limits a compound, or each compound of a list, to those
entries and skips the rest without building them (a chunk's entities, heightmaps,
light and block properties cost most of a full parse). Lists of
numbers and the array tags come back as NumPy arrays (big-endian dtypes), other
lists as Python lists, strings as str (modified UTF-8 read as UTF-8, errors
replaced). Chunk palettes repeat across sections and chunks: a short list met before
with the same bytes is replayed (a fresh copy, the same tags charged: _LISTS).
"""
from __future__ import annotations

import struct

import numpy as np

from .budget import Exceeded

END, BYTE, SHORT, INT, LONG, FLOAT, DOUBLE, BYTES, STRING, LIST, COMPOUND, INTS, LONGS = range(13)
MAX_DEPTH = 512
MAX_TAGS = 1 << 19   # one parse; a full 1.21 chunk has a few thousand
_FIXED = {BYTE: ">i1", SHORT: ">i2", INT: ">i4", LONG: ">i8", FLOAT: ">f4", DOUBLE: ">f8"}
_DT = {t: np.dtype(d) for t, d in {**_FIXED, BYTES: ">i1", INTS: ">i4", LONGS: ">i8"}.items()}
# bytes per element: scalars and numeric list items; arrays' items
_SIZE = {t: np.dtype(d).itemsize for t, d in _FIXED.items()}
_ASIZE = {BYTES: 1, INTS: 4, LONGS: 8}
_UNPACK = {t: struct.Struct(d.replace("i1", "b").replace("i2", "h").replace("i4", "i")
                            .replace("i8", "q").replace("f4", "f").replace("f8", "d")).unpack_from
           for t, d in _FIXED.items()}
_I32 = struct.Struct(">i").unpack_from


class NbtError(ValueError):
    pass


class Hostile(NbtError, Exceeded):
    """Past a limit no real file comes near (tags, nesting): refuse the whole file."""


class TooMany(Hostile):
    """More tags than the parse's limit."""


_KEEPS: dict = {}   # id(keep) -> (keep, its bytes-keyed copy); holding keep pins the id
_TEXT: dict = {}    # raw -> str of short names and strings met before (block names repeat)
_TEXT_MAX = 1 << 14


def _text(raw: bytes) -> str:
    s = raw.decode("utf-8", "replace")
    if len(raw) <= 64:   # names and block states, not arbitrary text
        if len(_TEXT) >= _TEXT_MAX:
            _TEXT.clear()
        _TEXT[raw] = s
    return s


def _bytes_keys(keep):
    """`keep` with names as bytes (compared before decoding) -> (sub-keep likewise, name)."""
    if keep is None:
        return None
    got = _KEEPS.get(id(keep))
    if got is None:
        if len(_KEEPS) > 256:
            _KEEPS.clear()
            _LISTS.clear()   # its keys hold ids of the keeps
            _HELD[0] = 0
        got = _KEEPS[id(keep)] = (keep, {k.encode(): (_bytes_keys(v), k) for k, v in keep.items()})
    return got[1]


# Lists met before (a chunk's block and biome palettes repeat across sections and
# chunks): (their first bytes, items, item tag, id of their keep) -> [(their bytes,
# value, tags)]. A list whose bytes match one of these is not parsed again: its tags
# are charged all the same, and only lists of strings or of compounds of strings (and
# compounds of strings: block properties) are kept, two levels deep, so the nesting
# limit cannot be passed on a replay (used only below depth _SHALLOW).
_LISTS: dict = {}
_LISTS_MAX, _PER_KEY, _PREFIX, _SHALLOW = 1024, 16, 24, 64
_RAW_MAX = 2048   # bytes of one remembered list (a real palette: tens to hundreds)
# bytes remembered in all: the values of a hostile list may take ~30x its bytes
_HELD, _HELD_MAX = [0], 1 << 20


def _plain(v) -> bool:
    return all(type(x) is str or (type(x) is dict and all(
        type(y) is str or (type(y) is dict and all(type(z) is str for z in y.values()))
        for y in x.values())) for x in v)


def _copy(v) -> list:
    """A list of _plain values, fresh down to its dicts (callers may change them)."""
    return [x if type(x) is str else
            {a: (dict(y) if type(y) is dict else y) for a, y in x.items()} for x in v]


def _length(b, pos, n, size):
    if pos + 4 > n:
        raise NbtError(f"NBT ends early at byte {pos} (wants 4 more)")
    (k,) = _I32(b, pos)
    if k < 0:
        raise NbtError(f"negative length {k} at byte {pos}")
    if pos + 4 + k * size > n:   # before anything is allocated
        raise NbtError(f"NBT ends early at byte {pos + 4} (wants {k * size} more)")
    return k


def _remember(rec, raw: bytes, tags: int) -> None:
    _, _, _, mk, v = rec
    if len(raw) > _RAW_MAX or not _plain(v):   # palettes are small; memory stays bounded
        return
    if len(_LISTS) >= _LISTS_MAX or _HELD[0] + len(raw) > _HELD_MAX:
        _LISTS.clear()
        _HELD[0] = 0
    got = _LISTS.setdefault(mk, [])
    if len(got) < _PER_KEY:
        got.append((raw, _copy(v), tags))
        _HELD[0] += len(raw)


def read(buf, keep=None, limit: int = MAX_TAGS):
    """(root compound, tags read) of an NBT document; see the module docstring."""
    b = buf if isinstance(buf, bytes) else bytes(buf)
    n = len(b)
    if n < 3 or b[0] != COMPOUND:
        raise NbtError("not NBT (the root is not a compound)")
    pos = 3 + (b[1] << 8 | b[2])
    if pos > n:
        raise NbtError("a string runs past the NBT at byte 1")
    kb = _bytes_keys(keep)
    SIZE, ASIZE, UNPACK, DT, frombuffer = _SIZE, _ASIZE, _UNPACK, _DT, np.frombuffer
    text, known = _text, _TEXT.get
    lists, rec = _LISTS.get, None   # rec: the list being remembered (_remember)
    root = {}
    left = limit
    # the open container: out (dict, list, or None while skipping), its keep, its list
    # item tag (None: a compound) and items left; its parents wait on `stack`
    out, k, item, cnt = root, kb, None, 0
    stack = []
    while True:
        if item is None:               # a compound: its next named tag
            if pos >= n:
                raise NbtError(f"NBT ends early at byte {pos} (wants 1 more)")
            t = b[pos]
            if t == END:
                pos += 1
                if not stack:
                    break
                out, k, item, cnt = stack.pop()
                continue
            if pos + 3 > n:
                raise NbtError(f"NBT ends early at byte {pos + 1}")
            s = pos + 3
            pos = s + (b[pos + 1] << 8 | b[pos + 2])
            if pos > n:
                raise NbtError(f"a string runs past the NBT at byte {s - 2}")
            name = sub = None
            if out is not None:
                key = b[s:pos]
                if k is None:
                    name = known(key) or text(key)
                else:
                    got = k.get(key)
                    if got is not None:
                        sub, name = got
                    # else: skipped, name stays None
        else:                          # a list: its next item
            if cnt == 0:
                if rec is not None and len(stack) == rec[0]:   # the list to remember
                    _remember(rec, b[rec[1]:pos], rec[2] - left)
                    rec = None
                out, k, item, cnt = stack.pop()   # a list is never the root
                continue
            cnt -= 1
            t, sub, name = item, k, (True if out is not None else None)
        left -= 1
        if left < 0:
            raise TooMany(f"more than {limit:,} NBT tags")
        build = name is not None
        # the value of tag t at pos
        if t == STRING:
            if pos + 2 > n:
                raise NbtError(f"NBT ends early at byte {pos}")
            e = pos + 2 + (b[pos] << 8 | b[pos + 1])
            if e > n:
                raise NbtError(f"a string runs past the NBT at byte {pos}")
            if build:
                r = b[pos + 2:e]
                v = known(r) or text(r)
            else:
                v = None
            pos = e
        elif t in SIZE:
            e = pos + SIZE[t]
            if e > n:
                raise NbtError(f"NBT ends early at byte {pos} (wants {SIZE[t]} more)")
            v = UNPACK[t](b, pos)[0] if build else None
            pos = e
        elif t in ASIZE:
            c = _length(b, pos, n, ASIZE[t])
            v = frombuffer(b, DT[t], c, pos + 4) if build else None
            pos += 4 + c * ASIZE[t]
        elif t == LIST:
            if pos + 1 > n:
                raise NbtError(f"NBT ends early at byte {pos} (wants 1 more)")
            it = b[pos]
            if it in SIZE:
                c = _length(b, pos + 1, n, SIZE[it])
                v = frombuffer(b, DT[it], c, pos + 5) if build else None
                pos += 5 + c * SIZE[it]
            elif it == END:
                _length(b, pos + 1, n, 0)
                v = [] if build else None
                pos += 5
            elif it > LONGS:
                raise NbtError(f"unknown list item tag {it} at byte {pos}")
            else:
                c = _length(b, pos + 1, n, 1)
                pos += 5
                v = [] if build else None
                if c and build and len(stack) < _SHALLOW:
                    mk = (b[pos:pos + _PREFIX], c, it, id(sub))
                    for raw, val, tags in lists(mk, ()):
                        if tags <= left and b.startswith(raw, pos):
                            v = _copy(val)
                            pos += len(raw)
                            left -= tags
                            c = 0   # read: assigned below as an empty list would be
                            break
                    else:   # the innermost list open is the one remembered
                        rec = (len(stack) + 1, pos, left, mk, v)
                if c:
                    if build:
                        if name is True:
                            out.append(v)
                        else:
                            out[name] = v
                    if len(stack) >= MAX_DEPTH - 1:
                        raise Hostile("NBT nested deeper than 512 levels")
                    stack.append((out, k, item, cnt))
                    out, k, item, cnt = v, sub, it, c
                    continue
                # else: v is [] or a remembered list, assigned below
        elif t == COMPOUND:
            if len(stack) >= MAX_DEPTH - 1:
                raise Hostile("NBT nested deeper than 512 levels")
            v = {} if build else None
            if build:
                if name is True:
                    out.append(v)
                else:
                    out[name] = v
            stack.append((out, k, item, cnt))
            out, k, item, cnt = v, sub, None, 0
            continue
        else:
            raise NbtError(f"unknown tag {t} at byte {pos}")
        if build:
            if name is True:
                out.append(v)
            else:
                out[name] = v
    return root, limit - left


def parse(buf, keep=None, limit: int = MAX_TAGS) -> dict:
    """The root compound of an NBT document (its name dropped)."""
    return read(buf, keep, limit)[0]
