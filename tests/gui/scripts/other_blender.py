"""The second Blender of two_blenders.py (background mode, run by it): open the same
world, see A's first stroke, stroke twice (stone over A's lamp, glass), wait for A's second stroke (the session's poll,
called by hand: a background script runs no timers), undo its second stroke."""
import json
import sys
import time
from pathlib import Path

import bpy

world, out, paths = sys.argv[sys.argv.index("--") + 1:][:3]
out = Path(out)
sys.path[:0] = json.loads(paths)  # Blender ignores PYTHONPATH
import voxel_addon  # noqa: E402 - the repo's
from voxel_addon.blender import session, strokes  # noqa: E402
from voxel_addon.core.blocks import REGISTRY  # noqa: E402

voxel_addon.register()
sc = bpy.context.scene
sc.voxel.path = world
w = session.world(world)
res = {"sees_a1": REGISTRY[w.get_block(3, 3, 100)].name}
res["b1"] = sorted(bpy.ops.voxel.edit(location=(3, 3, 100), block="stone"))  # over A's lamp
step = sc.voxel_edit.step
res["b2"] = sorted(bpy.ops.voxel.edit(location=(4, 3, 100), block="glass"))
t0 = time.monotonic()
while time.monotonic() - t0 < 60 and not (out / "a2.done").exists():
    time.sleep(0.1)
session._poll()
res["sees_a2"] = REGISTRY[w.get_block(5, 3, 100)].name
sc.voxel_edit.step = step
strokes.on_undo_redo(sc)      # B's Ctrl+Z: its glass goes, A's sand stays
res["after_undo"] = [REGISTRY[w.get_block(*c)].name for c in ((3, 3, 100), (5, 3, 100),
                                                               (4, 3, 100))]
voxel_addon.unregister()
(out / "b.json").write_text(json.dumps(res))
