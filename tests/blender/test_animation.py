"""Render Voxel Animation (bpy, exec path): one PNG per frame into the output path,
the camera's keyframes and the day cycle followed."""
from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np

from tests.host import python_cmd

JOB = Path(__file__).with_name("anim_job.py")


def test_render_animation_writes_each_frame_with_camera_and_day_cycle(bpy, tmp_path):
    from matplotlib.image import imread
    r = subprocess.run(python_cmd(JOB, tmp_path), capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    info = json.loads((tmp_path / "anim.json").read_text())
    assert info == {"result": ["FINISHED"], "files": ["f_0001.png", "f_0002.png", "f_0003.png"],
                    "frame": 1}
    imgs = [imread(tmp_path / "frames" / f)[..., :3] for f in info["files"]]
    assert all(i.shape == (36, 64, 3) for i in imgs)
    sky = [i[:6].mean((0, 1)) for i in imgs]
    # noon: a blue sky; 18:00 (sunset) differs; midnight is dark
    assert sky[0][2] > sky[0][0] and sky[0].mean() > 0.4, sky[0]
    assert np.abs(sky[1] - sky[0]).max() > 0.05, sky
    assert sky[2].mean() < sky[0].mean() - 0.3, sky


def test_render_animation_into_a_video_matches_the_png_frames(bpy, tmp_path):
    """Output format FFmpeg (MPEG-4/H.264): one movie named as Blender names it, as
    long and as large as the frames; decoded frames match the PNG path's (lossy: mean
    error small) and noon and midnight stay apart; no temporary scene is left."""
    from matplotlib.image import imread
    r = subprocess.run(python_cmd(JOB, tmp_path, "movie"), capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    info = json.loads((tmp_path / "anim.json").read_text())
    m = info["movie"]
    assert m["result"] == ["FINISHED"] and info["frame"] == 1, info
    assert m["files"] == [m["path"]] == ["fly_0001-0006.mp4"], m
    assert m["duration"] == 6 and m["size"] == [64, 36], m
    assert m["scenes"] == ["Scene"], m
    for name, f in zip(m["decoded"], (1, 3, 5)):
        png = imread(tmp_path / "frames" / f"f_{f:04d}.png")[..., :3]
        dec = imread(tmp_path / name)[..., :3]
        assert dec.shape == png.shape == (36, 64, 3)
        err = np.abs(dec - png).mean()
        assert err < 0.02, (f, err)
    day, night = (imread(tmp_path / n)[..., :3] for n in m["decoded"][:2])
    assert np.abs(day - night).mean() > 0.3
