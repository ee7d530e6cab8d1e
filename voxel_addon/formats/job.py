"""A Minecraft import's resume note (meta `import_job`): the one mechanism by which
an import, in one process (formats/minecraft.py) or on a cluster (cluster/imports.py),
killed mid-way (kill -9, Ctrl-C, a full disk, a power cut) does only what is missing
when the same command runs again.

The note is a JSON list, one {sig, done, since, src, files, options} per unfinished
import (older files: one such object, the last three missing), so two imports into
one world, both killed, both resume. `sig` names the import: its region files (path,
size, mtime), --y-min, --area and --replace; `src` the region files' paths, `files`
their state (size, mtime), `options` the import's options as the command line spells
them (what an import refused over the unfinished one's chunks says). Every batch's
transaction sets its note's `done` (chunks of the plan settled, in plan order) with
the batch's chunks, biome rows and palettes; the import's end drops the note. On
resume, without --replace every chunk of the plan already in the file is ours (the
first run refused to start over any), so it is skipped; with --replace the plan's
first `done` chunks are. `since` is the first run's start: edits saved since then
survive a replace.

Not part of an import's name: --resources (kept in the meta, the last given wins: the
same command with other resources resumes) and --workers/--scheduler (a run in one
process resumes one killed on a cluster and the other way round, the same rows either
way). The same files with other --area, --y-min or --replace, or changed since (the
game saved them again), are another import: a fresh one where none of its chunks is
in the world (or with --replace), else refused with one line naming the unfinished
one."""
from __future__ import annotations

import hashlib
import json
import time

from ..core.errors import VoxelError
from ..storage import minecraft as mcfile

JOB = "import_job"


def notes(raw) -> list:
    """The notes of meta `import_job` (a list, or an older file's one object);
    damaged: none."""
    try:
        got = json.loads(raw) if raw else []
    except ValueError:
        return []
    got = [got] if isinstance(got, dict) else got
    return [j for j in got if isinstance(j, dict)] if isinstance(got, list) else []


def find(raw, sig):
    """The unfinished job of the same import (same files, same options), or None."""
    for job in notes(raw):
        if job.get("sig") == sig and isinstance(job.get("done"), int) \
                and isinstance(job.get("since", 0.0), (int, float)):
            return job
    return None


def noted(raw, sig, done=None, since=None, more=None) -> str:
    """RAW (the notes) with this import's note set to DONE and SINCE (and MORE: what
    a refused other import tells of it), or dropped (DONE None); the other imports'
    notes as they are ("" when none is left)."""
    jobs = [j for j in notes(raw) if j.get("sig") != sig]
    if done is not None:
        jobs.append({"sig": sig, "done": done, "since": since, **(more or {})})
    return json.dumps(jobs) if jobs else ""


def options(y_min, area, replace) -> str:
    """An import's options as the command line spells them."""
    out = [f"--area {' '.join(map(str, area))}"] if area else []
    out += [f"--y-min {y_min}"] if y_min is not None else []
    return " ".join(out + (["--replace"] if replace else []))


def signature(files, y_min, area, replace) -> tuple[str, str, str]:
    """(sig, src, files' state) of an import of FILES (see the module docstring)."""
    h = hashlib.sha256(json.dumps([y_min, area and list(area), bool(replace)]).encode())
    s, t = hashlib.sha256(), hashlib.sha256()   # (sig as the cluster's first notes had it)
    for f in files:
        st = f.stat()
        one = f"{f.resolve()}\0{st.st_size}\0{st.st_mtime_ns}\0".encode()
        h.update(one)
        t.update(one)
        s.update(f"{f.resolve()}\0".encode())
    return h.hexdigest()[:16], s.hexdigest()[:16], t.hexdigest()[:16]


class Job:
    """One import's note: what a run skips (`skip`), how it notes a batch (`note`,
    inside the batch's transaction), its start and end. Made before the first write:
    refuses (VoxelError) an import whose chunks are in the file already, unless it
    resumes or replaces."""

    def __init__(self, file, files, keys, *, y_min=None, area=None, replace=False):
        self.file, self.replace = file, bool(replace)
        self.sig, src, state = signature(files, y_min, area, replace)
        self.more = {"src": src, "files": state, "options": options(y_min, area, replace)}
        got = file.query("SELECT value FROM meta WHERE key=?", (JOB,))  # as it is now
        raw = got[0][0] if got else None
        job = find(raw, self.sig)
        keys = list(keys)
        self.have = set(keys) & set(file.chunk_keys())
        if job is None and self.have and not replace:
            raise VoxelError(f"{len(self.have)} of the {len(keys)} chunks are already in "
                             f"{file.path}{self._why(raw)} import with --replace (Blender: "
                             "Replace) to overwrite them")
        self.resumed = job is not None
        self.noted = False   # this run wrote its note
        self.start = job["done"] if job else 0
        # edits saved from the first run's start on survive a replace (store_rows)
        self.since = job.get("since", time.time()) if job else time.time()
        # how many chunks of the plan a resumed run finds done
        self.skipped = sum(map(self.skip, range(len(keys)), keys)) if job else 0

    def _why(self, raw) -> str:
        """Where the chunks in the way came from, as far as the notes tell."""
        for j in notes(raw):
            if j.get("src") != self.more["src"]:
                continue
            if j.get("files") != self.more["files"]:
                return (", from an unfinished import of these region files before the game "
                        "saved them again (it cannot resume);")
            opts = j.get("options")
            how = f"with {opts}" if opts else "without --area, --y-min or --replace"
            return (f", from an unfinished import of these region files {how}: the same "
                    "import again finishes it, or")
        return " (imported before, or generated);"

    def skip(self, i: int, key) -> bool:
        """Whether the plan's Ith chunk (KEY) was done by the run this one resumes."""
        if not self.resumed:
            return False
        return key in self.have if not self.replace else i < self.start

    def line(self, total: int) -> str | None:
        """What a resumed run says (None: not resumed)."""
        if not self.resumed:
            return None
        return (f"resuming an interrupted import: {self.skipped} of {total} chunks already "
                "imported")

    def begin(self) -> None:
        """Before the first batch: a --replace import notes its start (a run killed
        before its first batch resumes with its `since`); any other is noted with its
        first batch, so one refused before it (a hostile chunk) leaves the file as it
        was."""
        if self.replace and not self.resumed:
            self.file.update_meta(JOB, lambda raw: noted(raw, self.sig, self.start,
                                                         self.since, self.more))
            self.noted = True

    def note(self, db, done: int) -> None:
        """In a batch's transaction: the plan's first DONE chunks are settled (the
        other imports' notes as the file holds them)."""
        mcfile.update(db, JOB, lambda raw: noted(raw, self.sig, done, self.since, self.more))
        self.noted = True

    def end(self) -> None:
        """Finished: this import's note dropped (the other imports' stay)."""
        if self.noted or self.resumed:
            self.file.update_meta(JOB, lambda raw: noted(raw, self.sig))
