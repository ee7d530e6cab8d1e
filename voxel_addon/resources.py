"""The one module that knows where data files live: gpu/ (OpenCL C) and shaders/ (GLSL).

In the repo they sit beside voxel_addon/; in the extension zip build.py stages them
the same way, so one relative path serves both. `load_source` resolves
`#include "name"` lines (relative to the same folder) once per file, like
moderngl-window's loader, so kernels and shaders can share helpers.
"""
from __future__ import annotations

import re
from functools import lru_cache
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
KERNELS = ROOT / "gpu"
SHADERS = ROOT / "shaders"

_INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"\s*$', re.M)


@lru_cache(maxsize=None)
def load_source(folder: Path, name: str) -> str:
    """Text of folder/name with #include "x" lines replaced (each file once)."""
    seen: set[str] = set()

    def expand(rel: str) -> str:
        if rel in seen:
            return ""
        seen.add(rel)
        path = folder / rel
        if not path.is_file():
            raise FileNotFoundError(f"{path} (included data file is missing)")
        return _INCLUDE.sub(lambda m: expand(m.group(1)), path.read_text(encoding="utf-8"))

    return expand(name)


def kernel(name: str) -> str:
    return load_source(KERNELS, name)


def shader(name: str) -> str:
    return load_source(SHADERS, name)
