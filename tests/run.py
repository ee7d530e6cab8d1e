"""Run the pytest suite inside a Blender binary:

    blender -b --factory-startup -P tests/run.py [-- PYTEST_ARGS]

Blender's exit code is pytest's. Blender's bundled Python has no pytest: if it cannot
be imported, the checkout's .venv site-packages (python build.py setup) are appended
to sys.path — appended, so Blender's own bpy and numpy still win. Otherwise install
pytest into Blender's Python (`<blender>/5.0/python/bin/python3 -m pip install pytest`).
"""
from __future__ import annotations

import glob
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main() -> int:
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    os.chdir(ROOT)
    sys.path.insert(0, ROOT)
    try:
        import pytest
    except ImportError:
        v = f"python{sys.version_info.major}.{sys.version_info.minor}"
        sys.path += glob.glob(os.path.join(ROOT, ".venv", "lib", v, "site-packages"))
        try:
            import pytest
        except ImportError:
            print("tests/run.py: pytest is not importable in Blender's Python; run "
                  "`python build.py setup` (same Python minor version) or pip-install "
                  "pytest into Blender's Python", file=sys.stderr)
            return 2
    return int(pytest.main(args or [os.path.join(ROOT, "tests")]))


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)  # Blender would otherwise exit 0 after a -P script
