"""The voxel.edit operator and the stroke journal in the bpy module (issue 13).

The bpy module has no window, so it cannot undo: here the handlers are called the way
Blender calls them after it restored `scene.voxel_edit.step`; tests/gui/test_edit_tool.py
(the real Blender GUI) checks Blender's own Ctrl+Z / Ctrl+Shift+Z."""
from __future__ import annotations

import random

import pytest

from voxel_addon.blender import strokes
from voxel_addon.core.blocks import REGISTRY
from voxel_addon.storage import WorldFile


def on_file(path, x, y, z):
    """The block at (x, y, z) as a fresh reader of the world file sees it."""
    wf = WorldFile(path, readonly=True)
    try:
        got = wf.read_chunk((x >> 4, y >> 4))
        return None if got is None else REGISTRY[int(got[0][x & 15, y & 15, z])].name
    finally:
        wf.close()


@pytest.fixture
def addon(bpy, tmp_path):
    import voxel_addon
    voxel_addon.register()
    sc = bpy.context.scene
    sc.voxel.path, sc.voxel.seed, sc.voxel.generator = str(tmp_path / "w.sqlite"), 3, "flat"
    assert bpy.ops.voxel.world_new() == {"FINISHED"}
    sc.voxel_edit.step = 0
    yield sc
    for k in ("voxel", "voxel_edit"):   # leave the scene as other tests expect it
        sc.property_unset(k)
    voxel_addon.unregister()


def generated(sc, x, y, z):
    from voxel_addon.blender import session
    return REGISTRY[session.world(sc.voxel.path).get_block(x, y, z)].name


def _undo_to(sc, step):
    """What Blender does on Ctrl+Z: restore the scene (here: its step), then undo_post."""
    sc.voxel_edit.step = step
    strokes.on_undo_redo(sc)


def test_edit_operator_writes_the_file_before_it_returns(bpy, addon):
    sc, path = addon, addon.voxel.path
    assert on_file(path, 3, 4, 60) is None  # the chunk is not in the file yet
    ground = generated(sc, 3, 4, 60)
    assert bpy.ops.voxel.edit(location=(3, 4, 60), block="lamp_red") == {"FINISHED"}
    assert on_file(path, 3, 4, 60) == "lamp_red"
    s1 = sc.voxel_edit.step
    assert bpy.ops.voxel.edit(location=(3, 4, 60), block="air", size=3, shape="SPHERE") == {"FINISHED"}
    assert on_file(path, 3, 4, 60) == "air" and on_file(path, 4, 4, 60) == "air"
    s2 = sc.voxel_edit.step
    assert s2 != s1
    _undo_to(sc, s1)                     # Ctrl+Z
    assert on_file(path, 3, 4, 60) == "lamp_red"
    _undo_to(sc, 0)                      # Ctrl+Z
    assert on_file(path, 3, 4, 60) == ground
    _undo_to(sc, s2)                     # two redos at once (undo history jump)
    assert on_file(path, 3, 4, 60) == "air" and on_file(path, 4, 4, 60) == "air"


def test_bad_input_is_one_line_and_changes_nothing(bpy, addon):
    path = addon.voxel.path
    assert bpy.ops.voxel.edit(location=(0, 0, 10), block="glass") == {"FINISHED"}
    step = addon.voxel_edit.step
    for kw in ({"block": "unobtainium"}, {"location": (0, 0, 256)}, {"location": (0, 0, -1)},
               {"box": True, "corner": (200, 200, 200)}):
        args = {"location": (0, 0, 10), "block": "dirt", **kw}
        with pytest.raises(RuntimeError, match=r"^Error: [^\n]+\n?$"):
            bpy.ops.voxel.edit(**args)
    assert on_file(path, 0, 0, 10) == "glass" and addon.voxel_edit.step == step
    # the same block again changes nothing and records no step
    assert bpy.ops.voxel.edit(location=(0, 0, 10), block="glass") == {"CANCELLED"}
    assert addon.voxel_edit.step == step


def test_box_and_brush(bpy, addon):
    path = addon.voxel.path
    assert bpy.ops.voxel.edit(location=(1, 1, 100), box=True, corner=(3, 2, 101), block="glass") == {"FINISHED"}
    assert all(on_file(path, x, y, z) == "glass" for x in (1, 2, 3) for y in (1, 2) for z in (100, 101))
    assert on_file(path, 4, 1, 100) == "air"
    assert bpy.ops.voxel.edit(location=(30, 30, 130), size=2, block="sand") == {"FINISHED"}
    assert on_file(path, 31, 31, 131) == "sand" and on_file(path, 29, 30, 130) == "air"
    # remove (the Redo panel's checkbox): the same cells cleared, whatever the block
    assert bpy.ops.voxel.edit(location=(30, 30, 130), size=2, block="sand", remove=True) == {"FINISHED"}
    assert on_file(path, 31, 31, 131) == "air" and on_file(path, 30, 30, 130) == "air"


def test_random_strokes_undo_redo_jumps_equal_a_model(bpy, addon):
    """Blender's history as a model (a list of states, a cursor; a new step after undo
    drops the redo tail); the file must equal the model's state after every move."""
    sc, path = addon, addon.voxel.path
    rng = random.Random(4)
    cells = [(x, y, 40) for x in range(14, 19) for y in range(0, 3)]   # across a chunk edge
    blank = {c: generated(sc, *c) for c in cells}
    hist, cur = [(0, dict(blank))], 0        # (step, state)
    names = ["stone", "glass", "lamp_blue", "air", "water"]
    for _ in range(60):
        r = rng.random()
        if r < 0.5:
            c, b = rng.choice(cells), rng.choice(names)
            state = dict(hist[cur][1])
            if state[c] == b:
                continue
            assert bpy.ops.voxel.edit(location=c, block=b) == {"FINISHED"}
            state[c] = b
            del hist[cur + 1:]
            hist.append((sc.voxel_edit.step, state))
            cur += 1
        else:
            cur = rng.randrange(len(hist))       # any undo/redo jump
            _undo_to(sc, hist[cur][0])
        for c in cells:
            assert (on_file(path, *c) or blank[c]) == hist[cur][1][c], (c, cur)


def test_journal_routes_through_the_common_ancestor():
    j = strokes.Journal()
    a = j.push(strokes.empty())
    b = j.push(strokes.empty())
    j.applied = a                   # undo b
    c = j.push(strokes.empty())    # new branch
    assert j.route(b) == [("undo", c), ("redo", b)]
    assert j.route(0) == [("undo", c), ("undo", a)]
    j.applied = 0
    assert j.route(c) == [("redo", a), ("redo", c)]


def test_tool_and_palette_registered(bpy, addon):
    from bl_ui.space_toolsystem_toolbar import VIEW3D_PT_tools_active as P
    from voxel_addon.blender.ui import edit

    def flat(items):
        for t in items:
            if hasattr(t, "idname"):      # a ToolDef (itself a named tuple)
                yield t
            elif isinstance(t, tuple):     # a group of tools
                yield from flat(t)
    assert "voxel.edit_tool" in [t.idname for t in flat(P._tools["OBJECT"])]
    items = edit._palette(None, bpy.context)
    assert [i[0] for i in items] == REGISTRY.names()[1:]
    # each block's icon is its own texture (icon ids exist only with a UI: real Blender)
    import numpy as np
    from voxel_addon import textures
    icons = edit.palette_icons()
    for name in ("lamp_red", "glass", "flowers"):
        px = np.array(icons[name].icon_pixels_float).reshape(32, 32, 4)[::-2, ::2]
        assert np.allclose(px * 255, textures.image(REGISTRY[name].texture("-y"))[0], atol=0.5)
    addon.voxel_edit.block = "lamp_yellow"
    assert addon.voxel_edit.block == "lamp_yellow"


def test_register_twice_leaves_no_handler(bpy):
    import voxel_addon
    before = [len(h) for h in (bpy.app.handlers.undo_post, bpy.app.handlers.redo_post)]
    for _ in range(3):
        voxel_addon.register()
        voxel_addon.unregister()
    assert [len(h) for h in (bpy.app.handlers.undo_post, bpy.app.handlers.redo_post)] == before


def test_hover_outline_geometry(bpy, addon):
    from voxel_addon.blender.ui.edit import outline
    from voxel_addon.core.ray import Hit
    top = Hit("hit", (5, 6, 10), (0, 0, 1), 3.0, 1)
    pts = outline(top)
    assert len(pts) == 8
    assert all(p[2] == pytest.approx(11.004) for p in pts)
    assert {(p[0], p[1]) for p in pts} == {(5, 6), (6, 6), (6, 7), (5, 7)}
    side = Hit("hit", (5, 6, 10), (-1, 0, 0), 3.0, 1)
    assert all(p[0] == pytest.approx(4.996) for p in outline(side))
    # a size-3 brush covers the 3x3 cells around the hovered one; size 2 grows to +x +y
    assert {(p[0], p[1]) for p in outline(top, size=3)} == {(4, 5), (7, 5), (7, 8), (4, 8)}
    assert {(p[0], p[1]) for p in outline(top, size=2)} == {(5, 6), (7, 6), (7, 8), (5, 8)}
    box = outline(top, corner=(3, 6, 11))   # box mode: from the first corner to the new cell
    xs, zs = {p[0] for p in box}, {p[2] for p in box}
    assert len(box) == 24 and xs == {3, 6} and zs == {11, 12}


def test_journal_trim_keeps_what_blender_can_reach():
    j = strokes.Journal()
    chain = [j.push(strokes.empty()) for _ in range(50)]
    j.applied = chain[39]                      # ten undos
    dead = chain[40:]
    new = [j.push(strokes.empty()) for _ in range(3)]   # a new branch: the old redo tail is gone
    j.applied = new[0]                         # two undos on the new branch
    j.trim(5)
    assert not set(dead) & set(j.nodes)
    assert chain[34] not in j.nodes and chain[35] in j.nodes   # five strokes above new[0]
    assert j.route(new[2]) == [("redo", new[1]), ("redo", new[2])]
    assert j.route(chain[35]) == [("undo", new[0])] + [("undo", s) for s in chain[39:35:-1]]
