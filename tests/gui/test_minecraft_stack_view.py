"""The live view of a Minecraft import with the world's resource stack (issue 30 d):
model blocks with the stack's sprites (the test pack's poppy: a red bloom on a cross),
against the same build imported without a stack (today's look)."""
from __future__ import annotations

from tests.mcres.builds import imported


def _red(img, rect):
    x, y, wd, ht = rect
    h = img.shape[0]
    v = img[h - (y + ht):h - y, x:x + wd].astype(int).reshape(-1, 3)
    return int(((v[:, 0] > 60) & (v[:, 0] > 3 * v[:, 1]) & (v[:, 0] > 3 * v[:, 2])).sum())


def test_model_blocks_in_the_live_view(gui, tmp_path):
    paths, _ = imported(tmp_path)
    worlds = {name: str(p) for name, p in paths.items()}
    res = gui("minecraft_stack_view.py", timeout=400, **worlds)
    r = res.result
    for name in worlds:
        st = r["status"][name]
        assert st["error"] in (None, "") and st["drawn"] >= st["wanted"] > 0, st
    red = {n: _red(res.image(n), r["rect"]) for n in worlds}
    assert red["with"] > 200 and red["without"] < red["with"] / 4, red
