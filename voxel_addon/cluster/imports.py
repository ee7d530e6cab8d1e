"""`import` of a Minecraft world on a cluster. The writer reads the region files and
sends each chunk's compressed bytes; workers decompress, parse and convert it and
encode its blocks row. The writer handles results in the order the one-process
import reads chunks, so colours join the world's palette in the same order (the
same data values, the same blobs bit for bit); it commits in batches through
World.store_rows (each chunk decided inside the transaction, as the one-process
import: a chunk another writer stored meanwhile is kept unless --replace, and with
--replace the edits saved since the import started are applied again), the palette
how far it got (formats/job.py: meta `import_job`, the one-process import's note too)
and the chunks' biome rows in the same transaction, so a run killed and started again
does only what is missing and no chunk is left without its biomes.

Hostile input: a worker decodes with the per-chunk limits (region.MAX_NBT,
anvil.CHUNK_TAGS; a chunk past the tag limit refuses the import) and reports what
it decoded; the writer charges the import's budget.Budget with that in the same
order, so a spent budget refuses the import at the chunk the one-process import
would."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..core.errors import VoxelError
from ..storage import minecraft as mcfile
from . import knob, tail, task_size
from .imports_writer import _Writer

COMMIT = 64  # chunks per transaction


class _LocalPalette:
    """formats.minecraft._Palettes on a worker, one per task: block states get
    task-local indices (1, 2, ... in the order met over the task's chunks, which are
    in plan order; `local`: (state key, rgb or None, block id) each), which the writer
    maps to the world's state palette or, for dye states, their colours, and to 0 for
    its block's default state (`voxels`: each local index's voxels in the chunk in
    hand, for the writer's mcstate.States.settle); the same for block names (`names`:
    (name, block, how) in the order met; `report.blocks` their voxels so far). Being
    the task's, a section palette met in an earlier chunk (`keyed`, convert's memo)
    costs one lookup, as in one process. The writer settles a chunk's new entries
    (those past the previous chunk's) in the order met, so states, colours and report
    lines join in one-process order. Biomes stay chunk-local (`biomes`, reset per
    chunk): the columns hold them as bytes, and a task (of a modded save) may meet
    more than 256 biomes where a chunk does not (one that does: `low`, `high`)."""

    def __init__(self, known=None):
        from types import SimpleNamespace
        self.known = known
        self.ids: dict = {}
        self.keyed: dict = {}
        self.local: list = []
        self.wv: list = [0]            # each local index's value in `known` (0 if none)
        self.unknown: set = set()      # local indices `known` lacks
        self.names: list = []
        self.biomes: dict = {}
        self.report = SimpleNamespace(blocks={})
        self.voxels = self.remap = None

    def of(self, name: str, props=None):
        key = (name, tuple(sorted(props.items())) if props else ())
        got = self.ids.get(key)
        if got is None:
            skey, rgb, bid, block, how = _meet(name, props)
            d = 0
            if bid:
                self.local.append((skey, rgb, bid))
                d = len(self.local)
                v = self.known.get(skey) if self.known is not None else None
                if v is None:
                    self.unknown.add(d)
                self.wv.append(v or 0)
            got = self.ids[key] = (bid, d)
            if name not in self.report.blocks:
                self.report.blocks[name] = [block, how, 0]
                self.names.append((name, block, how))
        return got

    def settle(self, ids, vals, counts):
        """Keep each local index's voxels; no defaults here (the writer's). Where
        `known` gives every state of the chunk its world value, VALS (what convert
        writes into the data array) become those values in place (`remap`): the data
        comes out as the writer would map it, without a gather over the voxels."""
        self.voxels = np.bincount(vals, counts, minlength=len(self.local) + 1).astype(np.int64)
        if self.known is not None and self.unknown.isdisjoint(vals.tolist()):
            self.remap = np.array(self.wv, np.uint16)
            vals[:] = self.remap[vals]
        return np.zeros(int(ids.max()) + 1, np.uint16)

    def biome(self, name) -> int:
        return self.biomes.setdefault(name, len(self.biomes))

    # columns are bytes: a chunk naming more than 256 biomes (hostile) is numbered in
    # two passes, low bytes then high ones, so that each name keeps its own number
    # (the writer maps them to the world's, which stops at 255 as in one process)
    def low(self, name) -> int:
        return self.biome(name) & 255

    def high(self, name) -> int:
        return self.biomes[name] >> 8


def _meet(name: str, props):
    """A block state's (state key, rgb or None, block id, block, how): the same in
    every chunk (the imports here only: `of` runs ~66 times a chunk)."""
    from ..core.blocks import REGISTRY
    from ..formats import mapping
    from ..formats.mcstate import state_key
    block, rgb, how = mapping.lookup(name)
    return (state_key(name, props), None if rgb is None else tuple(int(v) for v in rgb),
            REGISTRY.id(block), block, how)


def packed(item, shared) -> bytes:
    """Worker: read()'s answer pickled as one object. Dask would pickle each chunk's
    result apart and the writer's process unpickle each (its event loop's largest
    cost); one pickle shares the block names and state keys of the task's chunks."""
    import pickle
    return pickle.dumps(read(item, shared), protocol=pickle.HIGHEST_PROTOCOL)


def read(item, shared):
    """Worker: one (result, (bytes, tags) decoded, where) per (index, (region name,
    cx, cz, kind, body)) of the task's chunks; result: ("ok", version, row without data,
    data, (local states, how many so far, voxels per local state), (block names, how
    many so far, [(name's index, voxels)]), dropped, key, local biome columns or None,
    local biome names), ("unfinished", version, status), ("damaged",
    message, before 1.13?) or ("hostile", message); the lists are the task's
    (_LocalPalette), the same objects in each chunk's result (pickled once).
    `data`: None, or the data blob and the local -> world map it was encoded with
    when the task's `known` (state key -> world value, what the writer had settled
    when the task went out; a value turns 0 once at most, when a chunk still in flight
    decides its block's default: _Writer._redefault) covers every state of the chunk
    (the map's other entries: whatever, no voxel has them), else the local data (the
    writer maps and encodes it). `kind`
    None: the worker shares the writer's file system (a local cluster) and reads the
    chunk's bytes itself from shared["files"][name], the region's path."""
    from ..formats import anvil, mcstate, minecraft, nbt
    from ..formats.budget import Budget, Exceeded
    from ..formats.region import MAX_NBT, External, Region, RegionError, unpack
    chunks, known = item
    out, regions = [], {}
    pal = _LocalPalette(known)
    counts, before = pal.report.blocks, []
    for _, (name, cx, cz, kind, body) in chunks:
        where = f"{name} chunk ({cx}, {cz})"
        b = Budget(MAX_NBT, anvil.CHUNK_TAGS)  # the per-chunk limits; the writer charges the rest
        try:
            if kind is None:
                reg = regions.get(name) or regions.setdefault(name, Region(shared["files"][name]))
                kind, body = reg.raw(cx, cz)
            ch = anvil.read(unpack(name, cx, cz, kind, body, b), b, packed=True)
        except Exceeded as e:  # nbt.Hostile too: refuses the import, as in one process
            out.append((("hostile", f"{where}: {e}; import refused"), b.spent(), where))
            continue
        except External:   # as the writer settles it when it reads the file itself
            out.append((("external",), b.spent(), where))
            continue
        except (RegionError, anvil.ChunkError, nbt.NbtError) as e:
            msg = str(e)
            full = msg if msg.startswith(name) else f"{where}: {msg}"
            out.append((("damaged", full, "before 1.13" in msg), b.spent(), where))
            continue
        if ch.status not in anvil.DONE:
            out.append((("unfinished", ch.version, ch.status), b.spent(), where))
            continue
        pal.voxels = pal.remap = None
        blocks, data, dropped = minecraft.convert(ch, shared["y_min"], pal)
        row = shared["encoder"].row(minecraft.to_key(cx, cz), blocks)
        if data is not None and pal.remap is not None:
            # the writer's zstd (the largest share of its time) done here: values once
            # given never change, so this map is the one the writer makes in plan order
            # (convert already wrote the world values: _LocalPalette.settle)
            data = (shared["encoder"].data(data), pal.remap)
        pal.biomes = {}
        cols = mcstate.columns(ch, blocks, shared["y_min"], pal.low)
        if cols is not None and len(pal.biomes) > 256:  # a hostile chunk: the high bytes
            cols = cols | mcstate.columns(ch, blocks, shared["y_min"], pal.high).astype(
                np.uint16) << 8
        # this chunk's voxels per block name: what the task's counts grew by
        now = [v[2] for v in counts.values()]
        before += [0] * (len(now) - len(before))
        grew = [(i, n - m) for i, (n, m) in enumerate(zip(now, before)) if n != m]
        before = now
        out.append((("ok", ch.version, row, data, (pal.local, len(pal.local), pal.voxels),
                     (pal.names, len(pal.names), grew), dropped, minecraft.to_key(cx, cz), cols,
                     list(pal.biomes)), b.spent(), where))
    return out


def run(world, pool, path, *, y_min=None, area=None, replace=False, progress=None,
        report=None, resources=None, say=None) -> int:
    """Like formats.minecraft.import_world, `report` (a minecraft.Report) filled as it
    goes, `say` told when it resumes; returns how many chunks the workers read."""
    import pickle
    from ..formats import anvil, minecraft
    from ..formats.budget import Budget
    from ..formats.job import Job
    from ..formats.region import External, RegionError
    world.writable()
    f = world.file
    todo = minecraft.plan(path, area)
    keys = [minecraft.to_key(cx, cz) for _, cx, cz in todo]
    job = Job(f, minecraft.regions_of(path), keys, y_min=y_min, area=area, replace=replace)
    start, skip = job.start, job.skip

    # a local cluster's workers read the region files themselves: the chunks' bytes
    # then pass through neither this process nor the scheduler
    near = getattr(pool, "local", False)
    # each chunk: sent to a worker, or settled here (a place the file cannot give;
    # workers that read the file themselves find those too, as they read it)
    plan, local = [], {}
    for i, (reg, cx, cz) in enumerate(todo):
        if skip(i, keys[i]):
            continue
        try:
            if not near:
                reg.raw(cx, cz)
        except External:
            local[i] = (("external",), (0, 0), None)
            continue
        except RegionError as e:
            local[i] = (("damaged", str(e), False), (0, 0), None)
            continue
        plan.append((i, reg, cx, cz))
    version = minecraft.level_version(path) if Path(path).is_dir() else None
    if version is not None and version < anvil.V_FLATTENING:  # refused before any write
        raise VoxelError(f"{Path(path).name}: level.dat has DataVersion {version}, before 1.13 "
                         "(numeric block ids); open and save the world in Minecraft 1.13 "
                         "or newer first")
    budget = Budget.of_input(sum(r.stored for r in {id(t[0]): t[0] for t in todo}.values()))
    if version is None:
        version = minecraft.first_version(todo, budget)
    report = minecraft.Report() if report is None else report
    report.resumed = job.skipped
    report.take_version(version, y_min)
    shared = {"y_min": report.y_min, "encoder": f.encoder()}
    if near:
        regs = {id(t[0]): t[0] for t in todo}.values()
        shared["files"] = {r.path.name: str(r.path.resolve()) for r in regs}
    # a chunk is quick here (~2 ms): bigger tasks. Each task costs the writer's process
    # ~4 ms of Dask's own work (submit, scheduler, gather, release): 128 chunks a task
    # took 0.14 s less of it than 64 for 4096 chunks
    size = pool.size  # asked once: each ask is a round trip to the scheduler (~1.5 ms here)
    step = task_size(len(plan), size, most=128)
    # the first window of tasks goes out before any result is settled (no `known` yet:
    # the writer encodes their data blobs itself), so it is made of smaller tasks
    small = max(1, min(step, 64) // 4)
    first = 4 * size * small

    def tasks():  # the bytes are copied as tasks go out, not all at once
        j = 0
        while j < len(plan):
            n = small if j < first else tail(len(plan) - j, step, size)
            part = plan[j:j + n]
            if near:
                chunks = tuple((i, (reg.path.name, cx, cz, None, None)) for i, reg, cx, cz in part)
            else:
                chunks = tuple((i, (reg.path.name, cx, cz, kind, bytes(body)))
                               for i, reg, cx, cz in part for kind, body in [reg.raw(cx, cz)])
            yield chunks, dict(w.known)
            j += n

    if say and job.resumed:
        say(job.line(len(todo)))
    job.begin()
    w = _Writer(world, report, job, progress, len(plan) + len(local), budget)
    w.meta = {mcfile.Y_MIN: str(report.y_min)}    # staged with the first batch, as in one process
    if resources is not None:
        w.meta[mcfile.RESOURCES] = json.dumps([str(r) for r in resources])
    order = sorted([p[0] for p in plan] + list(local))
    ready: dict = dict(local)
    computed, pos = 0, 0
    every = knob("COMMIT", COMMIT)
    try:
        for (task, _), results in pool.map(packed, tasks(), shared=shared):
            results = pickle.loads(results)
            computed += len(task)
            for (i, _), r in zip(task, results):
                ready[i] = r
            while pos < len(order) and order[pos] in ready:  # the one-process order
                w.settle(ready.pop(order[pos]))
                pos += 1
                if len(w.batch) >= every:
                    w.commit(order[pos - 1] + 1)
        while pos < len(order):  # no tasks at all: only local ones
            w.settle(ready.pop(order[pos]))
            pos += 1
        w.commit(len(todo))
    except BaseException:
        w.commit(order[pos - 1] + 1 if pos else start)  # keep what is settled
        raise
    job.end()   # done: this import's note dropped (other imports' stay)
    if w.old and w.old == len(report.damaged) and not (report.chunks or report.unfinished
                                                       or job.skipped):
        # nothing written: a world Minecraft never saved in 1.13+ is refused whole
        raise VoxelError(f"none of the {w.old} chunks is from Minecraft 1.13 or newer, nothing "
                         f"was imported ({report.damaged[0]})")
    return computed

