"""The live view while another program changes its world file under it (Show on, the
real Blender under Xvfb, scripts/file_changes.py): another world moved over it is
drawn instead, a deleted or damaged file stops the drawing with one line in the
View panel, strokes afterwards are one line or go into the file at the path (never
into the old one), and the console shows no traceback."""
from __future__ import annotations

import numpy as np

from tests.gui import pixels

SEEDS = {"a": 3, "b": 4, "c": 5}
TOPS = {"a": "grass", "b": "sand", "c": "dirt"}


def _world(path, key):
    from voxel_addon.world import World
    layers = [["stone", 60], ["dirt", 3], [TOPS[key], 1]]
    with World.create(path, seed=SEEDS[key], generator="flat", params={"layers": layers},
                      loader=False) as w:
        w.chunk_at(0, 0)


def _on_file(path, x, y, z):
    from voxel_addon.core.blocks import REGISTRY
    from voxel_addon.storage import WorldFile
    wf = WorldFile(path, readonly=True)
    try:
        blocks, _ = wf.read_chunk((x >> 4, y >> 4))
        return None if blocks is None else REGISTRY[int(blocks[x & 15, y & 15, z])].name
    finally:
        wf.close()


def _centre(res, name):
    """The mean colour of the middle of the 3D view's region (the sidebar is on its right)."""
    x, y, w, h = res.result["region"]
    img = res.image(name).astype(int)
    x0, r0, x1, r1 = pixels.rect_rows([x + w // 4, y + h // 3, w // 3, h // 3], img.shape[0])
    return img[r0:r1, x0:x1].reshape(-1, 3).mean(0)


def test_the_view_follows_its_world_file_replaced_deleted_damaged(gui, tmp_path):
    paths = {k: tmp_path / f"{k}.sqlite" for k in SEEDS}
    for k, p in paths.items():
        _world(p, k)
    path, old, new = paths["a"], tmp_path / "old.sqlite", tmp_path / "new.sqlite"
    res = gui("file_changes.py", timeout=150, world=str(path), b=str(paths["b"]),
              c=str(paths["c"]), old=str(old), new=str(new), **{f"seed_{k}": s for k, s in SEEDS.items()})
    r = res.result
    # (Blender prints our one-line reports as "Error: ..."; a traceback is a bug)
    assert "Traceback" not in res.log and "Exception" not in res.log, res.log[-4000:]
    assert r["shown"]["seed"] == 3 and r["shown"]["problem"] is None, r["shown"]
    # replaced: the new world drawn; a stroke goes into it, not into the old file
    rep = r["replaced"]
    assert rep["seed"] == 4 and rep["problem"] is None and rep["open_seed"] == 4, rep
    assert rep["stroke"] == ["FINISHED"], rep
    assert _on_file(new, 3, 3, 100) == "lamp_red" and _on_file(old, 3, 3, 100) in (None, "air")
    grass, sand, back = _centre(res, "shown"), _centre(res, "replaced"), _centre(res, "back")
    assert np.abs(grass - sand).max() > 30, (grass, sand)
    assert np.abs(back - sand).max() > 20, (back, sand)
    # deleted, damaged: nothing drawn (Blender's background), one line in the panel
    for name in ("deleted", "damaged", "damaged_after"):
        c = _centre(res, name)
        assert np.ptp(c) < 6 and c.max() < 90, (name, c)
    dele = r["deleted"]
    assert dele["problem"] and "\n" not in dele["problem"], dele
    assert not dele["exists"] and isinstance(dele["stroke"], str), dele
    assert "Traceback" not in dele["stroke"] and "does not exist" in dele["stroke"], dele
    assert r["back"]["seed"] == 5, r["back"]
    dam = r["damaged"]
    for said in (dam["problem"], dam["stroke"]):  # (the file opened anew: not readable)
        assert isinstance(said, str) and said.count("\n") <= 1, dam
        assert "not a readable world file" in said and "Traceback" not in said, dam
    assert r["damaged_after"]["problem"] == dam["problem"], r["damaged_after"]
    # the panel: the sentence without the folder, in lines that fit the sidebar
    for case in (dele, dam):
        assert " ".join(case["lines"]) == case["problem"].replace(f"{tmp_path}/", ""), case
        assert all(len(ln) <= 48 for ln in case["lines"]), case
