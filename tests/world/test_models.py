"""Minecraft model quads in the world's payloads (issue 30 d, live view): with the
world's resource stack a batch's chunks carry their model quads and the greedy mesh
leaves those voxels out; an edit meshes them again; the renderer draws them from
payloads."""
from __future__ import annotations

import shutil

import numpy as np
import pytest

from voxel_addon.core.blocks import REGISTRY

from ..mcres.builds import imported

POPPY = (9, -10, 65)     # the build's poppy (Minecraft 9, 1, 9) in voxels
KEY = (0, -1)


@pytest.fixture(scope="module")
def worlds(tmp_path_factory):
    return imported(tmp_path_factory.mktemp("mcworld"))[0]


def payload(path):
    from voxel_addon.world import World, build
    with World.open(path, readonly=True, loader=False) as w:
        return {p.key: p for p in build.light_and_mesh(w, -1, -2, 2, 1)}[KEY]


def flowers(mesh):
    q = mesh.quads
    return int((q["block"] == REGISTRY.id("flowers")).sum())


def inside(centres, voxel):
    """Quads whose centre is inside the voxel (not on its sides)."""
    return np.all(np.abs(centres - (np.asarray(voxel) + 0.5)) < 0.49, axis=1)


def test_payloads_carry_model_quads(worlds):
    p, q = payload(worlds["with"]), payload(worlds["without"])
    assert q.mesh.models is None and flowers(q.mesh) > 0
    m = p.mesh.models
    assert m is not None and flowers(p.mesh) == 0          # the greedy path leaves it out
    pos = m.mesh.positions.reshape(-1, 4, 3).mean(1)
    poppy = inside(pos, POPPY)
    assert poppy.any()
    assert {m.mesh.sprites[i] for i in m.mesh.sprite[poppy].tolist()} == {"minecraft:block/poppy"}
    assert set(m.images) == set(m.mesh.sprites)


def test_a_chunk_meshes_all_its_columns(worlds):
    """The build's stone floor spans its chunk: each of the chunk's 16×16 columns has
    model quads, in a batch around it and in a batch of it alone (where its edge
    columns are the batch's; the ring around a batch only hides faces)."""
    from voxel_addon.world import World, build
    with World.open(worlds["with"], readonly=True, loader=False) as w:
        for batch in ((-1, -2, 2, 1), (0, -1, 1, 0)):
            p = {p.key: p for p in build.light_and_mesh(w, *batch)}[KEY]
            v = (p.mesh.models.mesh.voxel[:, :2] - 1) % 16
            assert len({(int(a), int(b)) for a, b in v}) == 256


def test_an_edit_meshes_the_models_again(worlds, tmp_path):
    from voxel_addon.world import World, build
    from voxel_addon.world.edit import edit
    path = tmp_path / "w.sqlite"
    shutil.copy(worlds["with"], path)
    with World.open(path, loader=False) as w:
        build.light_and_mesh(w, -1, -2, 2, 1)
        edit(w, (*POPPY, 0))
        m = w.chunks[KEY].mesh.models
        pos = m.mesh.positions.reshape(-1, 4, 3).mean(1)
        assert m is not None and not inside(pos, POPPY).any()
        assert "minecraft:block/oak_planks" in m.mesh.sprites      # the stair stays


def test_the_renderer_draws_payload_models(worlds):
    from voxel_addon.render import Camera
    from voxel_addon.render.pipeline import Renderer
    from voxel_addon.render.device import mgl
    ps = {}
    for name in ("with", "without"):
        from voxel_addon.world import World, build
        with World.open(worlds[name], readonly=True, loader=False) as w:
            ps[name] = build.light_and_mesh(w, -1, -2, 2, 1)
    imgs = {}
    ctx = mgl.context()
    try:
        for name, got in ps.items():
            r = Renderer(ctx)
            r.update_chunks(got)
            # the stone floor's top (z 64) stands on the area's wall, model or not
            assert r.edges[KEY][:4].max() == 65 and (r.edges[KEY][:4] == 65).mean() > 0.9
            imgs[name] = r.render(Camera(14, -18, 69, 120, -30), 12.0, (320, 200)).astype(int)
            if name == "with":    # culled per chunk: none drawn looking away from the build
                from voxel_addon.render.models import NAMES
                cam = Camera(14, -18, 69, 120, -30).fitted(1.6, 70.0, 300.0)
                assert r.models.batches(NAMES, cam.matrices()[0])["m_opaque"]
                away = Camera(14, 30, 69, 0, 0).fitted(1.6, 70.0, 300.0)
                assert not any(r.models.batches(NAMES, away.matrices()[0]).values())
            r.release()
    finally:
        ctx.release()
    red = {k: ((a[..., 0] > 60) & (a[..., 0] > 3 * a[..., 1]) & (a[..., 0] > 3 * a[..., 2])).sum()
           for k, a in imgs.items()}
    assert red["with"] > 20 and red["without"] < red["with"] / 4


def test_model_blocks_that_are_no_cube_pass_light(worlds):
    """A rail and a door's halves are planks cubes in today's look; with the stack they
    pass light as in the game: their voxels are lit like open air beside them (the
    floor under a rail is not dark), without the stack they hold nothing."""
    from voxel_addon.world import World, build
    from ..mcres import builds
    got = {}
    for name in ("with", "without"):
        with World.open(worlds[name], readonly=True, loader=False) as w:
            build.light_and_mesh(w, -1, -2, 2, 1)
            light = w.chunks[KEY].light
            got[name] = {k: int(light[x, 15 - z, y + 64]) >> 12      # daylight
                         for k, (x, z, y) in {"rail": (13, 9, 1), "door": (8, 3, 1),
                                              "air": (12, 9, 1)}.items()}
    assert got["with"]["rail"] == got["with"]["air"] == got["with"]["door"] == 15
    assert got["without"]["rail"] == 0 and got["without"]["air"] == got["with"]["air"]
