"""The writer of a cluster `import` (cluster/imports.py): results settled in plan
order into the report, the palettes and batches of rows, committed with the batch's
biome rows and this import's resume note (formats/job.py, meta `import_job`) in one
transaction."""
from __future__ import annotations

import numpy as np

from ..core.errors import VoxelError
from ..formats.budget import Exceeded
from ..storage import minecraft as mcfile

class _Writer:
    """Results in plan order into the report, the palette and batches of rows."""

    def __init__(self, world, report, job, progress, total, budget):
        from ..core import colors
        self.world, self.report, self.job, self.budget = world, report, job, budget
        self.replace, self.since, self.old = job.replace, job.since, 0
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
            self.job.note(db, upto)

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
