"""The live voxel view in the real Blender's 3D viewport, checked on screenshots of
the X screen (what a person sees). One Blender session runs every step of
viewport_job.py; the tests here read its pictures and reports."""
from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
JOB = Path(__file__).with_name("viewport_job.py")
CAM = (40.0, -60.0, 110.0, 90.0, -25.0, 50.0)  # as in viewport_job.py


def _run(app, out: Path, world: Path, steps: str | None = None, timeout=900):
    """Blender under a private Xvfb screen, the job inside it; never hangs."""
    app.run(["--factory-startup", "-P", JOB, "--", out, world, *([steps] if steps else [])],
            log=out / "blender.log", timeout=timeout)
    err = out / "error.txt"
    assert not err.exists(), err.read_text()
    return json.loads((out / "result.json").read_text())


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    path = tmp_path_factory.mktemp("world") / "w.sqlite"
    r = subprocess.run([sys.executable, "-m", "voxel_addon", "generate", "--world", str(path),
                        "--seed", "2019", "--radius", "12"], cwd=ROOT, capture_output=True,
                       text=True, env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert r.returncode == 0, r.stderr
    return path


@pytest.fixture(scope="module")
def run(app, world, tmp_path_factory):
    out = tmp_path_factory.mktemp("gui")
    res = _run(app, out, world)
    res["log"] = (out / "blender.log").read_text()
    res["out"] = out
    return res


ALONE = "far,leak"  # the steps viewport_job.py runs apart on Vulkan (its run() says why)


@pytest.fixture(scope="module")
def alone_run(app, world, request, tmp_path_factory):
    """The far and leak steps' results: from the job's one Blender, but on Vulkan from a
    Blender of their own (viewport_job.py run())."""
    if app.backend_name() != "vulkan":
        return request.getfixturevalue("run")
    return _run(app, tmp_path_factory.mktemp("gui_alone"), world, ALONE)


def _img(step):
    from matplotlib.image import imread
    return (imread(step["png"])[..., :3] * 255).round().astype(np.int16)


def _region(step):
    r = step["rect"]
    return _img(step)[r["y"]:r["y"] + r["h"], r["x"]:r["x"] + r["w"]]


def _patch(img, p, k=3):
    x, y = int(round(p[0])), int(round(p[1]))
    return img[y - k:y + k + 1, x - k:x + k + 1].reshape(-1, 3)


def test_voxels_and_blender_objects_mix_by_depth(run):
    off, on = run["steps"]["off"], run["steps"]["on"]
    a, b = _img(off), _img(on)
    # the cube above the terrain keeps its pixels
    assert np.abs(_patch(a, on["cube"]) - _patch(b, on["cube"])).max() <= 3
    # the cube buried under the terrain is shown without the world, hidden with it
    grey = _patch(a, on["buried"]).mean(0)
    assert np.ptp(grey) < 10 and grey.mean() > 120, grey  # Blender's lit grey cube
    assert np.abs(_patch(b, on["buried"]).mean(0) - grey).max() > 30
    # voxels (terrain or sky) wherever Blender showed its background
    ra, rb = _region(off), _region(on)
    bg = np.median(ra.reshape(-1, 3), 0)
    was_bg = (np.abs(ra - bg).max(-1) <= 2)
    changed = np.abs(rb - ra).max(-1) > 10
    assert changed[was_bg].mean() > 0.95, changed[was_bg].mean()
    green = (rb[..., 1] > rb[..., 0] + 20) & (rb[..., 1] > rb[..., 2])
    assert green.mean() > 0.2, "grass-covered terrain in view"


def test_a_still_view_redraws_from_its_kept_frame(run):
    st = run["steps"]
    kept, fresh = st["still_kept"], st["still_fresh"]
    # redraws of a still view reuse the frame, and look as the pipeline's own
    assert kept["frames"] >= 3 and kept["fresh"] == 0 and kept["last_reused"], kept
    assert fresh["fresh"] == fresh["frames"] >= 2 and not fresh["last_reused"], fresh
    d = np.abs(_region(st["still_kept"]) - _region(st["still_fresh"])).max(-1)
    # (but for the cube's edges: Blender's own anti-aliasing adds samples while still)
    r, (x, y) = kept["rect"], kept["cube"]
    x, y = int(x) - r["x"], int(y) - r["y"]
    d[max(0, y - 70):y + 70, max(0, x - 70):x + 70] = 0
    assert d.max() <= 2, (d.max(), (d > 2).mean())
    # a change makes a new frame (and the redraws after it reuse that one)
    for name in ("still_edit", "still_unedit", "still_hours", "still_view"):
        assert st[name]["fresh"] >= 1 and st[name]["last_reused"], (name, st[name])
    a, b = _img(st["still_kept"]), _img(st["still_edit"])
    p = st["still_edit"]["block"]
    assert np.abs(_patch(a, p) - _patch(b, p)).mean() > 20, "the placed blocks show"
    e = np.abs(_region(st["still_unedit"]) - _region(st["still_kept"]))
    assert e.mean() < 0.5 and np.percentile(e, 99.9) < 8, "and go again"
    noon, evening = _region(st["still_kept"]), _region(st["still_hours"])
    assert np.abs(noon - evening).mean() > 20
    turned = (np.abs(_region(st["still_view"]) - evening).max(-1) > 5).mean()
    assert turned > 0.1, turned


def test_blender_objects_move_on_a_still_view_without_a_new_frame(run):
    st = run["steps"]
    base = _img(st["still_hours"])
    up, down = st["still_cube"], st["still_buried"]
    for s in (up, down):
        assert s["frames"] >= 3 and s["fresh"] == 0, s
    # the cube moved over the terrain shows (Blender's lit grey), buried it is hidden
    grey = _patch(_img(up), up["moved"]).mean(0)
    assert np.ptp(grey) < 10 and grey.mean() > 120, grey
    assert np.abs(_patch(base, up["moved"]).mean(0) - grey).max() > 30
    assert np.abs(_patch(_img(down), down["moved"]) - _patch(base, down["moved"])).max() <= 3


def test_show_off_gives_back_blenders_image(run):
    a, b = _region(run["steps"]["off"]), _region(run["steps"]["off_again"])
    # 0.5 %: Blender's own cube edges (its overlay's smoothing) differ by a few pixels
    # between two draws; a live view left drawing covers most of the region
    assert (np.abs(a - b).max(-1) <= 2).mean() > 0.995


def test_time_of_day_changes_the_sky(run):
    noon, night = _region(run["steps"]["sky12"]), _region(run["steps"]["sky21"])
    top_noon, top_night = noon[:60].reshape(-1, 3).mean(0), night[:60].reshape(-1, 3).mean(0)
    assert top_noon[2] > 90 and top_noon[2] > top_noon[0] + 15, top_noon
    # (21:00: the moon stands at 40 degrees, the eye has adapted: a dark blue sky)
    assert top_night.mean() < 0.65 * top_noon.mean() and top_night[0] < top_night[2], (top_noon, top_night)


def _cli(world, size, hours=12.0):
    """The CLI's renderer from the job's camera, on a standalone EGL context."""
    from voxel_addon.world import World
    from voxel_addon.render import Camera, Settings, source
    from voxel_addon.render.device import mgl
    from voxel_addon.render.pipeline import Renderer
    s = Settings(distance=4, light_radius=4, fov=CAM[5], dof=False)  # as the viewport
    w = World.open(world, readonly=True, loader=False)
    try:
        a = source.world_area(w, CAM[0], CAM[1], s.distance, s.light_radius)
        s.sea_level = source.sea_level(w.generator)  # as the viewport (the world's sea)
    finally:
        w.close()
    ctx = mgl.context()
    try:
        r = Renderer(ctx, s)
        r.set_area(a.blocks, a.light, a.cx0, a.cy0, ring=True, light_at=a.light_at)
        img = r.render(Camera(*CAM[:5]), hours, size)
        r.release()
    finally:
        ctx.release()
    return img.astype(np.int16)


def test_camera_view_shows_what_the_cli_renders(run, world):
    st = run["steps"]["camera"]
    xs = [p[0] for p in st["frame"]]
    ys = [p[1] for p in st["frame"]]
    x0, x1, y0, y1 = int(min(xs)) + 2, int(max(xs)) - 1, int(min(ys)) + 2, int(max(ys)) - 1
    shot = _img(st)[y0:y1, x0:x1]
    ref = _cli(world, (x1 - x0, y1 - y0))
    d = np.abs(shot - ref)
    # the same terrain from the same camera: small differences only (the viewport's
    # frame covers the whole region, so texels and edges fall a little differently)
    assert d.mean() < 12 and np.percentile(d, 50) < 8, (d.mean(), np.percentile(d, 50))
    # and not just similar colours: a shifted picture is much further away
    assert np.abs(shot[:, 20:] - ref[:, :-20]).mean() > d.mean() * 1.3


def test_side_view_from_outside_sees_a_closed_wall_not_caves(run):
    """Orthographic, from outside the shown area, level with its underground: with the
    outer wall closed (the default) every pixel below the terrain shows the wall (none
    shows the sky through the slab, as the control without it does)."""
    def sky_share(step):
        img = _img(step)
        sky = np.array([img[int(y), int(x)] for x, y in step["sky"]], float)
        band = np.array([img[int(y), int(x)] for x, y in step["band"]], float)
        near = np.abs(band[:, None, :] - sky[None, :, :]).max(-1).min(-1) < 12
        return near.mean(), sky.mean(0), band.mean(0)
    closed, open_ = sky_share(run["steps"]["side"]), sky_share(run["steps"]["side_open"])
    assert closed[0] < 0.02, closed
    assert open_[0] > 0.1, open_  # the control: the sky shows through the open side


def test_ortho_top_view_shows_the_rivers_where_the_world_has_water(run, world):
    """Orthographic top view: pixels over columns whose top block is water are blue."""
    from voxel_addon.core.blocks import REGISTRY
    from voxel_addon.world import World
    st = run["steps"]["ortho"]
    (ax, ay), (bx, _), (_, cy) = st["corners"][0], st["corners"][1], st["corners"][2]
    w = World.open(world, readonly=True, loader=False)
    try:
        blocks = w.region_blocks(0, 0, 3, 3)  # blocks x, y in [0, 48)
    finally:
        w.close()
    solid = blocks != 0
    top = np.where(solid.any(-1), 255 - np.argmax(solid[..., ::-1], -1), 0)
    top_block = np.take_along_axis(blocks, top[..., None], -1)[..., 0]
    water = top_block == REGISTRY.id("water")
    assert 0.05 < water.mean() < 0.95, water.mean()
    img = _img(st)
    hits = []
    for x in range(2, 46, 2):
        for y in range(2, 46, 2):
            px = ax + (bx - ax) * (x + 0.5) / 48
            py = ay + (cy - ay) * (y + 0.5) / 48
            c = img[int(py), int(px)]
            blue = c[2] > c[1] + 15 and c[2] > c[0] + 15
            hits.append(blue == water[x, y])
    assert np.mean(hits) > 0.85, np.mean(hits)


def test_moving_the_view_streams_new_chunks(run):
    s0, s1 = run["steps"]["stream0"], run["steps"]["stream1"]
    assert s1["moved"] and s1["status"]["drawn"] == s1["status"]["wanted"] > 0
    assert np.abs(_region(s0) - _region(s1)).mean() > 10


def test_no_python_error_over_100_redraws(run):
    r = run["steps"]["redraws"]
    assert r["frames"] >= 100 and r["error"] is None, r
    # a keyframed panel value reaches the redraws at each frame (the kept settings
    # are read again after a frame change)
    assert r["animated_haze"] == [7.0, 1.5], r
    bad = [ln for ln in run["log"].splitlines()
           if re.search(r"Traceback|Error:|Exception", ln)]
    assert not bad, bad[:20]


def test_register_unregister_10_times_leaks_nothing(alone_run):
    leak = alone_run["steps"]["leak"]
    assert leak == {"renderers": 0, "gpus": 0, "feed": False, "handle": False,
                    "timer": False, "load_pre": 0, "threads": leak["threads"]}, leak
    assert leak["threads"] <= 0, leak
    # and nothing of the world is drawn any more
    reg = _region(alone_run["steps"]["unregistered"])
    bg = np.median(reg.reshape(-1, 3), 0)
    assert bg.max() - bg.min() < 6 and (np.abs(reg - bg).max(-1) <= 2).mean() > 0.8


def test_quad_view_draws_every_region(run):
    q = run["steps"]["quad"]
    assert q["gpus"] == 1 and q["regions"] >= 4 and q["status"]["error"] is None, q
    img = _img(q)
    grey = np.array([63, 63, 63])  # Blender's viewport background (theme): nothing drawn
    for r in q["rects"]:
        crop = img[r["y"] + 4:r["y"] + r["h"] - 4, r["x"] + 4:r["x"] + r["w"] - 4]
        assert (np.abs(crop - grey).max(-1) > 12).mean() > 0.9, r


def _green(img) -> float:
    return float(((img[..., 1] > img[..., 0] + 20) & (img[..., 1] > img[..., 2])).mean())


def test_a_second_window_shows_voxels_and_closing_it_releases_its_share(run):
    w = run["steps"]["window1"]
    assert w["windows"] == 2 and w["windows_drawn"] == 2, w
    # a Pane per window (framebuffers belong to one GL context; a platform may give
    # each window its own)
    assert w["gpus_open"] == 2, w
    assert w["regions_open"] >= 2, w
    r = w["rect2"]  # the second window's 3D viewport, the top view: grass
    crop = _img({"png": w["png2"]})[r["y"] + r["h"] // 5:r["y"] + 4 * r["h"] // 5,
                                   r["x"] + r["w"] // 5:r["x"] + 4 * r["w"] // 5]
    assert _green(crop) > 0.3, _green(crop)
    # closed: its region is forgotten, one Pane stays (the first window's), one
    # Renderer alive, no error, and the first window still draws voxels
    assert w["windows_closed"] == 1 and w["regions_closed"] == w["regions_open"] - 1, w
    assert w["gpus_closed"] == 1 and w["renderers"] == 1, w
    assert w["status"]["error"] is None and w["status"]["drawn"] == w["status"]["wanted"] > 0
    assert _green(_region(w)) > 0.2, _green(_region(w))


def test_without_a_world_the_panel_says_why(run):
    p = run["steps"]["problem"]
    assert p["sentence"].startswith("no world open"), p
    assert p["status"]["error"] is None


def test_file_new_removes_the_view_and_it_comes_back(run):
    n = run["steps"]["newfile"]
    assert not n["handle"] and not n["feed"] and not n["old_stream_alive"] and n["gpus"] == 0
    assert n["show"] is False
    again = n["again"]
    assert again["drawn"] == again["wanted"] > 0 and again["error"] is None


def test_render_animation_from_the_ui_writes_frames_and_esc_stops(run):
    a = run["steps"]["animation"]
    assert a["started"] == ["RUNNING_MODAL"], a
    assert a["files"] == ["f_0001.png", "f_0002.png", "f_0003.png"], a
    assert 2 <= a["stopped_at"] < 40 and a["after_stop"] == a["stopped_at"], a
    m = a["movie"]  # FFmpeg output: one movie; Esc leaves nothing behind
    assert m["started"] == ["RUNNING_MODAL"] and m["files"] == ["fly_0001-0004.mp4"], m
    assert m["tmp"] == [] and m["scenes"] == m["scenes2"] == ["Scene"], m
    # encoded by Blender's render job, with no render window and the preference back
    assert m["job"] and m["display"] == "WINDOW" and m["windows"] == 1, m
    assert m["stopped_with"] >= 2 and m["files2"] == [] and m["tmp2"] == [], m


def test_far_terrain_shows_and_mixes_with_far_objects_by_depth(alone_run):
    """Far 32 beyond distance 4 (viewport_job.py step_far): terrain where far 0 showed
    sky toward the horizon; a cube ~400 blocks away above the far ground stays in
    front of it, one sunk into the far ground is hidden by it."""
    st = alone_run["steps"]
    f0, f64, off = st["far0"], st["far32"], st["far_off"]
    assert f64["status"]["far_drawn"] >= f64["status"]["far_wanted"] > 0, f64["status"]
    a, b, c = _region(f0), _region(f64), _region(off)
    h = a.shape[0]
    band = slice(int(h * 0.25), int(h * 0.6))  # around the horizon
    changed = np.abs(b[band].astype(int) - a[band]).max(-1) > 12
    assert changed.mean() > 0.15, changed.mean()
    grey = _patch(_img(off), f64["above"]).mean(0)  # Blender's lit cube, voxels off
    assert np.ptp(grey) < 12, grey
    # in front of the far terrain: its pixels as without voxels
    assert np.abs(_patch(_img(f64), f64["above"]).mean(0) - grey).max() <= 12
    # sunk into the far ground: hidden by it (and shown without voxels)
    sunk_off = _patch(_img(off), f64["sunk"]).mean(0)
    assert np.ptp(sunk_off) < 12, sunk_off
    assert np.abs(_patch(_img(f64), f64["sunk"]).mean(0) - sunk_off).max() > 20
