"""The real Blender GUI for the viewport and edit areas (not an area itself): the
checkout's tools/blender_app.py starts it under a private Xvfb, and the Blender-side
jobs are tools/<area>_bench_job.py. Both live outside the package (an installed
add-on has no .blender/ to run), so they are found by path, never imported by name.
"""
from __future__ import annotations

import importlib.util
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TOOLS = ROOT / "tools"


def app():
    """tools/blender_app.py as a module, or None outside a checkout."""
    path = TOOLS / "blender_app.py"
    if not path.exists():
        return None
    import sys
    mod = sys.modules.get("voxel_blender_app")
    if mod is None:
        spec = importlib.util.spec_from_file_location("voxel_blender_app", path)
        mod = importlib.util.module_from_spec(spec)
        sys.modules[spec.name] = mod  # (its dataclasses look their module up there)
        spec.loader.exec_module(mod)
    return mod


def variants() -> list[tuple[str, str]]:
    """(application, backend) of every installed Blender and each GPU backend it is
    set up for, e.g. [("5.2", "opengl"), ("5.2", "vulkan"), ("4.3", "opengl")]."""
    a = app()
    return [(x.version, b) for x in a.apps() for b in x.backends]


def missing() -> str | None:
    """None when the GUI areas can run, else why not."""
    a = app()
    return "not a checkout (no tools/blender_app.py)" if a is None else a.gui_missing()


def run_job(area: str, args, result: Path, log: Path, timeout: float, simulate: bool,
            blender=None, gpu: str | None = None, env: dict | None = None) -> dict:
    """tools/AREA_bench_job.py in the Blender GUI with ARGS (BLENDER: which application,
    e.g. "4.3"; GPU: its backend, "opengl" or "vulkan"; None: blender_app's defaults;
    ENV: more environment); the JSON it wrote to RESULT."""
    app().run(["--factory-startup", "-P", TOOLS / f"{area}_bench_job.py", "--", *args],
              log=log, timeout=timeout, simulate=simulate, app=blender, gpu=gpu, env=env)
    if not result.exists():
        raise RuntimeError(f"the Blender job wrote nothing:\n{log.read_text(errors='replace')[-4000:]}")
    return json.loads(result.read_text())
