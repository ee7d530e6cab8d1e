"""`import` of a Minecraft world on a cluster. The writer reads the region files and
sends each chunk's compressed bytes; workers decompress, parse and convert it and
encode its blocks row. The writer handles results in the order the one-process
import reads chunks, so colours join the world's palette in the same order (the
same data values, the same blobs bit for bit); it commits in batches through
World.store_rows (each chunk decided inside the transaction, as the one-process
import: a chunk another writer stored meanwhile is kept unless --replace, and with
--replace the edits saved since the import started are applied again), the palette
how far it got (meta `import_job`) and the chunks' biome rows in the same
transaction, so a run killed and started again does only what is missing and no
chunk is left without its biomes. `import_job` keeps one note per unfinished import
(a JSON list of {sig, done, since}; older files: one such object), so two imports
into one world, both killed, both resume.

Hostile input: a worker decodes with the per-chunk limits (region.MAX_NBT,
anvil.CHUNK_TAGS; a chunk past the tag limit refuses the import) and reports what
it decoded; the writer charges the import's budget.Budget with that in the same
order, so a spent budget refuses the import at the chunk the one-process import
would.

On resume: without --replace every chunk of the plan already in the file is ours
(the first run refused to start over any), so it is skipped; with --replace the
plan's first `done` chunks are."""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np

from ..core.errors import VoxelError
from ..formats.budget import Exceeded
from ..storage import minecraft as mcfile
from . import knob, tail, task_size

COMMIT = 64  # chunks per transaction
JOB = "import_job"


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


def _signature(files, y_min, area, replace) -> str:
    h = hashlib.sha256(json.dumps([y_min, area and list(area), bool(replace)]).encode())
    for f in files:
        st = f.stat()
        h.update(f"{f.resolve()}\0{st.st_size}\0{st.st_mtime_ns}\0".encode())
    return h.hexdigest()[:16]


def run(world, pool, path, *, y_min=None, area=None, replace=False, progress=None,
        report=None, resources=None) -> int:
    """Like formats.minecraft.import_world, `report` (a minecraft.Report) filled as it
    goes; returns how many chunks the workers read."""
    import pickle
    import time
    from ..formats import anvil, minecraft
    from ..formats.budget import Budget
    from ..formats.region import External, RegionError
    world.writable()
    f = world.file
    todo = minecraft.plan(path, area)
    sig = _signature(minecraft.regions_of(path), y_min, area, replace)
    got = f.query("SELECT value FROM meta WHERE key=?", (JOB,))  # as the file holds it now
    job = _job(got[0][0] if got else None, sig)
    have = {minecraft.to_key(cx, cz) for _, cx, cz in todo} & set(f.chunk_keys())
    if job is None and have and not replace:
        raise VoxelError(f"{len(have)} of the {len(todo)} chunks are already in "
                         f"{f.path} (imported before, or generated); "
                         "import with --replace (Blender: Replace) to overwrite them")
    start = job["done"] if job else 0
    # edits saved from the first run's start on survive a replace (store_rows)
    since = job.get("since", time.time()) if job else time.time()

    def skip(i, key):
        if job is None:
            return False
        return key in have if not replace else i < start

    # a local cluster's workers read the region files themselves: the chunks' bytes
    # then pass through neither this process nor the scheduler
    near = getattr(pool, "local", False)
    # each chunk: sent to a worker, or settled here (a place the file cannot give;
    # workers that read the file themselves find those too, as they read it)
    plan, local = [], {}
    for i, (reg, cx, cz) in enumerate(todo):
        if skip(i, minecraft.to_key(cx, cz)):
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
        version = _first_version(todo, budget)
    report = minecraft.Report() if report is None else report
    report.version = version
    report.y_min = y_min if y_min is not None else (
        (-64 if version >= anvil.V_NO_LEVEL else 0) if version is not None else 0)
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

    f.update_meta(JOB, lambda raw: _noted(raw, sig, start, since))
    w = _Writer(world, report, sig, progress, len(plan) + len(local), budget)
    w.replace, w.since = replace, since
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
    # done: this import's note dropped (other imports' stay)
    f.update_meta(JOB, lambda raw: _noted(raw, sig))
    if w.old and w.old == len(report.damaged) and not (report.chunks or report.unfinished):
        # nothing written: a world Minecraft never saved in 1.13+ is refused whole
        raise VoxelError(f"none of the {w.old} chunks is from Minecraft 1.13 or newer, nothing "
                         f"was imported ({report.damaged[0]})")
    return computed


def _jobs(raw) -> list:
    """The notes of meta `import_job`: a list of {sig, done, since}, or (older files,
    one import at a time) one such object; damaged: none."""
    try:
        got = json.loads(raw) if raw else []
    except ValueError:
        return []
    got = [got] if isinstance(got, dict) else got
    return [j for j in got if isinstance(j, dict)] if isinstance(got, list) else []


def _job(raw, sig):
    """The unfinished job of the same import (same files, same options), or None."""
    for job in _jobs(raw):
        if job.get("sig") == sig and isinstance(job.get("done"), int) \
                and isinstance(job.get("since", 0.0), (int, float)):
            return job
    return None


def _noted(raw, sig, done=None, since=None) -> str:
    """RAW (the notes) with this import's note set to DONE and SINCE, or dropped
    (DONE None); the other imports' notes as they are ("" when none is left)."""
    jobs = [j for j in _jobs(raw) if j.get("sig") != sig]
    if done is not None:
        jobs.append({"sig": sig, "done": done, "since": since})
    return json.dumps(jobs) if jobs else ""


def _first_version(todo, budget):
    """DataVersion of the first readable chunk (what the one-process import uses);
    what it decodes is charged to the import's budget (a hostile file is refused)."""
    from ..formats import anvil, nbt
    from ..formats.region import RegionError
    for reg, cx, cz in todo:
        try:
            return anvil.read(reg.payload(cx, cz, budget), budget).version
        except Exceeded as e:
            raise VoxelError(f"{reg.path.name} chunk ({cx}, {cz}): {e}; import refused") \
                from None
        except (RegionError, anvil.ChunkError, nbt.NbtError):
            continue
    return None


class _Writer:
    """Results in plan order into the report, the palette and batches of rows."""

    def __init__(self, world, report, sig, progress, total, budget):
        from ..core import colors
        self.world, self.report, self.sig, self.budget = world, report, sig, budget
        self.replace, self.since, self.old = False, None, 0
        self.progress, self.total, self.done = progress, total, 0
        from ..core.blocks import REGISTRY
        from ..formats import mcstate
        self.palette = colors.parse(world.file.meta)
        self.states = mcstate.States(world.file)
        self.to_file = mcstate.ToFile(self.states)   # commits: onto the file's palettes
        self.grown = False
        self.batch, self.biomes, self.meta = [], [], {}
        self.enc = world.file.encoder()
        self.known: dict = {}  # state key -> its value in the world's data (workers encode with it)
        self.redefaulted = 0   # worker blobs made again by _redefault
        # the task in hand (its `local` list, _ok): each local state's world value and
        # block id (as lists and as `arrays`), each of its block names' report line
        self.task, self.wv, self.bids, self.refs, self.arrays = None, [0], [0], [], None
        # that task's map with the defaults zeroed (and its bytes) while no block of the
        # task's states is still undecided (`open`): the chunks after need no settle;
        # `sent`: what `known` last got from this task; each biome list's world values
        self.zeroed, self.open, self.sent, self.globs = None, True, None, {}
        self.color = REGISTRY.id("color")

    def settle(self, got) -> None:
        r, (nbytes, tags), where = got
        rep = self.report
        self.done += 1
        try:  # what the worker decoded, charged in the one-process order
            self.budget.spend_bytes(nbytes)
            self.budget.spend_tags(tags)
        except Exceeded as e:
            raise VoxelError(f"{where}: {e}; import refused") from None
        what = r[0]
        if what == "ok":
            self._ok(r)
            return
        if what == "external":
            rep.external += 1
        elif what == "hostile":
            raise VoxelError(r[1])
        elif what == "damaged":
            rep.damaged.append(r[1])
            self.old += r[2]
        elif what == "unfinished":
            rep.unfinished[r[2]] += 1

    def _ok(self, r) -> None:
        """A chunk read: its states, colours and biomes settled (per chunk for each
        of 4096+ chunks: Python lists here, NumPy once per chunk). The task's lists
        (read) are mapped as far as this chunk reached, once per task, in order."""
        _, _, row, data, (local, nloc, voxels), (names, nnames, grew), dropped, key, cols, \
            bnames = r
        rep = self.report
        if local is not self.task:   # the first chunk of the next task
            self.task, self.wv, self.bids, self.refs = local, [0], [0], []
            self.arrays = self.zeroed = self.sent = None
        refs = self.refs
        if len(refs) < nnames:
            blocks = rep.blocks
            for name, b, how in names[len(refs):nnames]:
                got = blocks.get(name)
                if got is None:
                    got = blocks[name] = [b, how, 0]
                refs.append(got)
        for i, n in grew:
            refs[i][2] += n
        rep.dropped += dropped
        wv, bids = self.wv, self.bids   # as formats.minecraft._Palettes
        if len(wv) <= nloc or self.arrays is None:
            states, of_key = self.states, self.states.of_key
            for skey, rgb, bid in local[len(wv) - 1:nloc]:
                st = of_key(skey)
                bids.append(bid)
                if rgb is not None:
                    self.palette, v = states.color(st, self.palette, rgb)
                    wv.append(v)
                    self.grown = True
                else:
                    wv.append(st)
            self.arrays = np.array(wv, np.uint16), np.array(bids, np.uint16)
            self.zeroed = None
        remap, ids = self.arrays
        if voxels is None:
            zb = None
        elif self.zeroed is not None and not self.open:
            remap, zb = self.zeroed   # every block of the task's states has its default
        else:                         # each block's default state is stored as 0
            dflt = self.states.settle(ids, remap, voxels[:len(remap)])
            remap = np.where(remap == dflt[ids], 0, remap).astype(np.uint16)
            self.open = not self.states.legacy and bool(
                ((dflt[ids] == 0) & (ids != 0) & (ids != self.color)).any())   # as States.settle
            zb = remap.tobytes()
            self.zeroed = remap, zb
        # a value changes once at most: to 0, when its block's default is decided
        if zb is None or self.sent != (nloc, zb):
            self.known.update(zip([e[0] for e in local[:nloc]], remap[1:].tolist()))
            self.sent = None if zb is None else (nloc, zb)
        if isinstance(data, tuple):  # encoded by the worker with what was known then
            blob, theirs = data
            if len(theirs) != len(remap):
                raise RuntimeError(f"{key}: a worker numbered block states otherwise")
            if theirs.tobytes() != zb:   # (most chunks: the same map)
                changed = (theirs != remap) & (voxels[:len(remap)] > 0)
                if changed.any():
                    blob = self._redefault(key, row, blob, theirs, remap, ids, changed)
        else:
            blob = None if data is None else self.enc.data(remap[data])
        self.batch.append(row[:4] + (blob,) + row[5:])
        if cols is not None:   # a world biome's index never changes once given
            names = tuple(bnames)
            glob = self.globs.get(names)
            if glob is None:
                glob = self.globs[names] = np.array([self.states.biome(n) for n in names],
                                                    np.uint8)
            self.biomes.append((key, glob[cols]))

    def _redefault(self, key, row, blob, theirs, remap, ids, changed):
        """A worker's data blob encoded before a chunk still in flight decided the
        default state of some of its blocks: those states' voxels become 0 (colour
        voxels keep their colour index, which may be the same number)."""
        from ..core import chunk as C
        from ..core.blocks import REGISTRY
        from ..storage import codecs
        color = REGISTRY.id("color")
        if (remap[changed] != 0).any() or (ids[changed] == color).any():
            raise RuntimeError(f"{key}: a worker mapped block states otherwise")
        vals = codecs.decode_u16(row[2], blob, C.VOLUME)
        blocks = codecs.decode_u16(row[2], row[3], C.VOLUME)   # the file's numbering
        fcolor = color if self.enc.to_file is None else int(self.enc.to_file[color])
        vals[np.isin(vals, theirs[changed]) & (blocks != fcolor)] = 0
        self.redefaulted += 1
        return self.enc.data(vals.reshape(C.SHAPE, order="F"))

    def commit(self, upto: int) -> None:
        f, to = self.world.file, self.to_file
        # in the transaction of the chunks that use it, as in one process
        to.stage(self.palette, self.grown)
        self.grown = False
        if self.batch:
            for k, v in self.meta.items():
                f.stage_meta(k, v)
            self.meta = {}

        def also(db, written=()):
            """In the batch's transaction: the biome rows of the chunks written (in
            the file's numbers, made again when the palettes moved) and the note of
            how far this import got, the other imports' notes as the file holds them."""
            mcfile.put(db, [(k, b) for k, b in to.columns(self.biomes) if k in written])
            mcfile.update(db, JOB, lambda raw: _noted(raw, self.sig, upto, self.since))

        if self.batch:
            kept = to.save(self.palette, lambda: self.world.store_rows(
                to.rows(self.batch, f, self.enc), replace=self.replace, since=self.since,
                also=also))
            self.report.chunks += len(self.batch) - len(kept)
            self.report.kept += len(kept)
            self.batch, self.biomes = [], []
        else:
            to.save(self.palette, lambda: f.save(also=also))  # the staged meta alone
        if self.progress:
            self.progress(self.done, self.total)
