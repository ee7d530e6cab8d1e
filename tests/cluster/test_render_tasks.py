"""bake --per tile --out DIR (and animate) in one process and on a real Dask cluster:
the same files, a killed worker costs only its tasks, a killed command resumes."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
REGION = ("-40", "-40", "40", "40")  # 2x2 tiles: 64x64, 16x64, 64x16, 16x16 columns
TILES = {f"tile_{x}_{y}.glb" for x in (-40, 24) for y in (-40, 24)}


def cli(*args, wait=True):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    cmd = [sys.executable, "-m", "voxel_addon", *map(str, args)]
    if not wait:
        return subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True, start_new_session=True)
    return subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=300)


def files(d: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(d.iterdir())}


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    from voxel_addon.world import World
    p = tmp_path_factory.mktemp("w") / "w.sqlite"
    with World.create(p, seed=5, backend="numpy", loader=False) as w:
        w.generate_area([(x, y) for x in range(-3, 3) for y in range(-3, 3)])
        w.set_block(20, 20, 120, "lamp_red")  # light that crosses the tile edge at x=24
    return p


def bake(world, out, *more, wait=True):
    return cli("bake", "--world", world, "--region", *REGION, "--per", "tile", "--out", out,
               *more, wait=wait)


@pytest.fixture(scope="module")
def baked(world, tmp_path_factory):
    """The one-process tiles."""
    out = tmp_path_factory.mktemp("ref") / "tiles"
    r = bake(world, out)
    assert r.returncode == 0, r.stderr
    got = files(out)
    assert set(got) == TILES
    return got


def test_tiles_are_self_contained_validator_clean_glbs(baked, tmp_path):
    import json
    import shutil
    import struct
    node = shutil.which("node")
    if not node or not (ROOT / ".tools" / "node_modules" / "gltf-validator").is_dir():
        pytest.skip("glTF validator missing (python build.py setup installs it into .tools)")
    for name, data in baked.items():
        (tmp_path / name).write_bytes(data)
        r = subprocess.run([node, str(ROOT / "tools" / "validate_gltf.mjs"), str(tmp_path / name)],
                           capture_output=True, text=True, timeout=120)
        issues = json.loads(r.stdout)["issues"]
        assert issues["numErrors"] == issues["numWarnings"] == 0, (name, issues["messages"])
        n = struct.unpack_from("<I", data, 12)[0]
        doc = json.loads(data[20:20 + n])
        assert all("uri" not in b for b in doc["buffers"] + doc.get("images", []))
        assert [m["name"] for m in doc["meshes"]] == [name[:-4]]  # the tile, nothing else


def test_bake_on_a_scheduler_equals_one_process(baked, world, cluster, tmp_path):
    r = bake(world, tmp_path / "t", "--scheduler", cluster.address)
    assert r.returncode == 0, r.stderr
    assert files(tmp_path / "t") == baked


def test_bake_on_local_workers_equals_one_process(baked, world, tmp_path):
    r = bake(world, tmp_path / "t", "--workers", "2")
    assert r.returncode == 0, r.stderr
    assert files(tmp_path / "t") == baked


def _busy_worker(client, prefix, proc, timeout=60.0):
    """The address of a worker holding a task whose key starts with `prefix` (of the
    command PROC: every task is handed out at once, so it holds it while it runs)."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout and proc.poll() is None:
        for addr, keys in client.processing().items():
            if any(str(k).startswith(prefix) for k in keys):
                return addr
        time.sleep(0.01)
    raise AssertionError(f"no worker was seen with a {prefix} task ({proc.poll()})")


def test_bake_survives_a_killed_worker(baked, world, cluster, tmp_path):
    with cluster.client() as c:
        p = bake(world, tmp_path / "t", "--scheduler", cluster.address, wait=False)
        victim = _busy_worker(c, "tile_glb", p)
        pid = c.run(os.getpid, workers=[victim])[victim]
        os.kill(pid, signal.SIGKILL)
        _, err = p.communicate(timeout=120)
        assert p.returncode == 0, err
        assert files(tmp_path / "t") == baked
    cluster.wait_workers(2)  # the nanny starts it again for the next test


def test_bake_killed_then_run_again_does_only_the_rest(baked, world, cluster, tmp_path):
    for attempt in range(3):  # a kill that came after the last tile proves nothing: again
        out = tmp_path / f"t{attempt}"
        p = bake(world, out, "--scheduler", cluster.address, wait=False)
        t0 = time.monotonic()
        while not any(out.glob("*.glb")) and p.poll() is None:
            assert time.monotonic() - t0 < 120
            time.sleep(0.005)
        os.killpg(p.pid, signal.SIGKILL)
        p.wait()
        kept = {q.name: q.stat() for q in out.glob("*.glb")}
        if len(kept) < len(TILES):
            break
    assert 1 <= len(kept) < len(TILES)  # killed mid-job
    assert all(files(out)[n] == baked[n] for n in kept)  # what is there is complete
    r = bake(world, out, "--scheduler", cluster.address)
    assert r.returncode == 0, r.stderr
    assert f"{len(TILES) - len(kept)} tiles written, {len(kept)} already there" in r.stderr
    assert files(out) == baked  # and no half file is left
    for n, st in kept.items():  # not written again
        assert (out / n).stat().st_mtime_ns == st.st_mtime_ns


# ------------------------------------------------------------------ animate

FRAMES = ["frame_0001.png", "frame_0002.png", "frame_0003.png"]


@pytest.fixture(scope="module")
def blend(tmp_path_factory):
    p = tmp_path_factory.mktemp("blend") / "fly.blend"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    r = subprocess.run([sys.executable, str(Path(__file__).with_name("blend_job.py")), str(p)],
                       capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 0 and p.is_file(), r.stderr[-2000:]
    return p


def animate(world, blend, out, *more, wait=True):
    return cli("animate", "--world", world, "--blend", blend, "--out", out, *more, wait=wait)


def pixels(d: Path) -> dict:
    import numpy as np
    from matplotlib.image import imread
    return {n: np.round(imread(d / n) * 255).astype(np.int16) for n in sorted(os.listdir(d))}


def same_frames(d: Path, ref: dict) -> None:
    got = pixels(d)
    assert set(got) == set(ref)
    for n, img in got.items():
        assert img.shape == ref[n].shape == (36, 64, 4)
        assert abs(img - ref[n]).max() <= 1, n


@pytest.fixture(scope="module")
def frames(world, blend, tmp_path_factory):
    """The one-process frames: the camera flies, the day goes from noon to midnight."""
    out = tmp_path_factory.mktemp("ref") / "frames"
    r = animate(world, blend, out)
    assert r.returncode == 0, r.stderr
    got = pixels(out)
    assert sorted(got) == FRAMES
    sky = [got[n][:4, :, :3].mean() for n in FRAMES]
    assert sky[0] > sky[2] + 40, sky  # noon is brighter than midnight: the day cycle
    return got


def test_animate_on_a_scheduler_equals_one_process(frames, world, blend, cluster, tmp_path):
    r = animate(world, blend, tmp_path / "f", "--scheduler", cluster.address)
    assert r.returncode == 0, r.stderr
    same_frames(tmp_path / "f", frames)


def test_animate_on_local_workers_equals_one_process(frames, world, blend, tmp_path):
    r = animate(world, blend, tmp_path / "f", "--workers", "2")
    assert r.returncode == 0, r.stderr
    same_frames(tmp_path / "f", frames)


def test_animate_survives_a_killed_worker(frames, world, blend, cluster, tmp_path):
    with cluster.client() as c:
        p = animate(world, blend, tmp_path / "f", "--scheduler", cluster.address, wait=False)
        victim = _busy_worker(c, "frame_png", p)
        os.kill(c.run(os.getpid, workers=[victim])[victim], signal.SIGKILL)
        _, err = p.communicate(timeout=120)
        assert p.returncode == 0, err
        same_frames(tmp_path / "f", frames)
    cluster.wait_workers(2)


def test_animate_killed_then_run_again_renders_only_the_rest(frames, world, blend, tmp_path):
    for attempt in range(3):  # a kill that came after the last frame proves nothing: again
        out = tmp_path / f"f{attempt}"
        p = animate(world, blend, out, wait=False)
        t0 = time.monotonic()
        while not any(out.glob("*.png")) and p.poll() is None:
            assert time.monotonic() - t0 < 120
            time.sleep(0.005)
        os.killpg(p.pid, signal.SIGKILL)
        p.wait()
        kept = {q.name: q.stat().st_mtime_ns for q in out.glob("*.png")}
        if len(kept) < len(FRAMES):
            break
    assert 1 <= len(kept) < len(FRAMES)
    r = animate(world, blend, out, "--frames", 1, 3)
    assert r.returncode == 0, r.stderr
    assert f"{3 - len(kept)} frames of 64x36 written, {len(kept)} already there" in r.stderr
    assert not list(out.glob(".*"))  # the frame the kill interrupted was written again
    same_frames(out, frames)
    assert {n: (out / n).stat().st_mtime_ns for n in kept} == kept


@pytest.mark.parametrize("args, message", [
    (("bake", "--region", 0, 0, 8, 8, "--out", "{tmp}/tiles"), "a folder takes --per tile"),
    (("animate", "--blend", "{tmp}/no.blend", "--out", "{tmp}/f"), "no .blend at"),
    (("animate", "--blend", "{tmp}/bad.blend", "--out", "{tmp}/f"), "cannot read"),
])
def test_mistakes_are_one_line(world, tmp_path, args, message):
    (tmp_path / "bad.blend").write_bytes(b"not a blend file")
    r = cli(args[0], "--world", world, *(str(a).format(tmp=tmp_path) for a in args[1:]))
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and message in r.stderr, r.stderr
    assert r.stdout == ""
