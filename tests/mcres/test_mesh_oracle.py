"""The batched `mcres.mesh.build` equals the first per-quad one (tests/mcres/mesh_ref)
quad for quad, in the same order, on random volumes of every state the test pack
names (variant keys, multipart `when` combinations, weighted stone and multipart parts),
unknown blocks,
code-drawn chests, the project's opaque voxels, biomes and a box origin."""
from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from voxel_addon.mcres import Resources, Stack
from voxel_addon.mcres.mesh import build
from voxel_addon.mcres.states import (BlockState, JavaRandom, draws, parse_props, pick,
                                      state_key)

from . import mesh_ref
from . import packfiles as pf


def _when_props(when, out: dict):
    if isinstance(when, dict):
        for k, v in when.items():
            if k in ("OR", "AND"):
                for w in v:
                    _when_props(w, out)
            else:
                for t in str(v).lower().split("|"):
                    out.setdefault(k, set()).add(t.lstrip("!"))


def pack_states() -> list[str]:
    """Every state the test pack's blockstates name."""
    keys = []
    for path, data in sorted(files().items()):
        if "/blockstates/" not in path:
            continue
        name = "minecraft:" + path.rpartition("/")[2][:-5]
        j = json.loads(data)
        if "variants" in j:
            keys += [state_key(name, parse_props(k)) for k in j["variants"]]
        else:
            props: dict = {}
            for part in j["multipart"]:
                _when_props(part.get("when"), props)
            ks = sorted(props)
            for vals in itertools.product(*(sorted(props[k] | {"false"}) for k in ks)):
                keys.append(state_key(name, dict(zip(ks, vals))))
    return sorted(set(keys))


# weighted parts of a multipart (drawn voxel by voxel) beside the test pack's own
MOSSY = {"multipart": [
    {"apply": [{"model": "block/stone", "weight": 2}, {"model": "block/stone_mirrored"}]},
    {"when": {"lit": "true"}, "apply": [{"model": "block/poppy"},
                                         {"model": "block/poppy", "y": 90, "weight": 5}]}]}


def files() -> dict:
    return {**pf.files(), pf.MC + "blockstates/mossy.json": json.dumps(MOSSY).encode()}


@pytest.fixture(scope="module")
def res(tmp_path_factory):
    r = Resources(Stack.open([pf.write(tmp_path_factory.mktemp("p") / "c.jar", files(),
                                       jar=True)]))
    yield r
    r.close()


def same(a, b, renumbered=False):
    """A equals B; RENUMBERED: B is a subset, its sprites compared by texture id."""
    assert a.quads == b.quads
    for k in ("positions", "uvs", "normals", "tint", "layer", "shade", "voxel", "drawn",
              *(() if renumbered else ("sprite",))):
        x, y = getattr(a, k), getattr(b, k)
        assert x.dtype == y.dtype and x.shape == y.shape, k
        assert np.array_equal(x, y), k
    if renumbered:
        assert [a.sprites[i] if i >= 0 else None for i in a.sprite.tolist()] \
            == [b.sprites[i] if i >= 0 else None for i in b.sprite.tolist()]
    else:
        assert a.sprites == b.sprites


@pytest.mark.parametrize("seed", range(4))
def test_batched_build_equals_the_per_quad_one(res, seed):
    rng = np.random.default_rng(seed)
    palette = ["", *pack_states(), "minecraft:mystery_block"]
    assert len(palette) > 40          # the multipart fence's combinations are in
    shape = (9, 8, 7)
    # half the states at random, a third stone (whole weighted cubes that hide
    # faces), some air
    st = rng.integers(1, len(palette), shape)
    stone = palette.index("minecraft:stone")
    st[rng.random(shape) < 0.35] = stone
    st[rng.random(shape) < 0.2] = 0
    opaque = (st == 0) & (rng.random(shape) < 0.3)
    opaque |= st == len(palette) - 1
    biomes = rng.integers(0, 3, shape[:2])
    names = ["minecraft:plains", "minecraft:desert", "minecraft:swamp"]
    kw = dict(origin=(16 * seed - 5, -3, 40), y_min=-64, biomes=biomes, biome_names=names)
    want = mesh_ref.build(res, palette, st, opaque, **kw)
    assert want.quads > 500 and len(want.sprites) > 5 and (want.tint != 255).any()
    same(build(res, palette, st, opaque, **kw), want)
    # only some columns: the same quads as all of them, there
    inside = (want.voxel[:, 0] >= 2) & (want.voxel[:, 0] < 7) & (want.voxel[:, 1] >= 1) \
        & (want.voxel[:, 1] < 6)
    same(build(res, palette, st, opaque, cols=(2, 1, 7, 6), **kw), want.subset(inside),
         renumbered=True)
    # no biomes, nothing drawn
    same(build(res, palette, st, opaque), mesh_ref.build(res, palette, st, opaque))
    z = np.zeros(shape, np.int32)
    same(build(res, palette, z, opaque), mesh_ref.build(res, palette, z, opaque))


def test_weighted_variants_drawn_at_once_as_one_by_one():
    """BlockState.picks (NumPy) draws what `choose` draws, near and far from 0."""
    bs = BlockState("t", {"variants": {"": [
        {"model": "a", "weight": 3}, {"model": "b"}, {"model": "c", "y": 90},
        {"model": "d", "weight": 7}], "a=1": {"model": "x"}}})
    rng = np.random.default_rng(7)
    pos = np.concatenate([rng.integers(-30_000_000, 30_000_000, (3000, 3)),
                          rng.integers(-300, 300, (3000, 3))])
    got = bs.picks({}, pos)
    opts = bs.variants[0][1]
    want = [opts.index(bs.choose({}, tuple(p))[0]) for p in pos.tolist()]
    assert np.array_equal(got, want) and len(set(want)) == 4
    assert not bs.picks({"a": 1}, pos).any()      # one option: no draw


def test_the_draw_where_java_keeps_abs_negative():
    """A seed whose nextLong has MIN_VALUE as its low int: |MIN_VALUE| stays negative
    in Java, so `pick` takes the first option; `draws` must too (and agree elsewhere)."""
    a, c, m = 0x5DEECE66D, 0xB, (1 << 48) - 1
    s2 = 0x80000000 << 16                         # the second next(32): MIN_VALUE
    s0 = (s2 - (a + 1) * c) * pow(a * a, -1, 1 << 48) & m
    seeds = [s0 ^ 0x5DEECE66D, 12345, -987654321, (1 << 62) + 7]
    seeds = [x - (1 << 64) if x >= 1 << 63 else x for x in seeds]
    opts = [{"weight": 2}, {"weight": 1}, {"weight": 4}]   # 2**31 % 7: the second
    want = [opts.index(pick(opts, JavaRandom(x))) for x in seeds]
    assert JavaRandom(seeds[0]).next_long() & 0xFFFFFFFF == 0x80000000
    assert draws(np.array(seeds, np.int64), [2, 1, 4]).tolist() == want
