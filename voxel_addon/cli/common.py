"""Argument and output helpers shared by the commands."""
from __future__ import annotations

import sys
import time
from pathlib import Path


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


def write_whole(path: Path, data: bytes) -> None:
    """Write under a temporary name, then rename: a killed run leaves no half file
    under the real name, so a file that is there is complete (resumable outputs)."""
    tmp = path.with_name(f".{path.name}.part")
    tmp.write_bytes(data)
    tmp.replace(path)
