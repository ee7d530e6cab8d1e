"""`render` as a user runs it: a real generated world file, real subprocesses, PNG out."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def cli(*args):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", "voxel_addon", *map(str, args)],
                          capture_output=True, text=True, env=env, timeout=600)


def png(path) -> np.ndarray:
    from matplotlib.image import imread
    return (imread(str(path))[..., :3] * 255).round()


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    from voxel_addon.world import World
    p = tmp_path_factory.mktemp("render") / "w.sqlite"
    r = cli("generate", "--world", p, "--seed", 2019, "--center", 0, 0, "--radius", 1)
    assert r.returncode == 0, r.stderr
    w = World.open(p, readonly=True, loader=False)
    col = w.region_blocks(0, 0, 1, 1)[8, 8]
    w.close()
    return p, int(np.flatnonzero(col).max())  # the surface at (8, 8)


def test_render_a_world_day_and_night(world, tmp_path):
    p, top = world
    cam = (8, -6, top + 12, 90, -35)  # looking +y down onto (8, 8)
    out = {}
    for name, t in (("day", "10:30"), ("night", "22:00")):
        r = cli("render", "--world", p, "--camera", *cam, "--time", t, "--size", 64, 36,
                "--distance", 1, "--out", tmp_path / f"{name}.png")
        assert r.returncode == 0, r.stderr
        assert "triangles" in r.stdout
        out[name] = png(tmp_path / f"{name}.png")
    assert out["day"].shape == (36, 64, 3)
    assert out["day"].std() > 5, "not a flat image"
    assert out["day"].mean() > out["night"].mean() + 40
    # a lamp placed with `edit` lights the night around it
    lamp = cli("edit", "--world", p, "--set", 8, 8, top + 1, "lamp_yellow")
    assert lamp.returncode == 0, lamp.stderr
    r = cli("render", "--world", p, "--camera", *cam, "--time", "22:00", "--size", 64, 36,
            "--distance", 1, "--out", tmp_path / "lamp.png")
    assert r.returncode == 0, r.stderr
    lit = png(tmp_path / "lamp.png")
    centre = (slice(10, 30), slice(20, 44))
    # (a tenth of the centre at least: the lamp stands by the water, which lets light
    # through and shows little of it itself)
    assert np.percentile((lit - out["night"])[centre].mean(2), 90) > 15
    assert lit[centre][..., 0].mean() > lit[centre][..., 2].mean(), "yellow light"


GOOD = ["--world", "W", "--camera", 8, 8, 90, 0, 0, "--size", 32, 18]


@pytest.mark.parametrize("args, words", [
    (["--world", "/nonexistent/w.sqlite", "--camera", 8, 8, 90, 0, 0], "no world file"),
    (["--camera", 8, 8, 90, 0, 0], "needs --world"),
    (GOOD + ["--time", "25:00"], "bad time of day"),
    (GOOD + ["--time", "noonish"], "bad time of day"),
    (GOOD + ["--size", 0, 10], "--size"),
    (GOOD + ["--size", 64], "--size"),
    (GOOD + ["--size", "big", 10], "--size"),
    (GOOD + ["--distance", 0], "view distance"),
    (GOOD + ["--effects", "+bloom"], "unknown effect"),
    (GOOD + ["--set", "bloom=2"], "NAME one of"),
    (GOOD + ["--set", "fov"], "NAME=VALUE"),
    (GOOD + ["--set", "fov=wide"], "not a valid float"),
    (GOOD + ["--set", "fov=500"], "fov must be"),
    (GOOD + ["--set", "ssao=maybe"], "not a valid bool"),
    (["--world", "W", "--camera", 8, 8, 900, 0, 0], "camera z"),
])
def test_bad_input_is_one_line_exit_2(world, tmp_path, args, words):
    argv = [world[0] if a == "W" else a for a in args]
    r = cli("render", *argv, "--out", tmp_path / "x.png")
    assert r.returncode == 2, (r.returncode, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and words in lines[0], r.stderr
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize("scene, effects", [("desert", "peel3"), ("ocean", "oit")])
def test_opengl_41_core_context_draws_the_same_image(tmp_path, scene, effects):
    """macOS offers at most GL 4.1 core: Mesa pretends to be exactly that, and the
    pipeline must compile and draw the same (with depth peeling, and with weighted
    blended OIT over the ocean's water)."""
    env41 = dict(os.environ, PYTHONPATH=str(ROOT), MESA_GL_VERSION_OVERRIDE="4.1",
                 MESA_GLSL_VERSION_OVERRIDE="410")
    probe = subprocess.run([sys.executable, "-c", "import moderngl; print(moderngl."
                            "create_standalone_context(backend='egl').version_code)"],
                           capture_output=True, text=True, env=env41, timeout=120)
    assert probe.stdout.strip() == "410", probe.stderr
    args = ["-m", "voxel_addon", "render", "--scene", scene, "--size", "160", "90",
            "--effects", effects]
    r41 = subprocess.run([sys.executable, *args, "--out", str(tmp_path / "a.png")],
                         capture_output=True, text=True, env=env41, timeout=600)
    r45 = cli(*args[2:], "--out", tmp_path / "b.png")
    assert r41.returncode == 0 and r45.returncode == 0, r41.stderr + r45.stderr
    assert np.abs(png(tmp_path / "a.png") - png(tmp_path / "b.png")).max() <= 2
