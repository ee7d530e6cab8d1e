"""formats/nbt.py remembers short lists of strings / compounds of strings (chunk
palettes) and replays them: a replay must give what a fresh parse gives (values, tags
charged, budget refusals) and never hand out the remembered objects."""
import struct

import pytest

from voxel_addon.formats import anvil, nbt


def _s(v: str) -> bytes:
    b = v.encode()
    return struct.pack(">H", len(b)) + b


def _entry(name, props=None) -> bytes:
    out = b"\x08" + _s("Name") + _s(name)
    if props:
        out += b"\x0a" + _s("Properties") + b"".join(
            b"\x08" + _s(k) + _s(v) for k, v in props.items()) + b"\x00"
    return out + b"\x00"


def _doc(entries, biomes) -> bytes:
    pal = b"\x09" + _s("palette") + b"\x0a" + struct.pack(">i", len(entries)) + b"".join(
        _entry(*e) for e in entries)
    bio = b"\x0a" + _s("biomes") + b"\x09" + _s("palette") + b"\x08" + struct.pack(
        ">i", len(biomes)) + b"".join(_s(b) for b in biomes) + b"\x00"
    sec = b"\x01" + _s("Y") + b"\x00" + b"\x0a" + _s("block_states") + pal + b"\x00" + bio
    body = b"\x03" + _s("DataVersion") + struct.pack(">i", 3953)
    body += b"\x09" + _s("sections") + b"\x0a" + struct.pack(">i", 1) + sec + b"\x00"
    return b"\x0a" + _s("") + body + b"\x00"


DOCS = [
    _doc([("minecraft:stone",), ("minecraft:water", {"level": "0"})], ["minecraft:plains"]),
    _doc([("minecraft:stone",), ("minecraft:water", {"level": "2"})], ["minecraft:plains"]),
    _doc([("minecraft:stone",), ("minecraft:water", {"level": "0"})],
         ["minecraft:plains", "minecraft:river"]),
    _doc([("minecraft:stone",)], ["minecraft:plains"]),
]


def _fresh(doc, keep, limit=nbt.MAX_TAGS):
    nbt._LISTS.clear()
    return nbt.read(doc, keep, limit)


@pytest.mark.parametrize("keep", [None, anvil.KEEP])
def test_replay_equals_fresh_parse(keep):
    want = [_fresh(d, keep) for d in DOCS]
    nbt._LISTS.clear()
    for _ in range(3):   # the second and third rounds replay remembered lists
        for d, w in zip(DOCS, want):
            assert nbt.read(d, keep) == w
    assert nbt._LISTS   # the palettes were remembered (else this tests nothing)


def test_replays_are_fresh_objects():
    want = _fresh(DOCS[0], None)[0]
    nbt._LISTS.clear()
    for _ in range(3):   # the first parse remembered, the others replays
        got = nbt.parse(DOCS[0])
        assert got == want
        pal = got["sections"][0]["block_states"]["palette"]
        pal[1]["Properties"]["level"] = "9"
        pal.append({"Name": "x"})
        got["sections"][0]["biomes"]["palette"][0] = "minecraft:void"


def test_budget_same_on_replay():
    tags = _fresh(DOCS[0], anvil.KEEP)[1]
    with pytest.raises(nbt.TooMany):
        _fresh(DOCS[0], anvil.KEEP, tags - 1)
    nbt.read(DOCS[0], anvil.KEEP)          # remembered
    with pytest.raises(nbt.TooMany):
        nbt.read(DOCS[0], anvil.KEEP, tags - 1)
    assert nbt.read(DOCS[0], anvil.KEEP, tags)[1] == tags


def test_memory_stays_bounded():
    """A flood of distinct lists (a hostile file) keeps at most _HELD_MAX bytes."""
    nbt._LISTS.clear()
    nbt._HELD[0] = 0
    for i in range(600):   # 600 lists of ~2,000 bytes: past the bound
        items = [f"{i:06d}-{j:011d}" for j in range(100)]
        doc = b"\x0a" + _s("") + b"\x09" + _s("l") + b"\x08" + struct.pack(">i", len(items)) \
            + b"".join(_s(x) for x in items) + b"\x00"
        assert nbt.parse(doc)["l"] == items
    held = sum(len(raw) for got in nbt._LISTS.values() for raw, _, _ in got)
    assert 0 < held <= nbt._HELD_MAX
