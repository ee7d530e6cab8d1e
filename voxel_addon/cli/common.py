"""Argument and output helpers shared by the commands."""
from __future__ import annotations

import sys
import time
from pathlib import Path


def coord(text: str, unit: int = 1) -> int:
    """argparse type of a horizontal block coordinate (UNIT 16: a chunk's): a whole
    number inside the world (core.chunk.REACH), else argparse's one line."""
    import argparse
    from ..core.chunk import REACH
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"invalid int value: {text!r}") from None
    if not -REACH <= v * unit < REACH:
        raise argparse.ArgumentTypeError(
            f"{text} is outside the world (-{REACH // unit}..{REACH // unit - 1})")
    return v


def chunk_coord(text: str) -> int:
    return coord(text, 16)


def add_world(p, help="world file (.sqlite)"):
    p.add_argument("--world", required=True, type=Path, metavar="W.sqlite", help=help)


class Progress:
    """'label  n/total  rate' on one terminal line; silent when stderr is not a tty."""

    def __init__(self, label: str, unit: str = "chunks", stream=None):
        self.label, self.unit = label, unit
        self.stream = stream or sys.stderr
        self.tty = self.stream.isatty()
        self.t0 = time.perf_counter()
        self._last = 0.0

    def __call__(self, done: int, total: int) -> None:
        now = time.perf_counter()
        if not self.tty or (now - self._last < 0.1 and done < total):
            return
        self._last = now
        rate = done / max(now - self.t0, 1e-9)
        self.stream.write(f"\r{self.label}: {done}/{total} {self.unit} ({rate:.0f}/s)  ")
        if done >= total:
            self.stream.write("\n")
        self.stream.flush()


def note(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


class Writing:
    """Around a command that writes the world file PATH (`with Writing(path, what) as w`,
    the world opened through `w.own(...)`): on success the world is closed (saved);
    on a failure nothing more is written, a file this command created is removed
    (with its -wal and -shm) while one that existed, or that another process made
    meanwhile, never is (WorldFile.created), and a full disk, a
    read-only or locked file becomes one line saying what failed and what was kept
    (core.errors.explain). `w.kept`: a function saying what is in the file so far
    (batch-wise commands), None while nothing is; `w.rest`: what follows "the rest was
    not written" (a resumable command: how to finish it)."""

    def __init__(self, path, what: str, doing: str = "saving"):
        self.path, self.what, self.doing = Path(path), what, doing
        self.new = not any(p.exists() for p in self._files())
        self.created = False  # this command made the file (not only found none at first)
        self.world = None
        self.kept = lambda: None
        self.rest = ""

    def _files(self) -> list[Path]:
        return [self.path] + [self.path.with_name(self.path.name + s)
                              for s in ("-wal", "-shm", "-journal")]

    def own(self, world):
        self.world = world
        self.created = self.created or world.file.created
        return world

    def __enter__(self):
        return self

    def __exit__(self, kind, e, tb):
        if e is None or isinstance(e, KeyboardInterrupt):  # an interrupt keeps what is done
            try:
                self._close(save=True)
            except Exception as e2:  # noqa: BLE001 - the last save failed: same as below
                self._failed(e2, "saving")
            return False
        if isinstance(e, Exception):
            self._failed(e, self.doing)
        return False

    def _close(self, save: bool) -> None:
        w = self.world
        if w is None:
            return
        if save:
            w.close()
        elif w.file.db is not None:
            w.file.close()  # abandon: what is not in the file stays out of it
        self.world = None

    def _failed(self, e: Exception, doing: str) -> None:
        from ..core.errors import explain
        try:
            self._close(save=False)
        except Exception:  # noqa: BLE001 - closing a broken file: the first error is the news
            pass
        removed = False
        if self.created:
            for p in self._files():
                try:
                    p.unlink()
                    removed = True
                except OSError:  # gone already (or never made)
                    pass
            kept = f"nothing was kept ({self.path.name}, which it created, was removed)"
        elif self.new and not self.path.exists():  # failed making it: nothing is there
            kept = f"nothing was kept ({self.path.name} was not made)"
        else:
            kept = self.kept()
            kept = f"{kept}; the rest was not written{self.rest}" if kept else \
                f"nothing of this {self.what} was written; the world is unchanged"
        err = explain(e, self.path, doing, kept)
        if err is e and removed:
            raise type(e)(f"{e} ({self.path.name}, which it created, was removed)") from None
        if err is None or err is e:
            return  # a user mistake says it already; a bug keeps its traceback
        raise err from None


def out_file(path: Path, make_folder: bool = False, world=None) -> Path:
    """Check an output file's path before the work: a folder there, or a missing
    folder above it (made with MAKE_FOLDER), is one line now, not a traceback after;
    so is the file of WORLD (or its journal) there: a typo would write over the world."""
    from ..core.errors import VoxelError
    if path.is_dir():
        raise VoxelError(f"--out {path} is a folder; name a file")
    if world is not None and _is_world(path, Path(world)):
        raise VoxelError(f"--out {path} is the world file itself; name another file")
    if make_folder:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise VoxelError(f"cannot create folder {path.parent}: {e.strerror}") from None
    elif not path.parent.is_dir():
        raise VoxelError(f"folder {path.parent} does not exist")
    return path


def _is_world(path: Path, world: Path) -> bool:
    """Whether PATH is WORLD's file or one of its journals (links and hard links
    followed)."""
    import os
    for p in [world] + [world.with_name(world.name + s) for s in ("-wal", "-shm", "-journal")]:
        if os.path.realpath(path) == os.path.realpath(p):
            return True
        try:
            if os.path.samefile(path, p):
                return True
        except OSError:  # one of them is not there
            pass
    return False


def write_out(path: Path, data) -> None:
    """Write an output file (DATA: bytes, or a Path to copy) under a temporary name,
    then rename: a killed run leaves no half file under the real name, so a file
    that is there is complete (resumable outputs). A failure (a full disk, a
    read-only folder) is one line naming the output, never the world, and leaves
    no part of it."""
    from ..core.files import write_whole
    write_whole(path, data, "; the world is unchanged")
