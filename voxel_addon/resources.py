"""The one module that knows where data files live: gpu/ (OpenCL C) and shaders/ (GLSL).

In the repo they sit beside voxel_addon/; in the extension zip build.py stages them
the same way, so one relative path serves both. `load_source` resolves
`#include "name"` lines (relative to the same folder) once per file, like
moderngl-window's loader, so kernels and shaders can share helpers. `shader_stage`
also marks where each file starts and resumes with `#line` (number: the file's index
in the returned list times LINES plus its line; drivers print the line and some drop
GLSL's source-string number, and MSL takes no number there), so a compiler's message
can name the file (render/glsl.py, Program.where).
"""
from __future__ import annotations

import re
from functools import lru_cache
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
KERNELS = ROOT / "gpu"
SHADERS = ROOT / "shaders"

LINES = 10000  # `#line` numbers: file index * LINES + line
_INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"\s*$', re.M)


@lru_cache(maxsize=None)
def load_source(folder: Path, name: str) -> str:
    """Text of folder/name with #include "x" lines replaced (each file once)."""
    return expand(folder, name)[0]


def expand(folder: Path, name: str, text: str | None = None,
           lines: bool = False) -> tuple[str, tuple[str, ...]]:
    """(text with includes replaced, the files in the order they were first read).
    `text` stands in for folder/name's contents (a test's own shader); with `lines`
    every file's lines are numbered K * LINES + N (`#line` where it starts and after
    each include), K the file's index in the list."""
    seen: list[str] = []

    def read(rel: str, body: str | None = None) -> str:
        if rel in seen:
            return ""
        seen.append(rel)
        k = len(seen) - 1
        if body is None:
            path = folder / rel
            if not path.is_file():
                raise FileNotFoundError(f"{path} (included data file is missing)")
            body = path.read_text(encoding="utf-8")
        if not lines:
            return _INCLUDE.sub(lambda m: read(m.group(1)), body)
        out = [f"#line {k * LINES + 1}"]
        for n, ln in enumerate(body.splitlines(), 1):
            m = _INCLUDE.match(ln)
            if m:
                out += [read(m.group(1)), f"#line {k * LINES + n + 1}"]
            else:
                out.append(ln)
        return "\n".join(out)

    return read(name, text), tuple(seen)


def kernel(name: str) -> str:
    return load_source(KERNELS, name)


def shader(name: str) -> str:
    return load_source(SHADERS, name)


@lru_cache(maxsize=None)
def shader_stage(name: str) -> tuple[str, tuple[str, ...]]:
    """A shader file with its includes and `#line` marks: (text, files)."""
    return expand(SHADERS, name, lines=True)
