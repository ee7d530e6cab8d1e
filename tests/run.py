"""Run the Blender-facing tests inside the real Blender application:

    python build.py blender -- -b --factory-startup --python-exit-code 1 -P tests/run.py [-- PYTEST_ARGS]

(any Blender works: `blender -b -P tests/run.py`). Without PYTEST_ARGS it runs
BLENDER_FACING, the tests that use bpy, Blender's GL context or its glTF exporter.
Blender's exit code is pytest's. pytest and the extension's wheels for that Blender's
Python come from .blender/<suite>/site (`python build.py setup`; the launcher names it
in VOXEL_BLENDER_SITE); for another Blender's Python, put pytest
on its path yourself (e.g. `<blender>/<version>/python/bin/python3 -m pip install pytest`).
Children that need bpy are started as that Blender again (tests/host.py).
"""
from __future__ import annotations

import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BLENDER_FACING = ["tests/blender", "tests/bake"]


def main() -> int:
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    os.chdir(ROOT)
    sys.path.insert(0, ROOT)
    from tests import host
    host.blender_paths()
    import bpy  # children that need bpy run this Blender again: build.py setup's
    # launcher (it sets VOXEL_BLENDER: the binary needs its loader), else the binary
    os.environ[host.BLENDER_ENV] = os.environ.get("VOXEL_BLENDER") or bpy.app.binary_path
    try:
        import pytest
    except ImportError:
        print("tests/run.py: pytest is not importable in Blender's Python; run "
              "`python build.py setup` or pip-install pytest into Blender's Python",
              file=sys.stderr)
        return 2
    return int(pytest.main(args or [os.path.join(ROOT, t) for t in BLENDER_FACING]))


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)  # Blender would otherwise exit 0 after a -P script
