"""Child of test_save_fails.py (a Blender of its own, via tests/host.py): opens the
world through the add-on's session, makes N edits that are not saved yet (a drag in
progress), then closes every world under a 4 KiB file-size limit (RLIMIT_FSIZE: the
save really fails, as on a full disk; root ignores permission bits, not this) and
prints what happened as JSON on its last line.

    save_fails_job.py WORLD N
"""
import json
import resource
import signal
import sys

import bpy  # noqa: F401 - the add-on registers into this Blender

import voxel_addon
from voxel_addon.blender import session
from voxel_addon.world import edit

path, n = sys.argv[1], int(sys.argv[2])
voxel_addon.register()
w = session.world(path)
w.idle_timeout = 1e9  # nothing leaves memory (and is saved) on its own meanwhile
changes = [(x % 16, x // 16, 70, "glass") for x in range(n)]
edit.edit(w, changes, write=False)  # shown, held until the stroke ends: not in the file
out = {"pending": len(w.unsaved_edits())}
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails with EFBIG
soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
resource.setrlimit(resource.RLIMIT_FSIZE, (4096, hard))
out["told"] = session.close_all()
resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
out["kept_open"] = sorted(session.unsaved)
out["told_again"] = session.close_all()  # no limit now: a world kept open saves
voxel_addon.unregister()
print(json.dumps(out))
