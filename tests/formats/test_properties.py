"""Property tests (Hypothesis, derandomized so CI sees the same cases): real-shaped
region files, chunk NBT, .vox files and a world file's chunk blobs, mutated (bytes
set, bits flipped, runs cut or inserted, 32-bit lengths overwritten with huge or
negative ones), give one clear error of the module's kinds (which the CLI turns into
one line) or a valid result, within a bounded memory (tracemalloc per example)."""
from __future__ import annotations

import sqlite3
import struct

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from voxel_addon.core.blocks import REGISTRY
from voxel_addon.core.errors import VoxelError
from voxel_addon.formats import anvil, budget, nbt, vox
from voxel_addon.formats.region import Region, RegionError
from voxel_addon.storage import CorruptChunk, WorldFile, codecs
from voxel_addon.world import World

from . import mcfiles as mc
from . import voxfiles as vf
from ..memory import peak_of

MIB = 1 << 20
SETTINGS = settings(max_examples=120, deadline=None, derandomize=True, database=None,
                    suppress_health_check=list(HealthCheck))
CHUNK_ERRORS = (RegionError, anvil.ChunkError, nbt.NbtError, budget.Exceeded)

edit = st.tuples(st.sampled_from(["set", "flip", "cut", "insert", "length"]),
                 st.integers(0, 1 << 30), st.integers(0, 255),
                 st.sampled_from([0x7FFFFFFF, 0x80000000, 0xFFFFFFFF, 1 << 24, 4096, 0]))
edits = st.lists(edit, min_size=1, max_size=6)


def mutate(data: bytes, ops, start: int = 0) -> bytes:
    b = bytearray(data)
    for op, where, byte, length in ops:
        if len(b) <= start:
            break
        i = start + where % (len(b) - start)
        if op == "set":
            b[i] = byte
        elif op == "flip":
            b[i] ^= 1 << (byte & 7)
        elif op == "cut":
            del b[i:i + 1 + byte * 16]
        elif op == "insert":
            b[i:i] = bytes([byte]) * (1 + byte % 9)
        else:  # a 32-bit length, big-endian (NBT, region) or little-endian (.vox)
            b[i:i + 4] = struct.pack(">I" if byte & 1 else "<I", length)
    return bytes(b)


def bounded(fn, limit=64 * MIB):
    peak = peak_of(fn)
    assert peak < limit, peak


def chunk(rng, cx, version=3953):
    names = np.array(["minecraft:stone", "minecraft:air", "minecraft:oak_stairs",
                      "minecraft:blue_wool", "minecraft:glass"], object)
    ys = (0, 1) if version < 2844 else (-1, 0)
    return mc.chunk_nbt(cx, 0, {y: names[rng.integers(0, 5, (16, 16, 16))] for y in ys},
                        version)


def _bases():
    rng = np.random.default_rng(0)
    nbts = [chunk(rng, 0), chunk(rng, 1, 2586), chunk(rng, 2, 2230)]
    regions = [mc.region({(0, 0): nbts[0], (1, 0): nbts[1]}, k) for k in (1, 2, 3, 4)]
    return nbts, regions


NBTS, REGIONS = _bases()


def check_chunk(payload: bytes, b: budget.Budget) -> None:
    try:
        ch = anvil.read(payload, b)
    except CHUNK_ERRORS:
        return
    for s in ch.sections:
        assert isinstance(s.y, int) and all(isinstance(n, str) for n in s.palette)
        assert s.indices is None or (s.indices.shape == (4096,)
                                     and int(s.indices.max()) < len(s.palette))


@SETTINGS
@given(base=st.sampled_from(range(len(REGIONS))), ops=edits, header=st.booleans())
def test_mutated_regions(base, ops, header):
    data = mutate(REGIONS[base], ops, 0 if header else 8192)

    def go():
        b = budget.Budget.of_input(len(data))
        try:
            reg = Region("r.0.0.mca", data)
        except RegionError:
            return
        for cx, cz in reg.chunks():
            try:
                payload = reg.payload(cx, cz, b)
            except CHUNK_ERRORS:
                continue
            check_chunk(payload, b)
    bounded(go)


@SETTINGS
@given(base=st.sampled_from(range(len(NBTS))), ops=edits, keep=st.booleans())
def test_mutated_nbt(base, ops, keep):
    data = mutate(NBTS[base], ops)

    def go():
        if keep:
            check_chunk(data, budget.Budget(1 << 30, 1 << 30))
            return
        try:
            root = nbt.parse(data)
        except nbt.NbtError:
            return
        assert isinstance(root, dict)
    bounded(go)


def _vox_base():
    rng = np.random.default_rng(3)
    a = [(x, y, z, int(rng.integers(1, 256))) for x, y, z in
         {tuple(int(v) for v in rng.integers(0, 8, 3)) for _ in range(60)}]
    body = (vf.model((8, 8, 8), a) + vf.model((3, 2, 5), [(0, 0, 0, 4), (2, 1, 4, 7)])
            + vf.trn(0, 1) + vf.grp(1, [2, 4]) + vf.trn(2, 3, (4, 5, 6), 17) + vf.shp(3, 0)
            + vf.trn(4, 5, (-3, 0, 2), 52) + vf.shp(5, 1)
            + vf.rgba(rng.integers(0, 256, (255, 3))))
    return [vf.file(body), vf.file(vf.model((8, 8, 8), a))]


VOX = _vox_base()


@SETTINGS
@given(base=st.sampled_from([0, 1]), ops=edits)
def test_mutated_vox(base, ops):
    data = mutate(VOX[base], ops, 8)

    def go():
        try:
            scene = vox.read(data)
            xyz, col, size = vox.voxels(scene)
        except vox.VoxError:
            return
        assert len(xyz) == len(col) <= vox.MAX_PLACED
        assert (xyz >= 0).all() and (xyz < size).all() and (col > 0).all()
    bounded(go)


@pytest.fixture(scope="module")
def chunk_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("blobs") / "w.sqlite"
    with World.create(path, seed=3, generator="flat", loader=False) as w:
        w.set_block(3, 4, 70, "glass")   # a data-free edit; the chunk is generated
        w.chunk_at(0, 0)
        w.flush()
    db = sqlite3.connect(path)
    row = db.execute("SELECT codec, blocks FROM chunks WHERE cx=0 AND cy=0").fetchone()
    raw = codecs.decode(row[0], row[1], 2 * 16 * 16 * 256)
    db.close()
    wf = WorldFile(path)
    yield path, wf, {c: codecs.encode(c, raw) for c in codecs.CODECS}
    wf.close()


@settings(max_examples=80, deadline=None, derandomize=True, database=None,
          suppress_health_check=list(HealthCheck))
@given(codec=st.sampled_from(codecs.CODECS), ops=edits, column=st.sampled_from(["blocks",
                                                                                 "data"]),
       name=st.sampled_from(["", "zstd", "zlib", "lz4", "gzip"]))
def test_mutated_chunk_blobs(chunk_file, codec, ops, column, name):
    path, wf, blobs = chunk_file
    blob = mutate(blobs[codec], ops)
    db = sqlite3.connect(path)
    db.execute(f"UPDATE chunks SET codec=?, blocks=?, data=? WHERE cx=0 AND cy=0",
               (name or codec, blob if column == "blocks" else blobs[codec],
                blob if column == "data" else None))
    db.commit()
    db.close()

    def go():
        try:
            got = wf.read_chunk((0, 0))
        except CorruptChunk as e:
            assert "\n" not in str(e)
            return
        except VoxelError as e:   # a codec this install cannot read
            assert "\n" not in str(e)
            return
        blocks, data = got
        assert blocks.shape == (16, 16, 256) and int(blocks.max()) < len(REGISTRY)
        assert data is None or data.shape == (16, 16, 256)
    bounded(go)
