"""Light and mesh a rectangle of chunks in one batch and hand out payloads: the one
path that streaming (stream.py) and edits (edit.py, for chunks not lit yet) share.

A chunk's light is final only when its 8 neighbours' blocks were known, so a batch
reads its rectangle plus a one-chunk ring; light saved in the file with a chunk is
final too (the world nulls it when a block around changes), so a rectangle whose
chunks all came with light is only meshed. Blocks are copied under the world's lock
with the tick of each chunk's last block change; the light and meshes are kept only
for chunks whose 3x3 did not change meanwhile (an edit raced us: done again later).
"""
from __future__ import annotations

import threading
import weakref

import numpy as np

from ..core import chunk as C
from ..core import ending
from . import models as mcmodels
from .payload import Payload

# Kernel objects (light, meshing) are shared per process and are not re-entrant:
# the stream's workers and edits take this lock around OpenCL light and meshing.
CL_LOCK = threading.Lock()


def backends() -> tuple[str, str]:
    """(light, meshing) backends for the world layer. Light: NumPy. Its flood uses
    less CPU per chunk than the OpenCL sweeps here (1.1-1.5 vs 1.4-2.2 ms per kept
    chunk on 2 shared cores) and pocl builds the sweep kernels again for every new
    region shape (~1.5 s each), which streaming's varied rectangles keep hitting.
    Meshing: OpenCL where present (~10x NumPy) and not warming up (opencl.warm), else
    NumPy."""
    from .. import opencl
    return "numpy", opencl.pick(None, "meshing")


def warm(world, opened: bool = False) -> bool:
    """Build and run once, in a background thread, the OpenCL kernels that streaming
    WORLD wants (its generator's chunks, then meshing: the order the stream needs
    them), on a 3x3 of chunks at the origin; generation runs NumPy until its kernels
    are built (opencl.ready), meshing until the end (opencl.warm); when the file holds
    that 3x3 (a stored view: the stream needs meshing, not generation) meshing first,
    on those chunks, then the generator's at a lower priority. Once per generator
    (another world of the same generator and version reuses the build: cheap); False
    when nothing was started (no device, warmed already, another warm-up running).
    Cold, on 2 quiet cores: ~3.3 s for the generator (before clsource.called cut its
    first launches' CPU ~3x), ~0.6 s meshing, which now builds beside the generator in
    a helper process (opencl.helper) and only loads from pocl's cache here. Then, with
    OpenCL already the default (opencl.warm's `later`) and once the world's streams
    have made all they want (one pocl queue: the stream's kernels would wait behind
    it), the far surface's program (the generator's 2D passes, its own kernel
    objects), so turning the far ring on does not wait for its build.
    OPENED: called when a world is opened, before anything shows it (Blender's New and
    Open): the kernels build while the user reaches for Show, and the far prebuild
    waits until a stream of the world exists and has all it wants."""
    from .. import meshing, opencl
    g = world.generator
    if g in _warmed:
        return False

    def job():
        from ..core import trace
        keys = keys_of(-1, -1, 2, 2)
        stored = _stored(world, keys)
        if stored is not None:
            # a file holding these chunks most likely holds the view's: the stream
            # needs meshing, not generation (issue 28: a cold Show of a stored view
            # waited ~5 s of quiet CPU, 15-20 s under load, for the generator's build)
            blocks = C.paste(zip(keys, stored), -1, -1, 2, 2)
            with CL_LOCK, trace.span("warm.mesh"):
                meshing.build_chunks(blocks[15:-15, 15:-15], (0, 0), backend="opencl")
            opencl.ready("meshing")
            opencl._yield_cpu()  # the stream's threads come first now
            if ending.exiting():
                return
            with trace.span("warm.generate"):
                if hasattr(g, "warm_opencl"):
                    g.warm_opencl(keys)
                else:
                    g.generate(keys)
            opencl.ready("generation")
            return
        from ..meshing import cl as mcl
        # meshing's kernels build in a process of their own meanwhile (opencl.helper:
        # pocl compiles one thing at a time per process); here they then load from
        # pocl's cache
        helper = opencl.helper("meshing.vertex", "warm_cache", list(mcl._options()),
                               nice=HELPER_NICE)
        try:
            with trace.span("warm.generate"):
                if hasattr(g, "warm_opencl"):  # the world's own generator (its kernels)
                    arrays = g.warm_opencl(keys)
                else:
                    arrays = g.generate(keys)
        except BaseException:
            _finish(helper, 0.0)
            raise
        # the stream generates with OpenCL from now on, while meshing's kernels build
        opencl.ready("generation")
        if ending.exiting():  # (the process ends: its exit waits for this thread)
            _finish(helper, 0.0)
            return
        blocks = C.paste(zip(keys, arrays), -1, -1, 2, 2)
        with trace.span("warm.helper", started=helper is not None):
            _finish(helper)
        with CL_LOCK, trace.span("warm.mesh"):
            meshing.build_chunks(blocks[15:-15, 15:-15], (0, 0), backend="opencl")

    surface = getattr(g, "warm_surface", None)

    def later():
        import time
        # pocl runs one in-order queue: the far surface's 16384-column batch and its
        # work-group build queued in front of the stream's kernels held the whole view
        # back by 1.5-2 s (issue 28's timeline): wait until the streams have all they want
        end = time.monotonic() + LATER_WAIT_S
        while time.monotonic() < end and not ending.exiting() and (
                any(not s.idle for s in list(world.streams)) or opened and not world.streams):
            time.sleep(0.1)
        if not ending.exiting():
            surface()

    started = opencl.warm(job, later=later if surface is not None else None)
    if started:
        _warmed.add(g)
        prebuild(g, world)
    return started


def _stored(world, keys):
    """The blocks of keys when the world's file has every one of them, else None."""
    try:
        got = [world.file.read_chunk(k) for k in keys]
    except Exception:  # noqa: BLE001 - a damaged chunk, no file: generate them instead
        return None
    return None if any(x is None for x in got) else [x[0] for x in got]


def prebuild(g, world=None) -> bool:
    """Build the far surface's OpenCL program once the warm-up's job (the near view's
    kernels) has ended and WORLD's streams have every chunk they want (none yet: at
    once), in a thread of its own at a lower priority (it takes leftover CPU): a
    separate program whose build takes neither the queue nor the build lock, and the
    far ring's tiles run on it seconds after a world opens (New, Open: the build fits
    in the user's pause before Show) instead of after the warm-up's later part (issue
    28: far 128 to the horizon). Surface calls run NumPy from now until then. Not
    beside the job: pocl (3.0, LLVM 14) compiles one program or work-group function
    at a time in the whole process, other cl.Contexts included, so the generator's
    build waited for the whole far build, which at nice 10 on a busy machine took
    seconds (issue 28's timeline: both builds ended together); not while the near
    view streams in: its CPU came from the near view's last batches, which bound the
    horizon in the GUI anyway. False when the generator has no far surface."""
    fn = getattr(g, "prebuild_surface", None)
    if fn is None:
        return False
    from .. import opencl

    def run():
        opencl._yield_cpu()
        try:
            fn(before=lambda: _after_warm_up(world))
        except Exception:  # noqa: BLE001 - surface() builds it (and raises) when used
            pass

    opencl.background(run, "voxel-far-prebuild")
    return True


def _finish(proc, wait: float | None = None) -> None:
    """Wait for opencl.helper's process PROC (None: none) at most WAIT seconds
    (HELPER_WAIT_S), then end it: what it has not put into pocl's cache by then is
    built here (a busy machine starves the niced helper: then this process builds as
    it did before)."""
    if proc is None:
        return
    import subprocess
    try:
        proc.wait(HELPER_WAIT_S if wait is None else wait)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


HELPER_WAIT_S = 2.0  # after the generator's kernels: the helper's ~1.5 s CPU is mostly done
# The helper's niceness: it takes only the CPU the first frames and the first NumPy
# chunks leave. At 0 the first frames of a fresh Blender (its shader compiles) came
# later; at 5, quiet, 2 of 5 cold Shows drew their first chunks at 3.0-3.6 s (frames of
# 1.3 s each) against 0.8-1.4 s for the rest and at 19 (issue 28's goal: 2 s)
HELPER_NICE = 19


def _after_warm_up(world=None) -> None:
    """Returns once no warm-up job runs (opencl.warming: its LATER part not counted)
    and WORLD's streams (if any) have all they want, or LATER_WAIT_S after that job."""
    import time
    from .. import opencl
    while opencl.warming() and not ending.exiting():
        time.sleep(0.05)
    end = time.monotonic() + LATER_WAIT_S
    while world is not None and time.monotonic() < end and not ending.exiting() and \
            any(not s.idle for s in list(world.streams)):
        time.sleep(0.1)
    if ending.exiting():
        raise ending.Exiting()  # the prebuild stops here (its caller: nothing built)


LATER_WAIT_S = 60.0  # the far prebuild waits at most this long for busy streams
_warmed: weakref.WeakSet = weakref.WeakSet()  # generators warm-up has run for


_ALL = slice(None)


def keys_of(cx0: int, cy0: int, cx1: int, cy1: int) -> list[tuple[int, int]]:
    return [(x, y) for y in range(cy0, cy1) for x in range(cx0, cx1)]


def snapshot(world, cx0: int, cy0: int, cx1: int, cy1: int, data: bool = False,
             pad: int = C.SIZE):
    """(blocks, ticks): active chunks of [cx0, cx1) x [cy0, cy1) as one array (air
    where a chunk is not active, e.g. corrupt) and {key: block tick} at copy time;
    with data=True (blocks, ticks, small data or None when no chunk has any).
    PAD < 16: the outer chunks give only their PAD voxels next to the inner ones
    (a batch that only meshes reads a one-voxel ring: the rest was copied for
    nothing); the array then starts at voxel (cx0 * 16 + 16 - pad, ...)."""
    s, o = C.SIZE, C.SIZE - pad  # o: voxels of the outer chunks left out on each side
    out = C.empty(width=s * (cx1 - cx0) - 2 * o, depth=s * (cy1 - cy0) - 2 * o)
    w, h = out.shape[:2]
    small = None
    keys = keys_of(cx0, cy0, cx1, cy1)
    with world.locked():
        ticks = {k: world.bver.get(k, 0) for k in keys}
        got = [(k, c, c.data) for k in keys for c in (world.chunks.get(k),) if c is not None]
    # copied outside the lock (issue 29: a batch's copy held it ~5 ms, the other
    # worker waiting): a block write after the ticks above changes its chunk's tick,
    # so store() drops what a torn copy made; packed blocks are never changed, and a
    # pack racing the copy leaves the same values
    for k, c, d in got:
        x, y = (k[0] - cx0) * s - o, (k[1] - cy0) * s - o  # chunk origin in `out`
        xa, ya = max(x, 0), max(y, 0)
        xs, ys = slice(xa - x, min(x + s, w) - x), slice(ya - y, min(y + s, h) - y)
        win = (slice(xa, x + xs.stop), slice(ya, y + ys.stop))
        whole = xs == _ALL16 and ys == _ALL16
        # a cold chunk decodes into the window and stays packed (issue 29)
        c.blocks_into(out[win], _ALL if whole else xs, _ALL if whole else ys, 0, C.HEIGHT,
                      zeroed=True)
        if data and d is not None:
            if small is None:
                small = np.zeros_like(out)
            small[win] = d[xs, ys]
    return (out, ticks, small) if data else (out, ticks)


_ALL16 = slice(0, C.SIZE)


def _run(backend, fn, *a, **kw):
    if backend == "opencl":
        with CL_LOCK:
            return fn(*a, backend=backend, **kw)
    return fn(*a, backend=backend, **kw)


def light_and_mesh(world, cx0: int, cy0: int, cx1: int, cy1: int, *, backends_=None,
                   load: bool = True) -> list[Payload]:
    """Final light + mesh of chunks [cx0, cx1) x [cy0, cy1), stored on the chunks;
    returns their payloads (chunks that are missing or raced by an edit left out)."""
    from .. import light, meshing
    from ..core import trace
    lb, mb = backends_ or backends()
    ring = keys_of(cx0 - 1, cy0 - 1, cx1 + 1, cy1 + 1)
    if load:
        with trace.span("batch.load", n=len(ring)):
            world.load(ring, hot=True)  # the caller compacts (Stream._make)
    with world.locked():  # light stored in the file (loaded with the blocks) is final
        need = any(c is not None and not c.has_light
                   for c in map(world.chunks.get, keys_of(cx0, cy0, cx1, cy1)))
    # light reads the whole ring (15 voxels of light come in from it), meshing one
    # voxel of it: a reloaded view's batches copy ~1/3 less (the ring's chunks)
    with trace.span("batch.snapshot", need=need):
        blocks, ticks, data = snapshot(world, cx0 - 1, cy0 - 1, cx1 + 1, cy1 + 1, data=True,
                                       pad=C.SIZE if need else 1)
    # the rectangle's blocks are packed now (no batch reads them again); the ring's
    # stay as read for the batch that has them inside (a pack then a decode
    # there; the stream's compact sweep packs those left over within a second)
    with trace.span("batch.pack"):
        pack_loaded(world, keys_of(cx0, cy0, cx1, cy1))
    # one solve for the whole rectangle: its ring is the only overhead
    # model blocks that are no whole cube pass light (with the world's resource stack)
    with trace.span("batch.light", backend=lb, need=need):
        lit = _run(lb, light.region_light, mcmodels.light_blocks(world, blocks, data),
                   tile=max(cx1 - cx0, cy1 - cy0)) if need else None
    inner, data = (blocks[15:-15, 15:-15], None if data is None else data[15:-15, 15:-15]) \
        if need else (blocks, data)
    # Minecraft model blocks (with the world's resource stack): air for the mesher
    models = mcmodels.build(world, inner, data, cx0, cy0)
    with trace.span("batch.mesh", backend=mb):
        meshes = _run(mb, meshing.build_chunks, inner, (cx0, cy0), data=data)
    for k, m in models.items():
        if k in meshes:
            meshes[k].models = m
    with trace.span("batch.store"):
        return store(world, cx0, cy0, cx1, cy1, lit, meshes, ticks)


def pack_loaded(world, keys) -> int:
    """Pack the blocks that load(hot=True) kept as read, now that the snapshot has
    copied them (issue 29: the resident goal), outside the world's lock (LZ4 of a
    chunk ~30-45 us); a chunk read or written meanwhile keeps its array (compact()
    packs it once cold). Returns how many were packed."""
    with world.locked():
        todo = [(c, a) for c in map(world.chunks.get, keys) if c is not None
                for a in (c.unread(),) if a is not None]
    if not todo:
        return 0
    done = [(c, a, C.pack(a)) for c, a in todo]
    with world.locked():
        return sum(c.packed(a, p) for c, a, p in done)


def compact(world, keys) -> None:
    """Chunk.compact() of the chunks of KEYS, their light packed outside the world's
    lock (issue 29: LZ4 of a batch's light held it ~3 ms, the other worker waiting)."""
    with world.locked():
        todo = [(c, a) for c in map(world.chunks.get, keys) if c is not None
                for a in (c.hot_light(),) if a is not None]
    done = [(c, a, C.pack(a)) for c, a in todo]
    with world.locked():
        for c, a, p in done:
            c.light_packed(a, p)  # (light set meanwhile: packed by this compact())
        for c in map(world.chunks.get, keys):
            if c is not None:
                c.compact()


def store(world, cx0, cy0, cx1, cy1, lit, meshes, ticks) -> list[Payload]:
    """Keep light (an array over the rectangle, or None to keep the chunks' own)
    and meshes on chunks whose 3x3 is unchanged since `ticks`; returns their new
    payloads. A chunk lit here for the first time is marked changed, so its light
    is saved with it (reloading then skips the solve)."""
    out = []
    s = C.SIZE
    with world.locked():
        # the chunks whose blocks changed since the snapshot (mostly none: then no
        # 3x3 test per chunk, ~9 lookups each)
        bv = world.bver.get
        moved = [k for k, t in ticks.items() if bv(k, 0) != t]
        for k in keys_of(cx0, cy0, cx1, cy1):
            c = world.chunks.get(k)
            if c is None:
                continue
            if moved and any(max(abs(m[0] - k[0]), abs(m[1] - k[1])) <= 1 for m in moved):
                continue
            if lit is not None:
                if not c.has_light and not world.readonly:
                    c.dirty = True
                x, y = (k[0] - cx0) * s, (k[1] - cy0) * s
                c.light = np.asfortranarray(lit[x:x + s, y:y + s])
            elif not c.has_light:
                continue
            c.mesh = meshes[k]
            v = world.pver[k] = world.tick()
            out.append(Payload(k, c.mesh, c.light_out(), v))
    return out


def payload(world, key) -> Payload | None:
    """The current payload of an active chunk whose light and mesh are known."""
    with world.locked():
        c = world.chunks.get(key)
        if c is None or not c.has_light or c.mesh is None:
            return None
        v = world.pver.get(key)
        if v is None:
            v = world.pver[key] = world.tick()
        return Payload(key, c.mesh, c.light_out(), v)
