"""Import a Minecraft Java world (or region files) into a world (issue 21).

Minecraft block (x, y, z) becomes voxel (x, -1-z, y - y_min): not mirrored, north
(-z) is +y, chunk (cx, cz) is chunk (cx, -cz-1); layers outside z 0..255 are dropped
and counted. Chunks Minecraft has not finished (Status other than full) are skipped
and counted; a damaged chunk (one from before 1.13 too) is skipped with its one-line
reason; a hostile file (a region header with shared sectors, an import budget spent:
formats/budget.py) refuses the import with one line. What can be checked is checked
before the first write: region headers and level.dat (when the files are listed),
chunks already in the world, a level.dat from before 1.13; a world whose chunks are
all from before 1.13 is refused having written nothing. Chunks go to the file in
batches, each one transaction (with the palettes they use and their biome rows): an
interrupted import keeps every finished batch, and no chunk is ever half-written
(nor without its biomes); each batch's transaction also notes how far the import got
(formats/job.py, meta `import_job`, as a cluster's import), so the same import run
again after a kill, a Ctrl-C, a full disk or a power cut does only what is missing and
ends with the world an uninterrupted one makes (the same rows: it goes on from the
palettes the batches written so far committed). Whether a chunk is already in the
file is decided again inside each batch's transaction (World.store_chunks), so a
chunk another writer stored while the import ran is kept (counted in `kept`), and
with replace the edits saved since the import started are applied over the imported
one. The palettes (states, colours, defaults, biome names) go with a batch only
while the file holds those they were built on: when another writer added to them
meanwhile, the batch is mapped onto the file's and written again (mcstate.ToFile).
"""
from __future__ import annotations

import gzip
import json
import os
from collections import Counter, deque
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from ..core import chunk as C
from ..core import colors
from ..core.blocks import REGISTRY
from ..core.errors import VoxelError
from ..storage import minecraft as mcfile
from . import anvil, mapping, mcstate, nbt, region
from .budget import Budget, Exceeded
from .job import Job
from .convert import convert
from .region import MAX_NBT, External, Region, RegionError, decompress

BATCH = 32
GROUP = 16   # chunks a helper task inflates
AHEAD_MAX = 1 << 20   # bytes of one chunk's NBT inflated ahead (real ones: tens of KB)
LAYOUTS = ("dimensions/minecraft/overworld/region", "region")  # 26.1 first, then older
LEVEL_KEEP = {"Data": {"DataVersion": None}}
LEVEL_TAGS = 1 << 18   # a level.dat has hundreds to thousands
LEVEL_BYTES = 16 << 20  # and tens of KB


@dataclass
class Report:
    chunks: int = 0                      # imported
    kept: int = 0                        # stored by another writer meanwhile: left as they were
    unfinished: Counter = field(default_factory=Counter)   # skipped, by Status
    damaged: list = field(default_factory=list)            # one-line reasons
    external: int = 0                    # in .mcc files, not read
    dropped: int = 0                     # non-air voxels outside z 0..255
    blocks: dict = field(default_factory=dict)  # mc name -> [block, how, count]
    y_min: int = 0
    version: int | None = None
    resumed: int = 0                     # chunks an interrupted run of this import had done

    def take_version(self, version, y_min=None) -> None:
        """The import's DataVersion, and the Minecraft y that becomes z 0: Y_MIN when
        given, else -64 from 1.18 on and 0 before (0 without a version)."""
        self.version = version
        self.y_min = y_min if y_min is not None else (
            -64 if version is not None and version >= anvil.V_NO_LEVEL else 0)

    def lines(self) -> list[str]:
        out = [f"{self.chunks} chunks imported (y_min {self.y_min}"
               f"{'' if self.version is None else f', DataVersion {self.version}'})"]
        if self.resumed:
            out.append(f"resumed: {self.resumed} chunks were imported by an interrupted run")
        if self.unfinished:
            out.append("skipped, not finished by Minecraft: " + ", ".join(
                f"{n} {s or '?'}" for s, n in self.unfinished.most_common()))
        if self.kept:
            out.append(f"kept, stored in the world by another writer during the import: "
                       f"{self.kept}")
        if self.external:
            out.append(f"skipped, stored in external .mcc files: {self.external}")
        if self.damaged:
            out.append(f"skipped, damaged: {len(self.damaged)}")
            out += [f"  {m}" for m in self.damaged[:10]]
        if self.dropped:
            out.append(f"dropped outside z 0..255: {self.dropped} voxels")
        out.append("blocks (minecraft name -> block, how, voxels):")
        for name, (b, how, n) in sorted(self.blocks.items(), key=lambda kv: -kv[1][2]):
            out.append(f"  {name} -> {b} ({how}) {n}")
        return out


def regions_of(path) -> list[Path]:
    """The region files of a save folder (both layouts), a folder of .mca files or
    one .mca file; their headers checked (check_headers) and a hostile level.dat
    refused, so that callers learn it before they make anything."""
    path = Path(path)
    if path.is_file():
        if path.suffix != ".mca":
            raise VoxelError(f"{path} is not a region file (.mca)")
        check_headers([path])
        return [path]
    if not path.is_dir():
        raise VoxelError(f"{path} does not exist")
    level_version(path)
    for sub in LAYOUTS:
        if (path / sub).is_dir():
            path = path / sub
            break
    files = sorted(p for p in path.glob("r.*.mca") if p.is_file())
    if not files:
        raise VoxelError(f"no region files (r.X.Z.mca) in {path} (nor in region/ or "
                         "dimensions/minecraft/overworld/region/)")
    check_headers(files)
    return files


def _refused(f, e) -> VoxelError:
    msg = str(e)
    name = f"{Path(f).name}: "
    return VoxelError(f"{f}: {msg[len(name):] if msg.startswith(name) else msg}")


def check_headers(files) -> None:
    """Refuse damaged or hostile region headers (shared sectors, sectors in the header
    or past the file) reading 8 KiB of each: before anything is written."""
    for f in files:
        try:
            region.check(f)
        except (OSError, RegionError) as e:
            raise _refused(f, e) from None


def level_version(path) -> int | None:
    """DataVersion from a save folder's level.dat, or None (a damaged one is ignored,
    one of more than LEVEL_TAGS tags or LEVEL_BYTES refused)."""
    f = Path(path) / "level.dat"
    if not f.is_file():
        return None
    try:
        with gzip.open(f) as g:
            raw = g.read(LEVEL_BYTES + 1)
        if len(raw) > LEVEL_BYTES:
            raise Exceeded(f"inflates past {LEVEL_BYTES >> 20} MiB")
        data = nbt.parse(raw, LEVEL_KEEP, LEVEL_TAGS).get("Data", {})
    except Exceeded as e:
        raise VoxelError(f"{f}: {e} (a hostile file?)") from None
    except (OSError, EOFError, ValueError):
        return None
    v = data.get("DataVersion") if isinstance(data, dict) else None
    return v if isinstance(v, int) else None


def to_key(cx: int, cz: int) -> tuple[int, int]:
    return (cx, -cz - 1)


class _Palettes:
    """Minecraft block states -> (block id, data): data is the state's index in the
    world's state palette (formats/mcstate.py; stored as 0 where it is its block's
    default: settle), or for the `color` block the index of the state's own colour in
    the world's colour palette."""

    def __init__(self, world, report: Report):
        self.world, self.report = world, report
        self.colors = colors.parse(world.file.meta)
        self.states = mcstate.States(world.file)
        self.to_file = mcstate.ToFile(self.states)
        self.ids: dict = {}
        self.keyed: dict = {}
        self.changed = False

    def of(self, name: str, props: dict | None = None) -> tuple[int, int]:
        key = (name, tuple(sorted(props.items())) if props else ())
        got = self.ids.get(key)
        if got is None:
            block, rgb, how = mapping.lookup(name)
            bid = REGISTRY.id(block)
            d = 0
            if bid:
                st = self.states.of(name, props)
                d = st
                if rgb is not None:
                    self.colors, d = self.states.color(st, self.colors, rgb)
                    self.changed = True
            got = self.ids[key] = (bid, d)
            self.report.blocks.setdefault(name, [block, how, 0])
        return got

    def settle(self, ids, vals, counts):
        return self.states.settle(ids, vals, counts)

    def save(self) -> None:
        """Stage the palettes (written with the next chunks, in their transaction)."""
        self.to_file.stage(self.colors, self.changed)
        self.changed = False


def plan(path, area=None) -> list[tuple[Region, int, int]]:
    """(region, cx, cz) of every stored chunk in `area` (Minecraft blocks x0 z0 x1 z1,
    half-open: chunks that touch it)."""
    out = []
    for f in regions_of(path):
        try:
            reg = Region(f)
        except (OSError, RegionError) as e:
            raise _refused(f, e) from None
        for cx, cz in reg.chunks():
            if area is not None:
                x0, z0, x1, z1 = area
                if not (16 * cx < x1 and 16 * cx + 16 > x0 and 16 * cz < z1 and 16 * cz + 16 > z0):
                    continue
            out.append((reg, cx, cz))
    return out


def import_world(world, path, *, y_min=None, area=None, replace=False, progress=None,
                 cancelled=None, report: Report | None = None, resources=None,
                 say=None) -> Report:
    """Import the chunks of a save folder / region files into `world` (see the
    module docstring). `progress(done, total)`; `cancelled()` -> True stops after
    the batch in hand (what was written stays, and the same import resumes); `report`
    is filled as it goes (what is in the file when it fails). `resources`: the
    resource stack's paths (checked by the caller), kept in the world's meta for
    renders, bakes and the live view. `say(line)`: told when the import resumes."""
    report = Report() if report is None else report
    for done, total in steps(world, path, report, y_min=y_min, area=area, replace=replace,
                             resources=resources, say=say):
        if progress:
            progress(done, total)
        if cancelled is not None and cancelled():
            break  # the batches written so far stay
    return report


def _inflate(items):
    """Each (region, cx, cz)'s NBT when it inflates to at most AHEAD_MAX bytes, else
    None (the import's thread decodes it as before: a bomb is never held ahead), or
    the error of reading its sectors."""
    out = []
    for reg, cx, cz in items:
        try:
            kind, body = reg.raw(cx, cz)
        except RegionError as e:
            out.append(e)
            continue
        try:
            out.append(decompress(kind, body, AHEAD_MAX))
        except ValueError:   # larger, or damaged: decoded again with the real limits
            out.append(None)
    return out


def _scan(inflated):
    """_inflate's answers (a future of them), each NBT as (NBT, anvil.scanned of it):
    the well-formed chunks read ahead (their NumPy work lets go of the GIL while the
    import's thread converts), their tags charged by the import's thread (_charged)."""
    return [x if x is None or isinstance(x, BaseException)
            else (x, anvil.scanned(bytes(x), packed=True)) for x in inflated.result()]


class _Inline:
    """The helper's interface without a thread: each task runs when submitted."""

    def submit(self, fn, *args):
        f = Future()
        try:
            f.set_result(fn(*args))
        except BaseException as e:   # handed over as the thread's future would
            f.set_exception(e)
        return f

    def shutdown(self, **kw):
        pass


def _helper():
    """The import's helper thread; none with VOXEL_IMPORT_THREAD=0 or on one core."""
    if os.environ.get("VOXEL_IMPORT_THREAD", "1") == "0" or (os.cpu_count() or 1) < 2:
        return _Inline()
    return ThreadPoolExecutor(1, thread_name_prefix="mc-import")


class _Blank:
    """Zeroed chunk arrays for convert: those of chunks already compressed (zeroed by
    _rows on the helper, while they are in its cache, and handed back at once: no
    more arrays alive than without them): new ones cost their pages' first touch, a
    few times a zeroing. At most HELD kept."""
    HELD = 2 * BATCH

    def __init__(self):
        self.free: list = []

    def __call__(self):
        try:
            return self.free.pop()   # list.pop and append: atomic across the threads
        except IndexError:
            return C.empty()

    def give(self, a) -> None:
        if a is not None and len(self.free) < self.HELD:
            a.fill(0)
            self.free.append(a)


def _rows(enc, items, blank=None):
    """Each (key, blocks, data)'s row; the arrays then go back to `blank` (_Blank)."""
    out = []
    for k, b, d in items:
        out.append(enc.row(k, b, d))
        if blank is not None:
            blank.give(b)
            blank.give(d)
    return out


def _charged(got, reg, cx, cz, budget):
    """_inflate's answer charged to the import's budget: what anvil.read(reg.payload(cx,
    cz, budget), budget, packed=True) gives. While the budget has MAX_NBT left that is
    the same decode (it fits the limit), and the helper's read is that chunk while its
    tags fit what is left; a chunk _inflate left, or one near the budget's end, is
    decoded again here under what is left, and a chunk the fast path left (or one
    whose tags do not fit) read here by the general reader: what read does after its
    fast path gives up (so this thread never scans while the helper does)."""
    if got is None or budget.bytes < MAX_NBT:
        return anvil.read(reg.payload(cx, cz, budget), budget, fast=False)
    if isinstance(got, BaseException):
        raise got
    payload, pre = got
    budget.spend_bytes(len(payload))
    if pre is not None and pre[1] <= anvil.limit_of(budget):
        budget.spend_tags(pre[1])
        return pre[0]
    return anvil.read(payload, budget, fast=False)


def first_version(todo, budget):
    """DataVersion of the first readable chunk of TODO (what the import's y_min
    follows without a level.dat); what it decodes is charged to the import's budget
    (a hostile file is refused)."""
    for reg, cx, cz in todo:
        try:
            return anvil.read(reg.payload(cx, cz, budget), budget).version
        except Exceeded as e:
            raise VoxelError(f"{reg.path.name} chunk ({cx}, {cz}): {e}; import refused") \
                from None
        except (RegionError, anvil.ChunkError, nbt.NbtError):
            continue
    return None


def steps(world, path, report: Report, *, y_min=None, area=None, replace=False,
          resources=None, say=None):
    """The import as a generator of (chunks done, total), one step per batch written,
    filling `report`. Closing it early keeps every batch written so far; the same
    import run again resumes (formats/job.py: `say(line)` is told so)."""
    todo = plan(path, area)
    keys = [to_key(cx, cz) for _, cx, cz in todo]
    # refuses chunks in the file unless resumed or replaced; `since`: edits saved from
    # the first run's start on survive a replace (store_chunks)
    job = Job(world.file, regions_of(path), keys, y_min=y_min, area=area, replace=replace)
    version = level_version(path) if Path(path).is_dir() else None
    if version is not None and version < anvil.V_FLATTENING:  # refused before any write
        raise VoxelError(f"{Path(path).name}: level.dat has DataVersion {version}, before 1.13 "
                         "(numeric block ids); open and save the world in Minecraft 1.13 "
                         "or newer first")
    old = 0  # chunks from before 1.13: skipped like damaged ones, unless all are
    budget = Budget.of_input(sum(r.stored for r in {id(t[0]): t[0] for t in todo}.values()))
    total = len(todo)
    if job.resumed:
        # the chunks done are not read again (their palettes are the file's); y_min
        # follows the plan's first chunk, as in the run resumed
        report.resumed = job.skipped
        if say:
            say(job.line(total))
        if job.skipped and version is None:
            version = first_version(todo, budget)
        if version is not None:
            report.take_version(version, y_min)
            world.file.stage_meta(mcfile.Y_MIN, str(report.y_min))
        at = [i for i, k in enumerate(keys) if not job.skip(i, k)]
        todo = [todo[i] for i in at]
    else:
        at = range(total)
    job.begin()
    pal = _Palettes(world, report)
    if resources is not None:   # written with the first batch
        world.file.stage_meta(mcstate.RESOURCES, json.dumps([str(r) for r in resources]))
    # one helper thread inflates chunks ahead (GROUP a task) and compresses each
    # batch's rows while the next batch is converted (zlib and zstd let go of the GIL;
    # few, large tasks: each hand-over of the GIL costs), the other reads the inflated
    # chunks (anvil.scanned); this thread converts and writes. Per 1,000 chunks, CPU:
    # ~0.26 s here, 0.28 inflating and compressing, 0.20 reading (a fourth thread, to
    # inflate alone, cost ~6 % more CPU on 2 busy cores: more hand-overs of the GIL).
    # A batch is written once the next one is converted, in the same order and with
    # the same staged meta as one after the other; an error writes the batch in hand
    # first, as the sequential import had (a close at a yield drops the one ahead).
    ex, ex_rows = _helper(), _helper()
    enc = world.file.encoder()
    ahead, got = deque(), deque()
    nxt = 0
    batch, biomes, pending = [], [], None
    blank = _Blank()

    def flush():
        nonlocal pending
        fut, bio, upto = pending
        pending = None
        rows, to = fut.result(), pal.to_file
        # the biome rows of the chunks written, in their transaction (mapped onto the
        # file's palettes as they are when another writer added to them)
        def also(db, written):   # and how far the import got (formats/job.py)
            mcfile.put(db, [(k, b) for k, b in to.columns(bio) if k in written])
            job.note(db, upto)

        kept = to.save(pal.colors, lambda: world.store_rows(
            to.rows(rows, world.file, enc), replace=replace, since=job.since, also=also))
        report.chunks += len(rows) - len(kept)
        report.kept += len(kept)
        return upto

    try:
        for n, (reg, cx, cz) in enumerate(todo, 1):
            done = at[n - 1] + 1   # chunks of the plan settled with this one
            while nxt < len(todo) and len(ahead) < 2:
                ahead.append(ex.submit(_scan, ex_rows.submit(_inflate, todo[nxt:nxt + GROUP])))
                nxt += GROUP
            if not got:
                got.extend(ahead.popleft().result())
            try:
                ch = _charged(got.popleft(), reg, cx, cz, budget)
            except Exceeded as e:
                raise VoxelError(f"{reg.path.name} chunk ({cx}, {cz}): {e}; import refused") \
                    from None
            except External:
                report.external += 1
                ch = None
            except (RegionError, anvil.ChunkError, nbt.NbtError) as e:
                msg = str(e)
                old += "before 1.13" in msg
                report.damaged.append(msg if msg.startswith(reg.path.name)
                                      else f"{reg.path.name} chunk ({cx}, {cz}): {msg}")
                ch = None
            if ch is not None:
                if report.version is None:
                    report.take_version(version if version is not None else ch.version, y_min)
                    world.file.stage_meta(mcfile.Y_MIN, str(report.y_min))
                if ch.status not in anvil.DONE:
                    report.unfinished[ch.status] += 1
                else:
                    blocks, data, dropped = convert(ch, report.y_min, pal, blank)
                    report.dropped += dropped
                    key = to_key(cx, cz)
                    cols = pal.states.columns(ch, blocks, report.y_min)
                    batch.append((key, blocks, data))
                    if cols is not None:
                        biomes.append((key, cols))
            if len(batch) >= BATCH or (n == len(todo) and batch):
                upto = flush() if pending else None
                pal.save()   # staged for this batch's transaction, as before
                pending = (ex_rows.submit(_rows, enc, batch, blank), biomes, done)
                batch, biomes = [], []
                if upto is not None:
                    yield upto, total
        if pending:
            yield flush(), total
    except GeneratorExit:   # closed at a yield: the sequential import had written
        raise               # up to that batch, not the one converted since
    except BaseException:
        if pending:   # the batch in hand, written as the sequential import had
            flush()
        raise
    finally:
        ex.shutdown(wait=True, cancel_futures=True)
        ex_rows.shutdown(wait=True, cancel_futures=True)
    job.end()   # done: this import's note dropped (other imports' stay)
    if old and old == len(report.damaged) and not (report.chunks or report.unfinished
                                                   or report.resumed):
        # nothing written: a world Minecraft never saved in 1.13+ is refused whole
        raise VoxelError(f"none of the {old} chunks is from Minecraft 1.13 or newer, nothing "
                         f"was imported ({report.damaged[0]})")
    if report.version is None:
        report.y_min = y_min if y_min is not None else 0
    yield total, total
