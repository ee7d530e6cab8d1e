"""CLI renders of a Minecraft import with the world's resource stack (issue 30 d):
model blocks (the build's stair, glass, poppy, slabs, panes, doors, rails…, the
pack's stone) drawn with the stack's
sprites; a stack whose files are gone draws today's look, pixel for pixel the same
as an import without one."""
from __future__ import annotations

import shutil

import numpy as np
import pytest

from ..mcres.builds import imported

CAMERA = ["14", "-18", "69", "120", "-30"]


@pytest.fixture(scope="module")
def worlds(tmp_path_factory):
    return imported(tmp_path_factory.mktemp("mcdraw"))


def render(world, out):
    from PIL import Image
    from voxel_addon.cli import main
    assert main(["render", "--world", str(world), "--camera", *CAMERA, "--distance", "1",
                 "--size", "320", "200", "--out", str(out)]) == 0
    return np.asarray(Image.open(out).convert("RGB")).astype(int)


def red(img):
    """Pixels of the pack's poppy (220, 30, 30) however lit."""
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    return (r > 60) & (r > 3 * g) & (r > 3 * b)


def test_model_blocks_with_the_stacks_sprites(worlds, tmp_path):
    (w, jar) = worlds
    a = render(w["with"], tmp_path / "with.png")
    b = render(w["without"], tmp_path / "without.png")
    # the project's flowers have no red bloom this big; the pack's poppy has (a cross)
    assert red(a).sum() > 40 and red(b).sum() < red(a).sum() / 4
    # the floor is the pack's stone, not the project's
    floor = slice(120, 180), slice(80, 240)
    assert (np.abs(a[floor] - b[floor]).max(axis=2) > 8).mean() > 0.5
    assert np.abs(a - b).max(axis=2).astype(bool).mean() > 0.2


def test_a_missing_stack_draws_todays_look(worlds, tmp_path):
    (w, jar) = worlds
    gone = tmp_path / "with.sqlite"
    shutil.copy(w["with"], gone)
    moved = jar.with_suffix(".away")
    jar.rename(moved)
    try:
        a = render(gone, tmp_path / "gone.png")
    finally:
        moved.rename(jar)
    b = render(w["without"], tmp_path / "without.png")
    assert np.array_equal(a, b)


def test_cli_renders_light_the_stacks_model_blocks_as_open(worlds):
    """The render's light (render.source.world_area) lets daylight through the
    build's rails (planks cubes in today's look) with the stack, as the bake and the
    live view do; without the stack they hold none."""
    from voxel_addon.render.source import world_area
    from voxel_addon.world import World
    from ..mcres import builds
    (w, _) = worlds
    day = {}
    for name in ("with", "without"):
        with World.open(w[name], readonly=True, loader=False) as world:
            a = world_area(world, 8, -8, 1)
        lx0, ly0 = a.light_at

        def at(x, z, y):
            v = (x - 16 * lx0, -1 - z - 16 * ly0, y + 64)
            return int(a.light[v]) >> 12
        day[name] = [at(x, z, y) for (x, z, y) in builds.RAILS]
    assert day["with"] == [15] * len(builds.RAILS)
    assert day["without"] == [0] * len(builds.RAILS)
