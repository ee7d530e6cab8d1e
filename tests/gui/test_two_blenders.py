"""Two Blenders on one world file (issue 26): the window's Blender and a second one in
background mode (scripts/two_blenders.py starts it) see each other's strokes, the
live view remeshes what the other changed, and each undo leaves the other's alone."""
from __future__ import annotations

from pathlib import Path

SCRIPTS = Path(__file__).with_name("scripts")


def test_two_blenders_see_each_others_strokes(gui, tmp_path):
    from voxel_addon.world import World
    path = tmp_path / "w.sqlite"
    with World.create(path, seed=3, generator="flat", loader=False) as w:
        w.chunk_at(0, 0)
    out = tmp_path / "b"
    out.mkdir()
    res = gui("two_blenders.py", timeout=150, world=str(path), out=str(out),
              other=str(SCRIPTS / "other_blender.py"))
    r = res.result
    assert r["shown"], r
    assert r["a1"] == ["FINISHED"] and r["a2"] == ["FINISHED"], r
    assert r["b_code"] == 0, r["b"]
    b = r["b"]
    assert b["sees_a1"] == "lamp_red" and b["b1"] == b["b2"] == ["FINISHED"], b
    assert b["sees_a2"] == "sand", b                        # B took in A's later stroke
    assert b["after_undo"] == ["stone", "sand", "air"], b   # B's undo: its glass only
    assert r["a_sees_b"] == ["stone", "glass"] and r["remeshed"], r  # by A's timer alone
    assert r["a_after_b_undo"] == "air", r
    # A's undo: its sand goes; its lamp was under B's stone, which stays
    assert r["a_after_undo"] == ["stone", "air", "air"], r
