"""MagicaVoxel: files the tests write (voxfiles.py) read voxel for voxel, scene graphs
placed as MagicaVoxel places them (checked by transforming each voxel's corners), and
import -> export round trips voxel for voxel and colour for colour."""
from __future__ import annotations

import itertools

import numpy as np
import pytest

from voxel_addon.cli import main
from voxel_addon.core import colors
from voxel_addon.core.blocks import REGISTRY
from voxel_addon.core.errors import VoxelError
from voxel_addon.formats import magica, vox
from voxel_addon.world import World

from . import voxfiles as vf

COLOR = REGISTRY.id("color")


def random_model(rng, size, n):
    pos = {tuple(int(v) for v in (rng.integers(0, s) for s in size)) for _ in range(n)}
    return [(x, y, z, int(rng.integers(1, 256))) for x, y, z in sorted(pos)]


def world_voxels(path, box):
    """{(x, y, z): rgb} of the color voxels of a world inside box."""
    x0, y0, z0, x1, y1, z1 = box
    out = {}
    with World.open(path, loader=False, readonly=True) as w:
        pal = colors.parse(w.file.meta)
        for cx in range(x0 >> 4, ((x1 - 1) >> 4) + 1):
            for cy in range(y0 >> 4, ((y1 - 1) >> 4) + 1):
                c = w.chunk_at(cx, cy)
                for lx, ly, z in zip(*np.nonzero(c.blocks == COLOR)):
                    out[(16 * cx + int(lx), 16 * cy + int(ly), int(z))] = \
                        tuple(pal[c.data[lx, ly, z]].tolist())
    return out


def test_single_model_at(tmp_path):
    rng = np.random.default_rng(1)
    pal = rng.integers(0, 256, (255, 3))
    vs = random_model(rng, (20, 7, 9), 300)
    f = tmp_path / "m.vox"
    f.write_bytes(vf.file(vf.model((20, 7, 9), vs) + vf.rgba(pal)))
    w = tmp_path / "w.sqlite"
    assert main(["import", "--world", str(w), "--from", str(f), "--at", "-5", "30", "40"]) == 0
    got = world_voxels(w, (-5, 30, 40, 15, 37, 49))
    want = {(x - 5, y + 30, z + 40): tuple(int(v) for v in pal[i - 1]) for x, y, z, i in vs}
    assert got == want


def corner_oracle(size, voxels, transforms):
    """Each voxel's cell (its 8 corners, pivot floor(size/2) subtracted) through the
    transforms (innermost first, each (R, t) with world = R p + t) -> its cell min."""
    out = {}
    piv = np.array(size) // 2
    for x, y, z, c in voxels:
        corners = np.array(list(itertools.product((x, x + 1), (y, y + 1), (z, z + 1))), float)
        p = corners - piv
        for r, t in transforms:
            p = p @ np.array(r, float).T + np.array(t, float)
        out[tuple(int(v) for v in p.min(0))] = c
    return out


@pytest.mark.parametrize("bits", [4, 52, 17, 6 | (1 << 4), 24 | (1 << 6), 9 | (1 << 5) | (1 << 6)])
def test_scene_graph_rotation_and_mirroring(bits):
    rng = np.random.default_rng(bits)
    size_a, size_b = (5, 4, 3), (2, 6, 7)
    a, b = random_model(rng, size_a, 25), random_model(rng, size_b, 25)
    ra, rb = vox.rotation(bits), vox.rotation(4)
    body = (vf.model(size_a, a) + vf.model(size_b, b)
            + vf.trn(0, 1) + vf.grp(1, [2, 4, 6])
            + vf.trn(2, 3, (10, -3, 4), bits) + vf.shp(3, 0)
            + vf.trn(4, 5, (-7, 2, 0)) + vf.shp(5, 1)
            + vf.trn(6, 7, (100, 0, 0), attrs={"_hidden": "1"}) + vf.shp(7, 1))
    scene = vox.read(vf.file(body))
    xyz, col, size = vox.voxels(scene)
    want = corner_oracle(size_a, a, [(ra, (10, -3, 4))])
    want.update(corner_oracle(size_b, b, [(rb, (-7, 2, 0))]))
    lo = np.min([list(k) for k in want], 0)
    got = {tuple((p + lo).tolist()): c for p, c in zip(xyz, col.tolist())}
    # the bounding box of the models (not only of their voxels) is the corner
    assert (xyz.min(0) >= 0).all()
    shift = np.array(list(got)).min(0) - np.array(list(want)).min(0)
    assert {tuple((np.array(k) + shift).tolist()): v for k, v in want.items()} == got


def test_nested_transforms_compose():
    body = (vf.model((1, 1, 1), [(0, 0, 0, 9)]) + vf.model((1, 1, 1), [(0, 0, 0, 10)])
            + vf.trn(0, 1) + vf.grp(1, [2, 6])
            + vf.trn(2, 3, (5, 0, 0), 1 | (0 << 2) | 0)       # rows: x<-y, y<-x (a mirror)
            + vf.grp(3, [4]) + vf.trn(4, 5, (0, 3, 0)) + vf.shp(5, 0)
            + vf.trn(6, 7, (0, 0, 0)) + vf.shp(7, 1))
    bits = 1 | (0 << 2)
    scene = vox.read(vf.file(body))
    xyz, col, _ = vox.voxels(scene)
    r = vox.rotation(bits)
    want = corner_oracle((1, 1, 1), [(0, 0, 0, 9)], [(np.eye(3), (0, 3, 0)), (r, (5, 0, 0))])
    want.update(corner_oracle((1, 1, 1), [(0, 0, 0, 10)], [(np.eye(3), (0, 0, 0))]))
    lo = np.min([list(k) for k in want], 0)
    assert {tuple((p + lo).tolist()): c for p, c in zip(xyz, col.tolist())} == want


def test_default_palette_and_errors(tmp_path):
    scene = vox.read(vf.file(vf.model((2, 2, 2), [(0, 0, 0, 1), (1, 1, 1, 255)])))
    assert scene.palette[1, :3].tolist() == [255, 255, 255]
    assert scene.palette[255, :3].tolist() == [17, 17, 17]
    for bad in (b"", b"VOX \x96\0\0\0", vf.file(vf.model((300, 1, 1), [])),
                vf.file(vf.model((2, 2, 2), [(2, 0, 0, 1)])),
                vf.file(vf.trn(0, 1) + vf.model((1, 1, 1), [(0, 0, 0, 1)]))):
        with pytest.raises(vox.VoxError):
            vox.voxels(vox.read(bad))
    f = tmp_path / "bad.vox"
    f.write_bytes(b"VOX nonsense")
    with pytest.raises(VoxelError, match="not a readable .vox"):
        magica.read_file(f)


def test_round_trip_import_export(tmp_path):
    rng = np.random.default_rng(4)
    pal = rng.integers(0, 256, (255, 3))
    size = (40, 33, 20)
    vs = random_model(rng, size, 2000)
    src = tmp_path / "in.vox"
    src.write_bytes(vf.file(vf.model(size, vs) + vf.rgba(pal)))
    w = tmp_path / "w.sqlite"
    at = (7, -20, 30)
    assert main(["import", "--world", str(w), "--from", str(src), "--at", *map(str, at)]) == 0
    out = tmp_path / "out.vox"
    box = [at[0], at[1], at[2], at[0] + size[0], at[1] + size[1], at[2] + size[2]]
    assert main(["export", "--world", str(w), "--box", *map(str, box), "--out", str(out)]) == 0
    scene = vox.read(out.read_bytes())
    xyz, col, got_size = vox.voxels(scene)
    assert tuple(got_size) == size
    got = {tuple(p.tolist()): tuple(scene.palette[c, :3].tolist()) for p, c in zip(xyz, col)}
    want = {(x, y, z): tuple(int(v) for v in pal[i - 1]) for x, y, z, i in vs}
    assert got == want
    # and back in again: the same voxels and colours in the world
    w2 = tmp_path / "w2.sqlite"
    assert main(["import", "--world", str(w2), "--from", str(out), "--at", *map(str, at)]) == 0
    assert world_voxels(w2, box) == world_voxels(w, box)


def test_big_box_splits_into_models_and_quantises(tmp_path):
    w = tmp_path / "w.sqlite"
    rng = np.random.default_rng(9)
    with World.create(w, seed=0, generator="empty", loader=False) as world:
        xyz = np.array([[0, 0, 0], [299, 1, 5], [150, 0, 2], [256, 0, 0]])
        pal = colors.parse(world.file.meta)
        pal, idx = colors.add(pal, rng.integers(0, 256, (400, 3)))
        world.file.set_meta(colors.KEY, colors.dump(pal))
        more = np.stack([np.arange(400) % 300, np.full(400, 3), np.arange(400) // 300 + 10], 1)
        world.set_blocks(np.concatenate([xyz, more]),
                         [REGISTRY.id("bricks"), COLOR, COLOR, REGISTRY.id("glass")] + [COLOR] * 400,
                         np.concatenate([[0, 0, 0, 0], idx]))
        world.flush()
    out = tmp_path / "big.vox"
    assert main(["export", "--world", str(w), "--box", "0", "0", "0", "300", "4", "12",
                 "--out", str(out)]) == 0
    scene = vox.read(out.read_bytes())
    assert len(scene.models) == 2 and all(max(m.size) <= 256 for m in scene.models)
    pos, col, size = vox.voxels(scene)
    assert tuple(size) == (300, 4, 12)
    got = {tuple(p.tolist()) for p in pos}
    assert {(0, 0, 0), (299, 1, 5), (150, 0, 2), (256, 0, 0)} <= got and len(got) == 404
    bricks = magica.block_colors()[REGISTRY.id("bricks")]
    c0 = scene.palette[col[pos.tolist().index([0, 0, 0])]][:3]
    assert np.abs(c0.astype(int) - bricks).max() <= 40   # quantised, near its average
    assert (scene.palette[1:, 3] == 255).all()


def test_export_memory_grows_by_bytes_per_voxel(tmp_path):
    """export works chunk by chunk: the box's arrays at once took ~31 bytes per voxel
    of the box (the 2^28 voxels the box may hold: 7 GB), now ~12 (at the limit the
    command measured 1.7 GB, the same file byte for byte)."""
    from tests.memory import peak_of
    box = (0, 0, 0, 128, 128, 256)
    with World.create(tmp_path / "w.sqlite", seed=1, generator="overworld", loader=False,
                      backend="numpy") as w:
        first = magica.export_vox(w, box, tmp_path / "a.vox")   # the chunks made here
        peak = peak_of(lambda: magica.export_vox(w, box, tmp_path / "b.vox"))
    assert first["voxels"] > 128 * 128 * 40
    assert (tmp_path / "a.vox").read_bytes() == (tmp_path / "b.vox").read_bytes()
    assert peak < 16 * 128 * 128 * 256, peak / (128 * 128 * 256)
