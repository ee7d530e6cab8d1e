"""Saves never fail silently (issue 18): closing the worlds (unregister) under a
file-size limit really fails the save; the user is told in the console and the
status bar, the unsaved edits go into a file beside the world (or, when that cannot
be written either, the world stays open and the next close saves it), and opening
the world again brings them back."""
from __future__ import annotations

import json
import subprocess

import pytest

from tests import host
from tests.blender.test_edit import on_file

JOB = host.ROOT / "tests" / "blender" / "save_fails_job.py"


@pytest.fixture
def world(tmp_path):
    from voxel_addon.world import World
    path = tmp_path / "w.sqlite"
    with World.create(path, seed=3, generator="flat") as w:
        w.chunk_at(0, 0)
    return path


def _close_under_limit(world, n):
    r = subprocess.run(host.python_cmd(JOB, world, n), capture_output=True, text=True,
                       timeout=300, cwd=host.ROOT)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    return json.loads(r.stdout.strip().splitlines()[-1]), r.stderr


def test_a_failing_save_is_told_and_its_edits_come_back_from_beside_the_world(bpy, world):
    from voxel_addon.world import rescue
    out, err = _close_under_limit(world, 3)
    assert out["pending"] == 3 and len(out["told"]) == 1, out
    told = out["told"][0]
    beside = rescue.places(world)[0]
    assert "could not save" in told and str(beside) in told, told
    assert "Voxel Worlds: could not save" in err  # the console
    assert on_file(world, 0, 0, 70) == "air" and beside.exists()  # the file lacks them
    assert len(json.loads(beside.read_text())["edits"]) == 3
    # the next open (here, in this process) puts them into the world file
    import voxel_addon
    from voxel_addon.blender import session
    voxel_addon.register()
    try:
        w = session.world(str(world))
        assert [w.get_block(x, 0, 70) for x in range(3)] == [w.get_block(0, 0, 70)] * 3
        assert not beside.exists()
    finally:
        voxel_addon.unregister()
    assert [on_file(world, x, 0, 70) for x in range(3)] == ["glass"] * 3


def test_when_nothing_can_be_written_the_world_stays_open_and_the_next_close_saves(bpy, world):
    from voxel_addon.world import rescue
    out, err = _close_under_limit(world, 256)  # the rescue file is over the limit too
    told = out["told"][0] if out["told"] else ""
    assert "could not be written anywhere" in told and out["kept_open"], out
    assert out["told_again"] == [], out  # retried without the limit: saved
    assert not any(p.exists() for p in rescue.places(world))
    assert on_file(world, 255 % 16, 255 // 16, 70) == "glass"
