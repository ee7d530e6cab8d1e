"""Golden images of the four reference scenes (meshing.scenes: ocean, desert, landscape,
cave) with the default effects, compared with a tolerance so that small driver or
rounding differences pass while a broken pass (sky, light, shadows, peeling, fog...)
fails.

The scenes come from the real generator, so retuning it changes them: golden/scenes.txt
holds a hash of each scene's blocks and light, and a changed scene fails with its own
message (regenerate) rather than as a pixel difference of the renderer.

Regenerate after an intended change of the look or of the scenes, then LOOK at the PNGs
before committing them:

    VOXEL_UPDATE_GOLDEN=1 .venv/bin/python -m pytest tests/render/test_golden.py
"""
from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numpy as np
import pytest

from voxel_addon.meshing import scenes

GOLDEN = Path(__file__).parent / "golden"
SIZE = (160, 90)
MEAN_TOL = 0.75  # mean absolute difference, 0..255 (shadows off: desert 0.4, landscape 0.7)
P99_TOL = 12.0   # 99th percentile (no shadows: 15-17 at the 50-block fade, no DOF: 15, no MSAA: 50)



def _hashes() -> dict:
    p = GOLDEN / "scenes.txt"
    return dict(ln.split() for ln in p.read_text().splitlines() if ln.strip()) if p.exists() else {}


def render_scene(gl, name):
    from voxel_addon.light import daytime
    from voxel_addon.render import Camera, Settings, source
    from voxel_addon.render.pipeline import Renderer
    sc = scenes.SCENES[name]
    a = source.scene_area(name)
    h = hashlib.sha256(repr((sc.camera, sc.time)).encode())
    for arr in (a.blocks, a.light):
        h.update(np.ascontiguousarray(arr).tobytes())
    r = Renderer(gl, Settings(sea_level=source.scene_sea_level(name)))  # as the CLI renders
    r.set_area(a.blocks, a.light, a.cx0, a.cy0, ring=True, light_at=a.light_at)
    r.s.sea = source.open_sea(r)
    img = r.render(Camera(*sc.camera), daytime.parse_time(sc.time), SIZE)
    r.release()
    return img, h.hexdigest()[:16]


@pytest.mark.parametrize("name", sorted(scenes.SCENES))
def test_scene_matches_golden(gl, name):
    from matplotlib.image import imread
    from voxel_addon.textures import png_bytes
    img, digest = render_scene(gl, name)
    path = GOLDEN / f"{name}.png"
    if os.environ.get("VOXEL_UPDATE_GOLDEN") == "1":
        GOLDEN.mkdir(exist_ok=True)
        path.write_bytes(png_bytes(np.dstack([img, np.full(img.shape[:2], 255, np.uint8)])))
        hashes = {**_hashes(), name: digest}
        (GOLDEN / "scenes.txt").write_text("".join(f"{k} {v}\n" for k, v in sorted(hashes.items())))
        pytest.skip(f"wrote {path}")
    assert path.exists(), f"no golden image {path}: run with VOXEL_UPDATE_GOLDEN=1"
    if _hashes().get(name) != digest:
        pytest.fail(f"scene {name!r} changed (generator or meshing.scenes retuned): "
                    "regenerate with VOXEL_UPDATE_GOLDEN=1 and look at the images")
    want = (imread(str(path))[..., :3] * 255).round()
    assert want.shape == img.shape
    d = np.abs(img.astype(float) - want)
    assert d.mean() < MEAN_TOL and np.percentile(d, 99) < P99_TOL, (d.mean(), np.percentile(d, 99))
    assert img.std() > 10, "the scene shows something"
