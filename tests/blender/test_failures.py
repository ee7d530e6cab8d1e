"""Blender operators that write, on a world file another process holds locked (a
real `BEGIN IMMEDIATE` in a child process, VOXEL_LOCK_TIMEOUT short): each ends with
one ERROR report naming the failure and what was kept, never a Python traceback;
an import that created its world file and failed removes it (issue 26). Export .glb
that cannot write is one line and keeps the earlier file; a failed close names its
cause."""
from __future__ import annotations

import sqlite3
import subprocess
import sys

import numpy as np
import pytest

from tests.formats import mcfiles as mc
from tests.formats import voxfiles as vf


@pytest.fixture
def world(tmp_path):
    from voxel_addon.world import World
    path = tmp_path / "w.sqlite"
    with World.create(path, seed=3, generator="flat", loader=False) as w:
        w.chunk_at(0, 0)
    return path


@pytest.fixture
def locked(world, monkeypatch):
    """WORLD held by another process's write transaction while the test runs."""
    monkeypatch.setenv("VOXEL_LOCK_TIMEOUT", "0.2")
    p = subprocess.Popen(
        [sys.executable, "-c", "import sqlite3, sys, time\n"
         "db = sqlite3.connect(sys.argv[1], isolation_level=None)\n"
         "db.execute('BEGIN IMMEDIATE'); print('held', flush=True); time.sleep(120)",
         str(world)], stdout=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "held"
    yield world
    p.kill()
    p.wait()


def _one_line(exc) -> str:
    msg = str(exc.value)
    assert "Traceback" not in msg and "locked by another program" in msg, msg
    return msg


def test_writing_operators_report_one_line(addon, locked):
    bpy = addon
    from voxel_addon.blender import session
    from voxel_addon.core import colors
    bpy.context.scene.voxel.path = str(locked)
    session.world(str(locked))  # opened before: reading needs no lock
    with pytest.raises(RuntimeError) as e:
        bpy.ops.voxel.edit(location=(3, 4, 70), block="glass")
    assert "shown but not in the file" in _one_line(e)
    s = bpy.context.scene.voxel_bake
    s.region_min, s.region_max = (160, 160), (200, 200)  # not generated yet
    with pytest.raises(RuntimeError) as e:
        bpy.ops.voxel.generate()
    _one_line(e)
    src = locked.parent / "m.vox"
    src.write_bytes(vf.file(vf.model((2, 2, 2), [(0, 0, 0, 5), (1, 1, 1, 9)])
                            + vf.rgba(np.full((255, 3), 77))))
    with pytest.raises(RuntimeError) as e:
        bpy.ops.import_scene.voxel_vox(filepath=str(src), location=(0, 0, 80))
    assert "nothing of this import was written" in _one_line(e)
    with pytest.raises(RuntimeError) as e:
        bpy.ops.voxel.world_recreate()
    _one_line(e)
    db = sqlite3.connect(f"file:{locked}?mode=ro", uri=True)
    assert db.execute("SELECT COUNT(*) FROM meta WHERE key=?", (colors.KEY,)).fetchone()[0] == 0
    assert db.execute("SELECT COUNT(*) FROM edits").fetchone()[0] == 0
    db.close()


def test_a_failed_import_removes_the_world_it_created(addon, tmp_path):
    bpy = addon
    save = tmp_path / "Old World"
    old = mc.nbt({"DataVersion": 1343, "Level": {"xPos": 0, "zPos": 0}})
    mc.write_region(save / "region", {(x, 0): old for x in range(3)})
    bpy.context.scene.voxel.path = ""
    with pytest.raises(RuntimeError) as e:
        bpy.ops.import_scene.voxel_minecraft(filepath=str(save / "region" / "r.0.0.mca"))
    assert "1.13" in str(e.value) and "Traceback" not in str(e.value)
    assert sorted(p.name for p in (save / "region").iterdir()) == ["r.0.0.mca"]  # no r.0.0.sqlite*
    assert bpy.context.scene.voxel.path == ""


def test_export_glb_that_cannot_be_written_is_one_line_and_keeps_the_old_file(addon, world):
    """A file-size limit (as a full disk: the write fails) during Export .glb: one line,
    the .glb there before untouched, no half-written file left beside it; once it
    can write, the export replaces it whole."""
    import resource
    import signal
    bpy = addon
    out = world.parent / "my bake.glb"
    out.write_bytes(b"the user's earlier export")
    sc = bpy.context.scene
    sc.voxel.path, sc.voxel_bake.glb_path = str(world), str(out)
    sc.voxel_bake.region_min, sc.voxel_bake.region_max = (0, 0), (16, 16)
    from voxel_addon.blender import session
    session.world(str(world)).chunk_at(0, 0)  # opened and read before: only the export writes
    old = resource.getrlimit(resource.RLIMIT_FSIZE)
    sig = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past it fails (EFBIG)
    resource.setrlimit(resource.RLIMIT_FSIZE, (4096, old[1]))
    try:
        with pytest.raises(RuntimeError) as e:
            bpy.ops.voxel.export_glb()
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, old)
        signal.signal(signal.SIGXFSZ, sig)
    msg = str(e.value)
    assert "Traceback" not in msg and "file-size limit" in msg and "unchanged" in msg, msg
    assert out.read_bytes() == b"the user's earlier export"
    assert sorted(p.name for p in world.parent.iterdir() if "glb" in p.name) == ["my bake.glb"]
    sc.voxel_bake.glb_path = str(world.parent)  # a folder: no file name
    with pytest.raises(RuntimeError, match="not a file name") as e:
        bpy.ops.voxel.export_glb()
    assert "Traceback" not in str(e.value)
    sc.voxel_bake.glb_path = str(out)
    assert bpy.ops.voxel.export_glb() == {"FINISHED"}
    assert out.read_bytes()[:4] == b"glTF"
    assert sorted(p.name for p in world.parent.iterdir() if "glb" in p.name) == ["my bake.glb"]


def test_a_failed_close_names_the_cause_and_says_no_edit_was_lost(addon, locked):
    """Closing a world whose only unsaved data is generated terrain, on a file another
    program holds: the cause in words, and that the user's edits are all in the file."""
    from voxel_addon.blender import session
    session.world(str(locked)).chunk_at(5, 5)  # generated here, not yet stored
    msg = session.close(str(locked))
    assert "locked by another program" in msg and "all your edits were saved" in msg, msg
