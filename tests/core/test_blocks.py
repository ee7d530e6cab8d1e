"""The block registry's tables agree with the Block objects and the issue's rules."""
from voxel_addon.core.blocks import FACES, REGISTRY, RENDERS, SHAPES


def test_tables_follow_blocks():
    for i, b in enumerate(REGISTRY.blocks):
        assert REGISTRY.id(b.name) == i
        assert SHAPES[REGISTRY.shape[i]] == b.shape and RENDERS[REGISTRY.render[i]] == b.render
        assert bool(REGISTRY.light_opaque[i]) == b.light_opaque
        assert tuple(REGISTRY.emission[i]) == b.emission
        for k, f in enumerate(FACES):
            if b.shape != "none":
                assert REGISTRY.texture_names[REGISTRY.face_texture[i, k]] == b.texture(f)


def test_light_properties_make_sense():
    air = REGISTRY["air"]
    assert air.shape == "none" and not air.light_opaque and air.attenuation == 0
    assert REGISTRY["glass"].attenuation == 0 and not REGISTRY["glass"].light_opaque
    assert REGISTRY["water"].attenuation > 0 and REGISTRY["leaves"].attenuation > 0
    lamps = [b for b in REGISTRY.blocks if b.name.startswith("lamp_")]
    assert len(lamps) >= 3 and all(b.light_opaque and max(b.emission) == 15 for b in lamps)
    assert REGISTRY["glowing_mushroom"].emission[2] > REGISTRY["glowing_mushroom"].emission[0]
    assert 0 < max(REGISTRY["ore"].emission) < 8   # faint
    assert REGISTRY["log"].texture("+z") != REGISTRY["log"].texture("+x")
    assert {REGISTRY[n].shape for n in ("flowers", "tall_grass", "mushroom", "glowing_mushroom")} == {"x"}
    assert REGISTRY["wheat"].shape == REGISTRY["cactus"].shape == "hash"
    assert REGISTRY["cactus"].inset < REGISTRY["wheat"].inset   # cactus walls nearer the edges
    assert not REGISTRY["flowers"].collision and REGISTRY["cactus"].collision
