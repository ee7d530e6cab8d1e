"""The batched `mcres.mesh.build` equals the first per-quad one (tests/mcres/mesh_ref)
quad for quad, in the same order, on random volumes of every state the test pack
names (variant keys, multipart `when` combinations, weighted stone), unknown blocks,
code-drawn chests, the project's opaque voxels, biomes and a box origin."""
from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from voxel_addon.mcres import Resources, Stack
from voxel_addon.mcres.mesh import build
from voxel_addon.mcres.states import parse_props, state_key

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
    for path, data in sorted(pf.files().items()):
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


@pytest.fixture(scope="module")
def res(tmp_path_factory):
    r = Resources(Stack.open([pf.write(tmp_path_factory.mktemp("p") / "c.jar", jar=True)]))
    yield r
    r.close()


def same(a, b):
    assert a.quads == b.quads
    for k in ("positions", "uvs", "normals", "sprite", "tint", "layer", "shade", "voxel", "drawn"):
        x, y = getattr(a, k), getattr(b, k)
        assert x.dtype == y.dtype and x.shape == y.shape, k
        assert np.array_equal(x, y), k
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
    # no biomes, nothing drawn
    same(build(res, palette, st, opaque), mesh_ref.build(res, palette, st, opaque))
    z = np.zeros(shape, np.int32)
    same(build(res, palette, z, opaque), mesh_ref.build(res, palette, z, opaque))
