"""anvil.read's fast path for 1.18+ chunks: one pass over the chunk's tag stream that
keeps only what the import needs (DataVersion, Status, each section's Y, block
palette and longs, biome palette and longs) and steps over everything else without
building objects. A block palette met before (they repeat across sections and
chunks) is matched by its bytes and replayed as the same (immutable) names and
properties, with a `key` (those bytes) that formats/minecraft.convert maps in one
lookup; so is a whole section without block longs (the air above ground: Y, palette,
biomes and light the same bytes from chunk to chunk), its tags charged the same.

It accepts only well-formed chunks: anything unusual (a type it does not expect, a
missing Y, a length that does not fit, nesting deeper than DEPTH, more tags than the
limit, a chunk from before 1.18) is `Bail`, and anvil.read then parses the chunk with
the general reader (nbt.read), which gives the one-line error or the result. So a
hostile file meets exactly the limits and messages of nbt.py; this path only has to
give, for what it accepts, what the general one gives (tests/formats/test_chunkscan.py:
the same sections and the same tags counted)."""
from __future__ import annotations

import struct

import numpy as np

from .nbt import BYTE, BYTES, COMPOUND, DOUBLE, END, FLOAT, INT, INTS, LIST, LONG, LONGS, SHORT, STRING

DEPTH = 48             # real chunks nest ~8 deep; deeper goes to the general reader
V_NO_LEVEL = 2844      # = anvil.V_NO_LEVEL (anvil imports this module)
_FIX = {BYTE: 1, SHORT: 2, INT: 4, LONG: 8, FLOAT: 4, DOUBLE: 8}
_ARR = {BYTES: 1, INTS: 4, LONGS: 8}
_I32 = struct.Struct(">i").unpack_from
_LONGS = np.dtype(">i8")


class Bail(Exception):
    """Not a chunk this path reads: the general reader decides."""


class Palette:
    """A block palette as read: names, each entry's properties (or None for all),
    the tags it holds, and its bytes (`key`: equal bytes, equal palette)."""
    __slots__ = ("names", "props", "tags", "key")

    def __init__(self, names, props, tags, key):
        self.names, self.props, self.tags, self.key = names, props, tags, key


# palettes met before: (first bytes, entries) -> [Palette]; bounded like nbt._LISTS
_MEMO: dict = {}
_MEMO_MAX, _PER_KEY, _PREFIX, _RAW_MAX, _HELD_MAX = 1024, 16, 24, 2048, 1 << 20
_held = [0]
_BIOMES: dict = {}     # bytes of a biome palette -> its names; both memos hold at most
# _MEMO_MAX keys and _HELD_MAX bytes of palettes (a hostile flood of distinct ones)


_SECS: dict = {}       # a section without block longs (most: all air) by its first bytes ->
_SEC_MAX = 8192        # [(its bytes, [y, Palette, None, biomes], tags)]: the same bytes,
# the same section (its Y among them); sections of at most _SEC_MAX bytes, bounded as above


def _clear() -> None:
    _MEMO.clear()
    _BIOMES.clear()
    _SECS.clear()
    _held[0] = 0


def _remember(mk, p: Palette) -> None:
    if len(p.key) > _RAW_MAX:
        return
    if len(_MEMO) >= _MEMO_MAX or _held[0] + len(p.key) > _HELD_MAX:
        _clear()
    got = _MEMO.setdefault(mk, [])
    if len(got) < _PER_KEY:
        got.append(p)
        _held[0] += len(p.key)


def _remember_section(mk, raw, sec, tags) -> None:
    if len(_SECS) >= _MEMO_MAX or _held[0] + len(raw) > _HELD_MAX:
        _clear()
    got = _SECS.setdefault(mk, [])
    if len(got) < _PER_KEY:
        if sec is not None and sec[3] is not None and sec[3][1] is not None:
            sec = [*sec[:3], (sec[3][0], sec[3][1].copy())]   # not a view of the chunk
        got.append((raw, sec, tags))
        _held[0] += len(raw)


def _text(raw: bytes) -> str:
    return raw.decode("utf-8", "replace")   # as nbt.py


def _skip(b, pos, t, tags, limit, depth):
    """(position after the value of tag `t` at pos, tags counted with those inside it):
    counted as nbt.read counts (each named tag and list item one; a list of numbers
    or an array one, its items none)."""
    stack = []
    while True:
        if t == COMPOUND:
            if depth + len(stack) >= DEPTH:
                raise Bail
            stack.append(None)
        elif t == LIST:
            it = b[pos]
            (c,) = _I32(b, pos + 1)
            pos += 5
            if c < 0 or it > LONGS:
                raise Bail
            if it in _FIX:
                pos += c * _FIX[it]
            elif it != END and c:   # a list of END holds nothing, whatever its length
                if depth + len(stack) >= DEPTH:
                    raise Bail
                tags += c
                if tags > limit:
                    raise Bail
                stack.append([it, c])
        elif t == STRING:
            pos += 2 + (b[pos] << 8 | b[pos + 1])
        elif t in _FIX:
            pos += _FIX[t]
        elif t in _ARR:
            (c,) = _I32(b, pos)
            if c < 0:
                raise Bail
            pos += 4 + c * _ARR[t]
        else:
            raise Bail
        while True:   # the next value, or done
            if not stack:
                return pos, tags
            top = stack[-1]
            if top is None:       # in a compound: its next named tag
                t = b[pos]
                if t == END:
                    pos += 1
                    stack.pop()
                    continue
                pos += 3 + (b[pos + 1] << 8 | b[pos + 2])
                tags += 1
                if tags > limit:
                    raise Bail
                break
            if top[1] == 0:       # a list's items (charged when it opened)
                stack.pop()
                continue
            top[1] -= 1
            t = top[0]
            break


def _entries(b, pos, c, tags, limit):
    """A block palette of c compounds at pos: (names, props, pos after, tags)."""
    names, props = [], []
    for _ in range(c):
        tags += 1
        name = pr = None
        while True:
            t = b[pos]
            if t == END:
                pos += 1
                break
            s = pos + 3
            pos = s + (b[pos + 1] << 8 | b[pos + 2])
            key = b[s:pos]
            tags += 1
            if key == b"Name":
                if t != STRING:
                    raise Bail
                e = pos + 2 + (b[pos] << 8 | b[pos + 1])
                name = _text(b[pos + 2:e])
                pos = e
            elif key == b"Properties":
                if t != COMPOUND:
                    raise Bail
                pr = {}
                while True:
                    t = b[pos]
                    if t == END:
                        pos += 1
                        break
                    if t != STRING:
                        raise Bail
                    s = pos + 3
                    pos = s + (b[pos + 1] << 8 | b[pos + 2])
                    e = pos + 2 + (b[pos] << 8 | b[pos + 1])
                    pr[_text(b[s:pos])] = _text(b[pos + 2:e])
                    pos = e
                    tags += 1
            else:
                pos, tags = _skip(b, pos, t, tags, limit, 4)
        if name is None or pos > len(b):
            raise Bail
        names.append(name)
        props.append(pr)
    if tags > limit:
        raise Bail
    return names, props, pos, tags


def _palette(b, pos, tags, limit):
    """The block palette list whose item tag is at pos: (Palette, pos after, tags)."""
    if b[pos] != COMPOUND:
        raise Bail
    (c,) = _I32(b, pos + 1)
    if c <= 0 or tags + c > limit:
        raise Bail
    pos += 5
    mk = (b[pos:pos + _PREFIX], c)
    for p in _MEMO.get(mk, ()):
        if b.startswith(p.key, pos):
            return p, pos + len(p.key), tags + p.tags
    names, props, end, got = _entries(b, pos, c, 0, limit - tags)
    p = Palette(names, props if any(props) else None, got, b[pos:end])
    _remember(mk, p)
    return p, end, tags + got


def _longs(b, pos):
    (c,) = _I32(b, pos)
    if c < 0:
        raise Bail
    return np.frombuffer(b, _LONGS, c, pos + 4), pos + 4 + 8 * c


def _biomes(b, pos, tags, limit):
    """A section's biomes compound at pos: ((names, longs or None) or None, pos, tags)."""
    names = data = None
    while True:
        t = b[pos]
        if t == END:
            pos += 1
            break
        s = pos + 3
        pos = s + (b[pos + 1] << 8 | b[pos + 2])
        key = b[s:pos]
        tags += 1
        if key == b"palette":
            if t != LIST:
                raise Bail
            it = b[pos]
            (c,) = _I32(b, pos + 1)
            if c < 0 or tags + c > limit:
                raise Bail
            if it == END:
                names, pos = [], pos + 5
                continue
            if it != STRING:
                raise Bail
            start = pos = pos + 5
            for _ in range(c):
                pos += 2 + (b[pos] << 8 | b[pos + 1])
            raw = b[start:pos]
            names = _BIOMES.get(raw)
            if names is None:
                names, q = [], start
                for _ in range(c):
                    e = q + 2 + (b[q] << 8 | b[q + 1])
                    names.append(_text(b[q + 2:e]))
                    q = e
                if len(raw) <= _RAW_MAX:
                    if len(_BIOMES) >= _MEMO_MAX or _held[0] + len(raw) > _HELD_MAX:
                        _clear()
                    _BIOMES[raw] = names
                    _held[0] += len(raw)
            tags += c
        elif key == b"data":
            if t != LONGS:
                raise Bail
            data, pos = _longs(b, pos)
        else:
            pos, tags = _skip(b, pos, t, tags, limit, 3)
    return ((names, data) if names else None), pos, tags


def scan(b: bytes, limit: int):
    """(DataVersion, Status, sections, tags) of a 1.18+ chunk's NBT; each section
    [y, Palette, packed longs or None, biomes or None] in file order (sections
    without block_states left out), checked as anvil._section checks them. Bail
    when the general reader must decide."""
    try:
        return _scan(b, limit)
    except (IndexError, ValueError, struct.error):   # ran past the end, a bad view
        raise Bail from None


def _scan(b, limit):
    n = len(b)
    if n < 3 or b[0] != COMPOUND:
        raise Bail
    pos = 3 + (b[1] << 8 | b[2])
    version, status, secs, tags = None, "full", None, 0
    while True:
        t = b[pos]
        if t == END:
            pos += 1
            break
        s = pos + 3
        pos = s + (b[pos + 1] << 8 | b[pos + 2])
        key = b[s:pos]
        tags += 1
        if key == b"sections":
            if t != LIST:
                raise Bail
            it = b[pos]
            (c,) = _I32(b, pos + 1)
            pos += 5
            if c < 0 or it not in (COMPOUND, END):
                raise Bail
            secs = []
            if it == END:
                continue
            tags += c
            for _ in range(c):
                mk = b[pos:pos + _PREFIX]
                for raw, sec, k in _SECS.get(mk, ()):
                    if b.startswith(raw, pos):
                        pos += len(raw)
                        tags += k
                        if tags > limit:
                            raise Bail
                        break
                else:
                    start, before = pos, tags
                    sec, pos, tags = _section(b, pos, tags, limit)
                    if pos - start <= _SEC_MAX and (sec is None or sec[2] is None):
                        _remember_section(mk, b[start:pos], sec, tags - before)
                if sec is not None:
                    secs.append(sec)
        elif key == b"DataVersion":
            if t != INT:
                raise Bail
            (version,) = _I32(b, pos)
            pos += 4
        elif key == b"Status":
            if t != STRING:
                raise Bail
            e = pos + 2 + (b[pos] << 8 | b[pos + 1])
            status = _text(b[pos + 2:e])
            pos = e
        elif key == b"Level":
            raise Bail
        else:
            pos, tags = _skip(b, pos, t, tags, limit, 1)
        if tags > limit:
            raise Bail
    if pos > n or version is None or version < V_NO_LEVEL or tags > limit:
        raise Bail
    return version, status, [] if secs is None else secs, tags


def _section(b, pos, tags, limit):
    y, have, pal, data, bio = None, False, None, None, None
    while True:
        t = b[pos]
        if t == END:
            pos += 1
            break
        s = pos + 3
        pos = s + (b[pos + 1] << 8 | b[pos + 2])
        key = b[s:pos]
        tags += 1
        if key == b"block_states":
            if t != COMPOUND:
                raise Bail
            have, pal, data = True, None, None
            while True:
                t = b[pos]
                if t == END:
                    pos += 1
                    break
                s = pos + 3
                pos = s + (b[pos + 1] << 8 | b[pos + 2])
                k = b[s:pos]
                tags += 1
                if k == b"palette":
                    if t != LIST:
                        raise Bail
                    pal, pos, tags = _palette(b, pos, tags, limit)
                elif k == b"data":
                    if t != LONGS:
                        raise Bail
                    data, pos = _longs(b, pos)
                else:
                    pos, tags = _skip(b, pos, t, tags, limit, 3)
        elif key == b"biomes":
            if t != COMPOUND:
                raise Bail
            bio, pos, tags = _biomes(b, pos, tags, limit)
        elif key == b"Y":
            if t != BYTE:
                raise Bail
            y = b[pos] - 256 if b[pos] > 127 else b[pos]
            pos += 1
        else:
            pos, tags = _skip(b, pos, t, tags, limit, 2)
    if y is None or (have and pal is None):
        raise Bail
    if not have:
        return None, pos, tags
    k = len(pal.names)
    if data is None:
        if k > 1:
            raise Bail
    else:
        bits = max(4, (k - 1).bit_length())
        if len(data) != -(-4096 // (64 // bits)):
            raise Bail
    return [y, pal, data, bio], pos, tags
