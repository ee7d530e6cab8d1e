"""The bench's way to the Blender GUI (bench/gui.py) loads tools/blender_app.py by path
and lists what the viewport area runs: every installed Blender on each backend it is
set up for."""
from __future__ import annotations

from voxel_addon.bench import gui


def test_blender_app_loads_and_lists_the_variants():
    app = gui.app()
    assert app is not None and app is gui.app()  # loaded once
    why = gui.missing()
    assert why is None or isinstance(why, str)
    v = gui.variants()
    assert all(isinstance(b, str) and gpu in ("opengl", "vulkan") for b, gpu in v)
    assert {a.version for a in app.apps()} == {b for b, _ in v}
