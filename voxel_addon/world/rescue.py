"""Edits that could not be saved, kept in a small file until the world opens again.

When a world cannot write its file (disk full, a file-size limit, a drive gone) its
unsaved edits (World.unsaved_edits: the user's blocks; chunks and light come back
from the seed) go into `<world file>.unsaved.json` beside it, or, when that cannot be
written either, into the temporary folder under a name made from the world's path.
`restore` applies such a file to the world when it is opened next (as one stroke:
light and meshes follow, one transaction) and removes it once the world file holds
the edits.
"""
from __future__ import annotations

import hashlib
import json
import os
import tempfile
from pathlib import Path

FORMAT = "voxel-worlds unsaved edits 1"


def places(world_path) -> list[Path]:
    """Where the unsaved edits of the world at WORLD_PATH go, in order of preference."""
    p = Path(os.path.realpath(world_path))
    tag = hashlib.sha1(str(p).encode()).hexdigest()[:12]
    return [p.with_name(p.name + ".unsaved.json"),
            Path(tempfile.gettempdir()) / f"voxel-worlds-unsaved-{tag}.json"]


def write(world) -> Path:
    """Write WORLD's unsaved edits to the first place that takes them; its path.
    Raises OSError when none does."""
    from ..core.blocks import REGISTRY
    edits = [[x, y, z, REGISTRY[b].name, d] for x, y, z, b, d in world.unsaved_edits()]
    errors = []
    for path in places(world.file.path):
        text = json.dumps({"format": FORMAT, "world": os.path.realpath(world.file.path),
                           "seed": world.seed,  # an earlier rescue not restored yet stays first
                           "edits": _read(path) + edits})
        tmp = path.with_name(path.name + ".tmp")
        try:
            with open(tmp, "w", encoding="utf-8") as f:
                f.write(text)
                f.flush()
                os.fsync(f.fileno())
            os.replace(tmp, path)
            return path
        except OSError as e:
            errors.append(f"{path}: {e.strerror or e}")
            try:
                tmp.unlink()
            except OSError:
                pass
    raise OSError("; ".join(errors))


def _read(path: Path) -> list:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return []
    return data.get("edits", []) if data.get("format") == FORMAT else []


def restore(world) -> tuple[int, list[Path]]:
    """Apply every rescue file of WORLD (edits in the order they were made) and
    remove them once saved; (edits applied, files read)."""
    from . import edit
    found = [p for p in places(world.file.path) if p.exists()]
    if not found or world.readonly:
        return 0, []
    last = {}  # the newest edit of each voxel wins
    for p in found:
        for x, y, z, name, d in _read(p):
            last.pop((x, y, z), None)
            last[(x, y, z)] = (name, d)
    if last:
        edit.edit(world, [(x, y, z, name, d) for (x, y, z), (name, d) in last.items()], write=True)
        world.settle()  # in the file before the rescue files go
    for p in found:
        p.unlink()
    return len(last), found


def at_exit(world, error: Exception) -> None:
    """The interpreter exits and WORLD could not save (World.at_exit): one line on
    stderr, and its unsaved edits written where `restore` finds them, unless the
    world's folder is gone with its file (a temporary folder cleaned up: nobody opens
    it again)."""
    import sys
    from ..core.errors import cause
    path = world.file.path
    n = len(world.unsaved_edits())
    if not n:
        return  # generated terrain and light only: they come back from the seed
    msg = f"could not save {path}: {cause(error, path) or error}"
    if not Path(os.path.realpath(path)).parent.is_dir():
        msg += f"; its folder is gone with its {n} unsaved edits"
    else:
        try:
            msg += f"; its {n} unsaved edits are in {write(world)} (Blender applies them when it opens the world)"
        except OSError as e:
            msg += f"; its {n} unsaved edits could not be written anywhere ({e})"
    print(f"Voxel Worlds: {msg}", file=sys.stderr, flush=True)
