"""animate: a .blend's scene camera over its frames (and the voxel day cycle), as the
Blender operator Render Voxel Animation does, through the pipeline on the moderngl
device (as `render`) into DIR/frame_NNNN.png; in this process or on a Dask cluster."""
from __future__ import annotations

import hashlib
import os
import threading
import time
from pathlib import Path

from ..core.errors import VoxelError
from .common import Progress, add_world, note, write_out


def add_parser(sub):
    from .. import cluster
    p = sub.add_parser("animate", help="render a .blend's camera animation into PNG frames "
                                       "(headless OpenGL; bpy reads the .blend)")
    add_world(p)
    p.add_argument("--blend", type=Path, required=True, metavar="F.blend",
                   help="its scene camera, frame range, size and Voxel View settings")
    p.add_argument("--frames", type=int, nargs=2, metavar=("A", "B"),
                   help="frames A..B (default the scene's frame range)")
    p.add_argument("--out", type=Path, required=True, metavar="DIR",
                   help="folder of frame_NNNN.png (frames already there are kept)")
    cluster.add_arguments(p)
    return p


def name(frame: int) -> str:
    return f"frame_{frame:04d}.png"


def run(args):
    from .. import cluster
    from ..render import source
    from ..world import World
    from ..storage import check_path
    check_path(args.world)
    if not args.blend.is_file():
        raise VoxelError(f"no .blend at {args.blend}")
    if args.frames and args.frames[1] < args.frames[0]:
        raise VoxelError(f"--frames {args.frames[0]} {args.frames[1]}: the last frame comes "
                         "before the first")
    try:
        args.out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise VoxelError(f"cannot create folder {args.out}: {e.strerror}") from None
    t0 = time.perf_counter()
    with cluster.session(args) as pool:  # the cluster is checked before the slow part
        with World.open(args.world, readonly=True, loader=False) as w:
            sea = source.sea_level(w.generator)
        s, size, shots = _read(args.blend, args.frames)
        s.sea_level = sea
        todo = [sh for sh in shots if not (args.out / name(sh.frame)).is_file()]
        shared = {"settings": s, "size": size}
        if pool is None:
            pool = cluster.Serial()
            shared["world"] = {"path": str(args.world.resolve())}
        else:
            # Workers share no file system: the world goes to each once, as a consistent
            # snapshot (a frame needs the chunks around its camera, which the world's own
            # loader reads and generates; the same loader on a copy gives the same area).
            data = _snapshot(args.world)
            shared["world"] = {"bytes": data, "digest": hashlib.sha256(data).hexdigest()}
        for sh, png in pool.map(frame_png, todo, shared=shared,
                                progress=Progress("animate", "frames")):
            write_out(args.out / name(sh.frame), png)
    note(f"animate: {len(todo)} frames of {size[0]}x{size[1]} written, "
         f"{len(shots) - len(todo)} already there, in {time.perf_counter() - t0:.1f} s")
    print(args.out)


def _read(blend, frames):
    try:
        from ..blender import shots  # bpy itself only there
    except ImportError as e:
        raise VoxelError(f"animate reads the .blend with the bpy module (pip install bpy): "
                         f"{e}") from None
    return shots.read(blend.resolve(), frames)


def _snapshot(path: Path) -> bytes:
    """The world file's bytes as one consistent database (its WAL folded in)."""
    import sqlite3
    con = sqlite3.connect(f"file:{path.resolve()}?mode=ro", uri=True)
    try:
        return con.serialize()
    except sqlite3.Error as e:
        raise VoxelError(f"cannot read {path}: {e}") from None
    finally:
        con.close()



# ------------------------------------------------------------------ the task

_local = threading.local()  # per thread: GL contexts belong to the thread that made them
_worlds: dict = {}          # world key -> open World (read only), per process
_worlds_lock = threading.Lock()


def _world(src: dict):
    """The World of a task's `shared["world"]`: a path (this process) or the bytes of
    the file (a worker: written once to a temporary file, kept for the next frames)."""
    key = src.get("digest") or src["path"]
    with _worlds_lock:
        w = _worlds.get(key)
        if w is None:
            from ..world import World
            path = src.get("path")
            if path is None:
                path = _copy(src["bytes"], key)
            w = _worlds[key] = World.open(path, readonly=True, loader=False)
        return w


def _copy(data: bytes, key: str) -> str:
    """The world's bytes as a temporary file of this process, in the worker's scratch
    folder (gone with the worker, even a killed one); removed at exit too."""
    import atexit
    from .. import cluster
    path = os.path.join(cluster.scratch(), f"voxel_world_{key[:12]}_{os.getpid()}.sqlite")
    with open(path, "wb") as f:
        f.write(data)
    atexit.register(_remove, path)
    return path


def _remove(path: str) -> None:
    for p in (path, f"{path}-wal", f"{path}-shm"):
        try:
            os.remove(p)
        except OSError:
            pass


def frame_png(shot, shared) -> bytes:
    """One frame (blender.shots.Shot) -> PNG bytes: the task of `animate`, here and on
    cluster workers. As the operator, the area around the camera is loaded again only
    when the camera enters another chunk."""
    import math
    from ..render import Camera, source
    from ..render.device import mgl
    from ..render.pipeline import Renderer
    from ..textures import png_bytes
    import numpy as np
    s, (w, h) = shared["settings"], shared["size"]
    world = _world(shared["world"])
    st = getattr(_local, "state", None)
    key = (id(world), repr(s))
    if st is None or st["key"] != key:
        if st is not None:
            st["r"].release()
        else:
            _local.ctx = mgl.context()
        import copy
        st = _local.state = {"key": key, "r": Renderer(_local.ctx, copy.deepcopy(s)),
                             "centre": None}
    r = st["r"]
    cam = Camera(*shot.camera)
    c = (math.floor(cam.x) >> 4, math.floor(cam.y) >> 4)
    if c != st["centre"]:
        with _worlds_lock:  # one World, read by this process's threads in turn
            a = source.world_area(world, cam.x, cam.y, s.distance, s.light_radius)
            far = []
            if s.far:
                from ..far import ring
                far = ring(world.file, world.generator, cam.x, cam.y, s.far, s.distance)
        r.set_area(a.blocks, a.light, a.cx0, a.cy0, ring=True, method="greedy",
                   light_at=a.light_at, data=a.data)
        r.set_models(a.models or {})
        if a.palette is not None:
            r.set_palette(a.palette)
        r.remove_far(list(r.far.tiles))
        r.update_far(far)
        st["centre"] = c
    r.s.fov = shot.fov
    img = r.render(cam, shot.hours, (w, h))
    return png_bytes(np.dstack([img, np.full(img.shape[:2], 255, np.uint8)]))
