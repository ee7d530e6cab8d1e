"""How a test starts a Python child of its own kind.

Under the bpy module that is `sys.executable ARGS`. Under tests/run.py inside the real
Blender application, sys.executable is a Python that cannot `import bpy`, so the child
is that Blender in background mode running this file, which runs ARGS as `python ARGS`
would (a script path or `-m module`, then its arguments) and exits with its code.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BLENDER_ENV = "VOXEL_TEST_BLENDER"  # set by tests/run.py: the launcher of that Blender


def python_cmd(*args) -> list[str]:
    """The command line for `python ARGS` in this interpreter's kind of host."""
    blender = os.environ.get(BLENDER_ENV)
    if not blender:
        return [sys.executable, *map(str, args)]
    return [blender, "-b", "--factory-startup", "--quiet", "--python-exit-code", "1",
            "--python", str(Path(__file__).resolve()), "--", *map(str, args)]


def blender_paths() -> None:
    """Inside the real Blender: the checkout and its .blender/<suite>/site (pytest and
    the wheels for its Python that build.py setup installs there; the launcher names it
    in VOXEL_BLENDER_SITE) importable; Blender's own numpy wins."""
    for p in (os.environ.get("VOXEL_BLENDER_SITE"), str(ROOT)):
        if p and p not in sys.path:
            sys.path.insert(0, p)


def _main() -> None:  # inside Blender: run ARGS like `python ARGS`
    import runpy
    import traceback
    args = sys.argv[sys.argv.index("--") + 1:]
    blender_paths()
    code = 0
    try:
        if args[0] == "-m":
            sys.argv = [args[1], *args[2:]]
            runpy.run_module(args[1], run_name="__main__", alter_sys=True)
        else:
            sys.argv = args
            runpy.run_path(args[0], run_name="__main__")
    except SystemExit as e:
        code = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
        if not isinstance(e.code, (int, type(None))):
            print(e.code, file=sys.stderr)
    except BaseException:  # noqa: BLE001 - like python: traceback, exit 1
        traceback.print_exc()
        code = 1
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


if __name__ == "__main__" and "--" in sys.argv:
    _main()
