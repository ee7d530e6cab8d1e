"""Terrain generators (SPEC F4, F5): noise, the pass language with NumPy and OpenCL backends, Overworld, Flat. Depends only on core and resources."""
from __future__ import annotations

import importlib

from ..core.errors import VoxelError

# name -> "module:Class"; imported on demand so registering the add-on stays cheap.
GENERATORS = {
    "flat": "flat:FlatGenerator",
    "overworld": "overworld:OverworldGenerator",
    "empty": "empty:EmptyGenerator",  # air: worlds an import creates (issue 21)
}
DEFAULT = "overworld"


def generator_class(name: str):
    try:
        module, cls = GENERATORS[name].split(":")
    except KeyError:
        raise VoxelError(f"unknown generator {name!r} (known: {', '.join(GENERATORS)})") from None
    return getattr(importlib.import_module(f".{module}", __name__), cls)


def make_generator(name: str, seed: int, params: dict | None = None, backend: str | None = None):
    return generator_class(name)(seed, params, backend)


def default_backend() -> str:
    """"opencl" when an OpenCL device is present, else "numpy" (opencl.pick)."""
    from .. import opencl
    return opencl.pick()
