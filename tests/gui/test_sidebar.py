"""The installed extension in the real Blender's window: the sidebar gets a Voxel tab
and, clicked, shows the add-on's panels (checked in the screenshots' pixels).
The "voxel" screenshot is docs/images/blender_sidebar.png."""
from __future__ import annotations

import numpy as np

from tests.gui import pixels


def test_sidebar_shows_the_voxel_tab_and_panels(gui, ext_zip):
    res = gui("sidebar.py", zip=str(ext_zip))
    r = res.result
    assert r["install"] == ["FINISHED"] and r["enabled"], r
    # the tab strip gained exactly one label (the extension's category)
    assert len(r["tabs_after"]) == len(r["tabs_before"]) + 1 >= 2, r
    rect, scale, back = r["ui"], r["scale"], r["back"]
    before, voxel = res.image("before"), res.image("voxel")
    tabs = pixels.sidebar_tabs(voxel, rect, scale)  # the same labels (the active one
    assert len(tabs) == len(r["tabs_after"]) and all(  # is drawn a pixel differently)
        abs(a[0] - b[0]) <= 2 and abs(a[1] - b[1]) <= 2 for a, b in zip(tabs, r["tabs_after"]))
    # after the click: one panel box per top-level Voxel panel, each with a header label
    blocks = pixels.panel_blocks(voxel, rect, scale, back)
    assert r["panels"] and len(blocks) == len(r["panels"]), (blocks, r["panels"])
    x0 = rect[0]
    for top, bottom in blocks:
        header = (top, top + round(24 * scale))
        assert pixels.has_text(voxel, header, (x0 + round(30 * scale), x0 + round(150 * scale))), \
            f"panel at rows {top}..{bottom} has no header label"
    # and the sidebar shows something else than before (the Item tab's one panel)
    assert len(pixels.panel_blocks(before, rect, scale, back)) == 1
    x, r0, x1, r1 = pixels.rect_rows(rect, before.shape[0])
    assert np.abs(voxel[r0:r1, x:x1].astype(int) - before[r0:r1, x:x1]).mean() > 3
