"""Blender and another process on one world file (issue 26), in the bpy module: the
other process is a real `python -m voxel_addon edit`. Its edit shows up through the
session's poll, Blender's undo leaves it alone, and a world file deleted while open
sends the next stroke's edits to the rescue file with an error, never FINISHED; the
poll lets go of a world deleted or replaced while open; a file cut short is one line."""
from __future__ import annotations

import json
import os
import subprocess

import pytest

from tests import host
from tests.blender.test_edit import _undo_to, addon, on_file  # noqa: F401 - fixture
from voxel_addon.blender import session
from voxel_addon.core.blocks import REGISTRY


def other_process_sets(path, x, y, z, name):
    env = dict(os.environ, PYTHONPATH=str(host.ROOT), VOXEL_OPENCL="0")
    r = subprocess.run(host.python_cmd("-m", "voxel_addon", "edit", "--world", path, "--set",
                                       x, y, z, name), env=env, capture_output=True, text=True,
                       timeout=120, cwd=host.ROOT)
    assert r.returncode == 0, r.stderr[-2000:]


def test_another_process_shows_up_and_undo_leaves_it(bpy, addon):  # noqa: F811
    sc, path = addon, addon.voxel.path
    w = session.world(path)
    assert bpy.ops.voxel.edit(location=(3, 4, 100), block="lamp_red") == {"FINISHED"}
    assert bpy.ops.voxel.edit(location=(5, 4, 100), block="glass") == {"FINISHED"}
    other_process_sets(path, 5, 4, 100, "stone")    # over one of Blender's voxels
    other_process_sets(path, 7, 4, 100, "sand")
    assert session._poll() == session.POLL_S       # what the timer does each second
    assert [REGISTRY[w.get_block(x, 4, 100)].name for x in (3, 5, 7)] == \
        ["lamp_red", "stone", "sand"]
    _undo_to(sc, 0)                                # Ctrl+Z twice
    assert on_file(path, 3, 4, 100) == "air"        # Blender's own stroke undone
    assert on_file(path, 5, 4, 100) == "stone"      # the other process's edits stay
    assert on_file(path, 7, 4, 100) == "sand"


def test_a_deleted_world_sends_the_stroke_to_the_rescue_file(bpy, addon):  # noqa: F811
    from voxel_addon.world import rescue
    path = addon.voxel.path
    assert bpy.ops.voxel.edit(location=(3, 4, 100), block="lamp_red") == {"FINISHED"}
    os.remove(path)
    with pytest.raises(RuntimeError, match="deleted or moved.*unsaved edits are in"):
        bpy.ops.voxel.edit(location=(6, 4, 100), block="glass")
    beside = rescue.places(path)[0]
    edits = json.loads(beside.read_text())["edits"]
    assert [6, 4, 100, "glass", 0] in edits
    assert not session.is_open(path)                # let go: nothing more goes to it
    with pytest.raises(RuntimeError, match="does not exist"):
        bpy.ops.voxel.edit(location=(7, 4, 100), block="glass")


def test_a_world_path_through_a_changed_symlink_finds_the_new_world(bpy, tmp_path, monkeypatch):
    """The session remembers a path's resolution (it is asked on every redraw), but
    not past KEY_S: a symlink pointed at another world while Blender runs is seen."""
    from voxel_addon.world import World
    for name, seed in (("a", 3), ("b", 4)):
        World.create(tmp_path / f"{name}.sqlite", seed=seed).close()
    link = tmp_path / "current.sqlite"
    link.symlink_to(tmp_path / "a.sqlite")
    monkeypatch.setattr(session, "KEY_S", 0.05)
    try:
        assert session.world(str(link)).seed == 3
        link.unlink()
        link.symlink_to(tmp_path / "b.sqlite")
        import time
        time.sleep(0.1)
        assert session.world(str(link)).seed == 4
    finally:
        session.close_all()


def test_a_world_cut_short_while_open_is_one_line_never_a_traceback(bpy, addon, capsys):  # noqa: F811
    """Another program truncates the open world file: a stroke before the poll looked
    says nothing of it was applied; the poll lets the world go, saying so once (not
    each second); then a stroke and a bake name the file not readable."""
    sc, path = addon, addon.voxel.path
    assert bpy.ops.voxel.edit(location=(3, 4, 100), block="lamp_red") == {"FINISHED"}
    session.close(path)
    session.world(path)
    with open(path, "r+b") as f:
        f.truncate(1000)
    with pytest.raises(RuntimeError) as e:
        bpy.ops.voxel.edit(location=(6, 4, 100), block="glass")
    msg = str(e.value)
    assert "Traceback" not in msg and "damaged" in msg and "nothing of this stroke" in msg, msg
    capsys.readouterr()
    session._poll()
    session._poll()
    assert not session.is_open(path)
    said = capsys.readouterr().err
    assert said.count("was damaged") == 1 and "Traceback" not in said, said
    with pytest.raises(RuntimeError) as e:
        bpy.ops.voxel.edit(location=(6, 4, 100), block="glass")
    assert "Traceback" not in str(e.value) and "not a readable world file" in str(e.value)
    sc.voxel_bake.region_min, sc.voxel_bake.region_max = (0, 0), (16, 16)
    with pytest.raises(RuntimeError) as e:
        bpy.ops.voxel.bake()
    assert "Traceback" not in str(e.value) and "not a readable world file" in str(e.value), str(e.value)
    session.close_all()


def test_a_world_replaced_while_open_is_let_go_and_the_new_one_shown(bpy, addon, tmp_path):  # noqa: F811
    """Another program moves another world over the open file: within a poll the
    session lets ours go (its unsaved edits to the rescue file) and the next look-up
    opens the new world; the new file reads as itself, not through our old -wal."""
    from voxel_addon.world import World, rescue
    path = addon.voxel.path
    w = session.world(path)
    assert bpy.ops.voxel.edit(location=(3, 4, 100), block="lamp_red") == {"FINISHED"}
    w.set_block(6, 4, 100, "glass")          # not yet written (a drag's part)
    World.create(tmp_path / "other.sqlite", seed=99, generator="flat").close()
    os.replace(tmp_path / "other.sqlite", path)
    session._poll()
    assert not session.is_open(path)
    assert [6, 4, 100, "glass", 0] in json.loads(rescue.places(path)[0].read_text())["edits"]
    assert on_file(path, 3, 4, 100) is None   # the other world's: no chunk there
    assert session.world(path).seed == 99


def test_a_new_world_where_one_was_deleted_while_open_is_new(bpy, addon):  # noqa: F811
    """The user deletes the open world's .sqlite and makes a New one at the same
    path: the poll lets the old one go, so New makes a new world (not the deleted
    one still in memory, whose edits would go to a file nobody sees)."""
    sc, path = addon, addon.voxel.path
    assert bpy.ops.voxel.edit(location=(3, 4, 100), block="lamp_red") == {"FINISHED"}
    os.remove(path)
    session._poll()
    assert not session.is_open(path)
    sc.voxel.seed = 8
    assert bpy.ops.voxel.world_new() == {"FINISHED"}
    assert session.world(path).seed == 8 and on_file(path, 3, 4, 100) is None


def test_undo_of_a_stroke_never_writes_into_a_world_moved_over_its_file(bpy, addon, tmp_path):  # noqa: F811
    """Blocks removed (now air), the file replaced by another world: Ctrl+Z must not put
    our blocks back into theirs (wherever theirs is air too), and says why."""
    from voxel_addon.world import World
    sc, path = addon, addon.voxel.path
    session.world(path)
    assert bpy.ops.voxel.edit(location=(3, 4, 100), block="stone") == {"FINISHED"}
    assert bpy.ops.voxel.edit(location=(3, 4, 100), block="air") == {"FINISHED"}
    with World.create(tmp_path / "other.sqlite", seed=99, generator="flat") as w:
        w.chunk_at(0, 0)
    os.replace(tmp_path / "other.sqlite", path)
    session._poll()                                 # ours let go; theirs opens next
    _undo_to(sc, 1)
    assert on_file(path, 3, 4, 100) == "air"        # theirs, untouched
    session.close_all()


def test_the_views_stream_meeting_a_damaged_file_is_one_line_and_lets_go(bpy, addon, tmp_path):  # noqa: F811
    """LiveView._file_failed: a failure of the view's stream (a save on eviction, a
    read) that says the world file is damaged is the panel's one line and the
    session lets the world go (the next frame opens the file anew), before the poll
    sees it, its unsaved edits in the rescue file; any other failure is a bug (None:
    its traceback goes to the console)."""
    import sqlite3
    from voxel_addon.blender.liveview.feed import Feed
    from voxel_addon.blender.liveview.view import LiveView
    path = addon.voxel.path
    junk = tmp_path / "junk.sqlite"
    junk.write_bytes(b"not a world " * 400)
    with pytest.raises(sqlite3.DatabaseError) as err:  # a real damaged file's error
        sqlite3.connect(junk).execute("SELECT * FROM chunks")
    from voxel_addon.world import rescue
    w = session.world(path)
    w.set_block(6, 4, 100, "glass")          # not yet written (a drag's part)
    lv = LiveView()
    lv.feed = Feed(path, w, 1)
    try:
        said = lv._file_failed(err.value)
        assert said and "damaged" in said and "\n" not in said, said
        assert not session.is_open(path) and "1 unsaved edits are in" in said, said
        assert [6, 4, 100, "glass", 0] in json.loads(rescue.places(path)[0].read_text())["edits"]
        again = lv._file_failed(err.value)  # a redraw before the next frame's look-up
        assert "damaged" in again and "\n" not in again, again
        assert lv._file_failed(ValueError("a bug")) is None
    finally:
        lv.feed.close()
        session.close_all()

