"""The command line (SPEC §5): one module per command, each with add_parser(sub) and run(args)."""
from __future__ import annotations

import argparse
import importlib
import sys

from ..core.errors import VoxelError

# Order is the order of `--help`. A command's module may be missing until its issue lands.
COMMANDS = ["generate", "info", "dump", "edit", "map", "render", "animate", "bake", "importer",
            "exporter", "far", "bench"]


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2, like every other user mistake
        self.exit(2, f"{self.prog}: error: {message}\n")


def parser(only: str | None = None) -> argparse.ArgumentParser:
    """The whole command line, or with `only` (a module of COMMANDS) that command's
    alone: a command run does not import what the others' options list (meshing,
    render, bench: a tenth of a second before an import or a generate starts)."""
    p = _Parser(prog="python -m voxel_addon",
                description="Voxel Worlds: generate, inspect, edit, render and bake voxel worlds.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for name in [only] if only else COMMANDS:
        try:
            mod = importlib.import_module(f".{name}", __name__)
        except ModuleNotFoundError as e:
            if e.name == f"{__name__}.{name}":
                if only:
                    return parser()
                continue
            raise
        sp = mod.add_parser(sub)
        sp.set_defaults(_run=mod.run)
    return p


def _module(argv) -> str | None:
    """The module of the command argv starts with, when it starts with one."""
    first = argv[0] if argv else ""
    name = {"import": "importer", "export": "exporter"}.get(first, first)
    return name if name in COMMANDS and first not in ("importer", "exporter") else None


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    only = _module(argv)
    args = parser(only).parse_args(argv)
    try:
        return args._run(args) or 0
    except VoxelError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    except Exception as e:  # a full disk, a locked file...: one line too (core.errors)
        from ..core.errors import explain
        err = explain(e, getattr(args, "world", None), f"running {args.command} on")
        if err is None:
            raise  # a bug: its traceback is what helps
        print(f"error: {err}", file=sys.stderr)
        return 2
