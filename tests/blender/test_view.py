"""The pipeline on Blender's own GL context (blender/offscreen.View) draws what it
draws on its standalone EGL context, and Blender draws right afterwards.

The Blender side runs in a fresh process (view_job.py): bpy's GL context and this
process's EGL contexts stay apart. The EGL frame is rendered here, on the `gl` fixture.
"""
from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

from matplotlib.image import imread

from tests.host import python_cmd

JOB = Path(__file__).with_name("view_job.py")
SCENE, SIZE = "landscape", (160, 90)  # trees, plants, shadows: most passes have work
# Both contexts are the same driver here (Mesa llvmpipe), so the frames are identical;
# on a GPU Blender's context may differ a little (e.g. its own MSAA limit): the
# golden test's tolerance, which a broken pass (sky, light, shadows...) exceeds.
MEAN_TOL, P99_TOL = 0.75, 12.0


def _job(out: Path, *extra) -> dict:
    out.mkdir()
    r = subprocess.run(python_cmd(JOB, out, SCENE, *SIZE, *extra),
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    load = {p.stem: np.load(p) for p in out.glob("*.npy")}
    load.update({p.stem: imread(p) for p in out.glob("wb_*.png")})
    load["info"] = json.loads((out / "info.json").read_text())
    return load


def _egl(gl):
    from voxel_addon.light import daytime
    from voxel_addon.meshing import scenes
    from voxel_addon.render import Camera, Settings, source
    from voxel_addon.render.pipeline import Renderer
    sc, a = scenes.SCENES[SCENE], source.scene_area(SCENE)
    r = Renderer(gl, Settings())
    r.set_area(a.blocks, a.light, a.cx0, a.cy0, ring=True, light_at=a.light_at)
    img = r.render(Camera(*sc.camera), daytime.parse_time(sc.time), SIZE)
    r.release()
    return img


def _close(a, b) -> bool:
    d = np.abs(a.astype(float) - b)
    return d.mean() <= MEAN_TOL and np.percentile(d, 99) <= P99_TOL


def _blender_ok(res) -> bool:
    """Blender's own draws and Workbench render are unchanged by our frames."""
    return (np.array_equal(res["before"], res["after"])
            and np.array_equal(res["wb_before"], res["wb_after"]))


@pytest.fixture(scope="module")
def egl_frame(gl):
    return _egl(gl)


def test_blender_context_renders_like_egl_and_blender_still_draws(bpy, egl_frame, tmp_path):
    res = _job(tmp_path / "view")
    info = res["info"]
    assert info["backend"] == "OPENGL" and info["version_code"] >= 410, info
    frame = res["view"]
    assert frame.shape == (SIZE[1], SIZE[0], 3) and frame.std() > 10  # a picture, not a fill
    assert _close(frame, egl_frame), np.abs(frame.astype(float) - egl_frame).mean()
    # what a draw handler shows: the offscreen's colour texture holds the same frame
    assert np.array_equal(res["shown"], frame)
    # Blender's draws before our frames have the expected colours (the checks see real
    # pixels: texture left, 50 % blue over black right) and are unchanged after them
    b = res["before"].astype(int)
    assert (b[8, 4] == (200, 40, 90, 255)).all()
    assert np.abs(b[8, 28, :3] - np.array((0.2, 0.6, 1.0)) * 0.5 * 255).max() <= 2
    assert _blender_ok(res), np.abs(res["after"].astype(int) - res["before"]).mean()
    wb = res["wb_before"][8, 12, :3]  # single colour (0.2, 0.5, 0.8) flat, sRGB encoded
    assert np.abs(wb - (0.485, 0.735, 0.906)).max() < 0.01, wb


def test_a_pipeline_leaving_its_state_is_caught(bpy, egl_frame, tmp_path):
    """The same frame straight on Blender's context without glstate.kept(): our state
    spoils Blender's next draw, so the check above would fail. (Our own frame comes
    out right even so: every pass sets its framebuffer, switches, textures and the
    frame block itself.)"""
    res = _job(tmp_path / "dirty", "--dirty")
    assert not _blender_ok(res)


def test_render_view_operator_draws_the_world_from_the_scene_camera(tmp_path):
    """The add-on's operator: a flat world at noon seen from a camera looking down
    toward the horizon is sky above and lit ground below, in the image datablock."""
    out = tmp_path / "op"
    out.mkdir()
    r = subprocess.run(python_cmd(JOB.with_name("op_job.py"), out),
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    info = json.loads((out / "op.json").read_text())
    assert info == {"result": ["FINISHED"], "size": [96, 54]}
    px = np.load(out / "op.npy")[::-1, :, :3]  # top row first
    top, bottom = px[:8].mean((0, 1)), px[-8:].mean((0, 1))
    # (just above the horizon: the physical sky is paler there than at the zenith)
    assert top[2] > top[0] + 0.03, f"sky is blue at noon: {top}"
    assert abs(bottom - top).sum() > 0.3 and bottom.mean() > 0.1, (top, bottom)
