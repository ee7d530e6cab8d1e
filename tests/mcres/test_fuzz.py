"""Hostile packs: blockstates and models whose fields hold anything JSON can hold
give shapes or one-line errors (VoxelError), never another exception."""
from __future__ import annotations

import json

import numpy as np

from voxel_addon.core.errors import VoxelError
from voxel_addon.mcres import Resources, Stack

from . import packfiles as pf

ATOMS = [None, True, 0, -3, 7.5, 1e300, "", "x", "#all", "block/stone", "minecraft:block/cube",
         [], {}, [0, 0, 0], [16, 16, 16], [0, 0, 16, 16], {"model": "block/stone"}]


def value(rng, depth=0):
    k = rng.integers(0, 4 if depth < 3 else 1)
    if k == 0:
        return ATOMS[rng.integers(len(ATOMS))]
    if k == 1:
        return [value(rng, depth + 1) for _ in range(rng.integers(0, 4))]
    keys = ["model", "x", "y", "uvlock", "weight", "when", "apply", "OR", "AND", "facing",
            "parent", "textures", "elements", "from", "to", "faces", "up", "north", "uv",
            "texture", "rotation", "cullface", "tintindex", "axis", "angle", "origin",
            "rescale", "shade", "ambientocclusion", "variants", "multipart", ""]
    return {keys[rng.integers(len(keys))]: value(rng, depth + 1) for _ in range(rng.integers(0, 5))}


def mutate(rng, obj):
    """OBJ with one field somewhere replaced by a random value."""
    if isinstance(obj, dict) and obj and rng.random() < 0.7:
        k = list(obj)[rng.integers(len(obj))]
        return {**obj, k: mutate(rng, obj[k]) if rng.random() < 0.6 else value(rng)}
    if isinstance(obj, list) and obj and rng.random() < 0.7:
        i = rng.integers(len(obj))
        return obj[:i] + [mutate(rng, obj[i]) if rng.random() < 0.6 else value(rng)] + obj[i + 1:]
    return value(rng)


def test_mutated_packs_fail_in_one_line(tmp_path):
    base = pf.files()
    names = [k for k in base if k.endswith(".json") and any(
        w in k for w in ("stairs", "fence", "cross", "poppy", "torch", "cube", "block.json",
                         "stone.json", "grass_block", "slab", "pane", "door", "rail"))]   # what the shapes below read
    rng = np.random.default_rng(30)
    odd = []
    jar = pf.write(tmp_path / "client.jar", jar=True)
    for n in range(150):
        # the three mutated files in a pack over the whole one
        content = {"pack.mcmeta": base["pack.mcmeta"]}
        for k in rng.choice(names, 3, replace=False):
            content[k] = json.dumps(mutate(rng, json.loads(base[k]))).encode()
        d = tmp_path / f"p{n}"
        d.mkdir()
        r = Resources(Stack.open([jar, pf.write(d, content)]))
        for block, props in [("oak_stairs", {"facing": "east", "half": "top", "shape": "straight"}),
                             ("oak_fence", {"north": "true", "east": "false"}), ("poppy", {}),
                             ("grass_block", {"snowy": "false"}), ("stone", {}),
                             ("wall_torch", {"facing": "east"}), ("oak_slab", {"type": "top"}),
                             ("glass_pane", {"north": "true", "east": "false", "west": "true"}),
                             ("oak_door", {"facing": "west", "half": "upper", "hinge": "right",
                                           "open": "true"}),
                             ("rail", {"shape": "ascending_east"}), ("torch", {})]:
            try:
                sh = r.shape(block, props, (n, 64, -n))
                if sh is not None:
                    for q in sh.quads:
                        assert q.pos.shape == (4, 3) and np.isfinite(q.pos).all()
            except VoxelError as e:
                assert "\n" not in str(e)
            except Exception as e:  # noqa: BLE001  (what the test is looking for)
                odd.append(f"{block}: {type(e).__name__}: {e}")
    assert not odd, odd[:5]
