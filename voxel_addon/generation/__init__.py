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


def make_generator(name: str, seed: int, params: dict | None = None, backend: str | None = None,
                   version: int | None = None):
    """A generator; version None: the newest (what a new world gets)."""
    return generator_class(name)(seed, params, backend, version)


def for_file(wf, backend: str | None = None):
    """The generator of an open world file (storage.WorldFile): its name, seed and
    params at the version it was created with, so a world keeps generating the same
    terrain whatever the newest version is. The one place that reads that version:
    World.open, the CLI and the cluster workers (the World's generator) go through it.
    A file without one predates versions: version 1, what it was made with."""
    version = wf.generator_version  # (damaged settings: a VoxelError)
    try:
        return make_generator(wf.generator, wf.seed, wf.generator_params, backend, version)
    except (ValueError, TypeError, KeyError, IndexError, AttributeError, ArithmeticError) as e:
        # a hostile or damaged meta row: one line, not a traceback
        raise VoxelError(f"{wf.path}: its generator settings are damaged "
                         f"({type(e).__name__}: {e})") from None


def default_backend() -> str:
    """"opencl" when an OpenCL device is present, else "numpy" (opencl.pick)."""
    from .. import opencl
    return opencl.pick()
