"""Hostile files: thousands of truncated and bit-flipped region and .vox files give
only the decoders' one-line errors (ValueError subclasses, VoxelError through the
import), never another exception, and an import never leaves a half-written chunk
(every chunk row in the file reads back whole)."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon.core.errors import VoxelError
from voxel_addon.formats import anvil, minecraft, nbt, vox
from voxel_addon.formats.region import Region, RegionError
from voxel_addon.world import World

from . import mcfiles as mc
from . import voxfiles as vf

DECODE_ERRORS = (RegionError, anvil.ChunkError, nbt.NbtError)


def mutate(rng, data: bytes, head: int = 0) -> bytes:
    """Truncate, flip bits, or overwrite a run of bytes (at or after `head`)."""
    b = bytearray(data)
    k = rng.integers(0, 3)
    if k == 0:
        return bytes(b[:int(rng.integers(0, len(b)))])
    if k == 1:
        for _ in range(int(rng.integers(1, 9))):
            i = int(rng.integers(head, len(b)))
            b[i] ^= 1 << int(rng.integers(0, 8))
        return bytes(b)
    i = int(rng.integers(head, len(b)))
    n = int(rng.integers(1, 6))
    b[i:i + n] = rng.integers(0, 256, n, dtype=np.uint8).tobytes()
    return bytes(b)


def small_chunk(rng, cx, cz, version):
    secs = {}
    for y in ((0, 1) if version < 2844 else (-1, 0)):
        a = np.array(["minecraft:stone", "minecraft:air", "minecraft:oak_planks",
                      "minecraft:blue_wool", "minecraft:glass"], object)[
            rng.integers(0, 5, (16, 16, 16))]
        secs[y] = a
    return mc.chunk_nbt(cx, cz, secs, version, "minecraft:full")


@pytest.fixture(scope="module")
def regions():
    rng = np.random.default_rng(0)
    out = []
    for kind, version in ((3, 3953), (3, 2586), (3, 2230), (2, 3953), (4, 3953), (1, 3953)):
        chunks = {(0, 0): small_chunk(rng, 0, 0, version), (1, 0): small_chunk(rng, 1, 0, version)}
        out.append((kind, mc.region(chunks, kind)))
    return out


def decode_all(data: bytes):
    try:
        reg = Region("r.0.0.mca", data)
    except RegionError:
        return
    for cx, cz in reg.chunks():
        try:
            ch = anvil.read(reg.payload(cx, cz))
        except DECODE_ERRORS:
            continue
        for s in ch.sections:
            assert s.indices is None or (s.indices.shape == (4096,)
                                         and int(s.indices.max()) < len(s.palette))


def test_region_decoders_fuzz(regions):
    rng = np.random.default_rng(1)
    n = 0
    for i in range(3000):
        kind, data = regions[i % len(regions)]
        # most flips land in the payloads (NBT of uncompressed regions), some in the header
        decode_all(mutate(rng, data, head=0 if i % 5 == 0 else 8192))
        n += 1
    assert n == 3000


def test_import_fuzz_never_half_writes(tmp_path, regions):
    rng = np.random.default_rng(2)
    for i in range(60):
        kind, data = regions[i % len(regions)]
        folder = tmp_path / f"f{i}"
        folder.mkdir()
        (folder / "r.0.0.mca").write_bytes(mutate(rng, data, head=0 if i % 4 == 0 else 8192))
        w = tmp_path / f"w{i}.sqlite"
        with World.create(w, seed=0, generator="empty", loader=False) as world:
            try:
                rep = minecraft.import_world(world, folder)
            except VoxelError as e:
                assert "\n" not in str(e)
                continue
            assert rep.chunks <= 2 and rep.chunks + len(rep.damaged) + rep.external \
                + sum(rep.unfinished.values()) <= 1024   # header flips add phantom entries
        with World.open(w, loader=False, readonly=True) as world:
            for k in world.file.chunk_keys():
                blocks, _ = world.file.read_chunk(k)    # raises if a row were damaged
                assert blocks.shape == (16, 16, 256)


@pytest.fixture(scope="module")
def vox_files():
    rng = np.random.default_rng(3)
    a = [(x, y, z, int(rng.integers(1, 256))) for x, y, z in
         {tuple(int(v) for v in rng.integers(0, 8, 3)) for _ in range(60)}]
    body = (vf.model((8, 8, 8), a) + vf.model((3, 2, 5), [(0, 0, 0, 4), (2, 1, 4, 7)])
            + vf.trn(0, 1) + vf.grp(1, [2, 4]) + vf.trn(2, 3, (4, 5, 6), 17) + vf.shp(3, 0)
            + vf.trn(4, 5, (-3, 0, 2), 52) + vf.shp(5, 1)
            + vf.rgba(rng.integers(0, 256, (255, 3))))
    return [vf.file(body), vf.file(vf.model((8, 8, 8), a))]


def test_vox_fuzz(vox_files):
    rng = np.random.default_rng(4)
    for i in range(3000):
        data = mutate(rng, vox_files[i % 2], head=0 if i % 7 == 0 else 8)
        try:
            xyz, col, size = vox.voxels(vox.read(data))
        except vox.VoxError:
            continue
        assert len(xyz) == len(col) and (xyz >= 0).all() and (xyz < size).all()


def test_vox_import_fuzz(tmp_path, vox_files):
    from voxel_addon.formats import magica
    rng = np.random.default_rng(5)
    w = tmp_path / "w.sqlite"
    with World.create(w, seed=0, generator="empty", loader=False) as world:
        for i in range(40):
            f = tmp_path / f"{i}.vox"
            f.write_bytes(mutate(rng, vox_files[i % 2], head=8))
            try:
                magica.import_vox(world, f, (0, 0, 100))
            except VoxelError as e:
                assert "\n" not in str(e)
    with World.open(w, loader=False, readonly=True) as world:
        for k in world.file.chunk_keys():
            world.file.read_chunk(k)
