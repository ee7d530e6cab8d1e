"""One frame, two devices: the live view's device (Blender's gpu module) draws the
reference scenes as the moderngl device does on its standalone EGL context (same
scene, same camera, MSAA 1), and Blender draws as before right afterwards and finds
its GPU state as it left it.

The Blender side runs in a fresh process (view_job.py): bpy's GPU context and this
process's EGL context stay apart. The moderngl frames are rendered here, on the `gl`
fixture. Tolerance: the two differ where llvmpipe rounds differently (depth 24-bit on
moderngl, 32-bit float in Blender; derivatives at triangle edges): measured at most
mean 0.25 and 99th percentile 3 levels (of 255) over the four scenes on OpenGL and
Vulkan; a broken pass (sky, light, shadows, water, fog) moves the mean by tens.
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
SIZE = (160, 90)
MEAN_TOL, P99_TOL = 0.5, 4.0
SCENES = ("cave", "desert", "landscape", "ocean")


def _job(out: Path, *extra) -> dict:
    out.mkdir()
    r = subprocess.run(python_cmd(JOB, out, *SIZE, *extra),
                       capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    load = {p.stem: np.load(p) for p in out.glob("*.npy")}
    load.update({p.stem: imread(p) for p in out.glob("wb_*.png")})
    load["info"] = json.loads((out / "info.json").read_text())
    return load


def _moderngl(gl, name):
    from voxel_addon.light import daytime
    from voxel_addon.meshing import scenes
    from voxel_addon.render import Camera, Settings, source
    from voxel_addon.render.pipeline import Renderer
    sc, a = scenes.SCENES[name], source.scene_area(name)
    r = Renderer(gl, Settings(msaa=1))
    r.set_area(a.blocks, a.light, a.cx0, a.cy0, ring=True, light_at=a.light_at)
    img = r.render(Camera(*sc.camera), daytime.parse_time(sc.time), SIZE)
    r.release()
    return img


def _blender_ok(res) -> bool:
    """Blender's own draws and Workbench render are unchanged by our frames."""
    return (np.array_equal(res["before"], res["after"])
            and np.array_equal(res["wb_before"], res["wb_after"]))


@pytest.fixture(scope="module")
def blender(bpy, tmp_path_factory):
    return _job(tmp_path_factory.mktemp("view") / "view")


@pytest.mark.parametrize("name", SCENES)
def test_gpu_module_frame_equals_moderngl_frame(gl, blender, name):
    frame, want = blender[name], _moderngl(gl, name)
    assert frame.shape == (SIZE[1], SIZE[0], 3) and frame.std() > 10  # a picture, not a fill
    d = np.abs(frame.astype(float) - want)
    assert d.mean() <= MEAN_TOL and np.percentile(d, 99) <= P99_TOL, (d.mean(), np.percentile(d, 99))


def test_the_comparison_can_fail(gl, blender):
    """A frame of another hour (a broken sky or light would look like this) is far
    outside the tolerance."""
    from voxel_addon.light import daytime
    from voxel_addon.meshing import scenes
    from voxel_addon.render import Camera, Settings, source
    from voxel_addon.render.pipeline import Renderer
    sc, a = scenes.SCENES["desert"], source.scene_area("desert")
    r = Renderer(gl, Settings(msaa=1))
    r.set_area(a.blocks, a.light, a.cx0, a.cy0, ring=True, light_at=a.light_at)
    other = r.render(Camera(*sc.camera), daytime.parse_time(sc.time) + 3.0, SIZE)
    r.release()
    assert np.abs(blender["desert"].astype(float) - other).mean() > 5 * MEAN_TOL


def test_blender_draws_and_finds_its_state_after_our_frames(blender):
    info = blender["info"]
    assert info["backend"] in ("OPENGL", "VULKAN", "METAL"), info
    # Blender's draws before our frames have the expected colours (the checks see real
    # pixels: texture left, 50 % blue over black right) and are unchanged after them
    b = blender["before"].astype(int)
    assert (b[8, 4] == (200, 40, 90, 255)).all()
    assert np.abs(b[8, 28, :3] - np.array((0.2, 0.6, 1.0)) * 0.5 * 255).max() <= 2
    assert _blender_ok(blender), np.abs(blender["after"].astype(int) - blender["before"]).mean()
    wb = blender["wb_before"][8, 12, :3]  # single colour (0.2, 0.5, 0.8) flat, sRGB encoded
    assert np.abs(wb - (0.485, 0.735, 0.906)).max() < 0.01, wb
    assert info["state_after"] == info["state_before"], info
    assert info["state_before"]["blend"] == "ALPHA"  # (a host's state, not the defaults)


def test_a_pipeline_leaving_its_state_is_caught(bpy, tmp_path):
    """The same frames without liveview.host.kept(): the state check above fails."""
    res = _job(tmp_path / "dirty", "--dirty")
    assert res["info"]["state_after"] != res["info"]["state_before"]


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


def test_render_view_waits_for_far_terrain(tmp_path):
    """Far 48 beyond distance 2 (the flat world), 2 degrees down: the operator waits for
    the far ring, which fills the band below the horizon that far 0 leaves to the sky."""
    px = {}
    for far in (0, 48):
        out = tmp_path / f"far{far}"
        out.mkdir()
        r = subprocess.run(python_cmd(JOB.with_name("op_job.py"), out, far),
                           capture_output=True, text=True, timeout=600)
        assert r.returncode == 0, r.stderr[-3000:]
        assert json.loads((out / "op.json").read_text())["result"] == ["FINISHED"]
        px[far] = np.load(out / "op.npy")[::-1, :, :3]
    # below the horizon (~row 22 of 54, 0.43 degrees a row): the ground 110-400 blocks
    # away, grass with far on, haze or sea without
    band = slice(30, 54)
    green = {f: ((p[band, :, 1] > p[band, :, 2] + 0.1) & (p[band, :, 1] > p[band, :, 0] + 0.1)).mean()
             for f, p in px.items()}
    assert green[0] < 0.1 and green[48] > 0.9, green
