"""GUI test harness: the real Blender application (not -b) in its own Xvfb X server.

    from tests.gui.harness import run_gui, fresh_user
    res = run_gui(SCRIPT, out=tmp_path / "out", user=fresh_user(tmp_path / "user"),
                  params={"zip": str(zip_path)}, timeout=120)
    res.result          # the script's gui.result (JSON)
    res.image("open")   # a screenshot, (H, W, 3) uint8, top row first
    res.shot("open")    # its PNG path
    res.ys(y)           # window y (origin bottom-left, as Blender gives it) -> image row

Which Blender and GPU backend: VOXEL_BLENDER_APP ("sid", "trixie", "5.2", "4.3";
default the newest) and VOXEL_GPU_BACKEND ("opengl", default, or "vulkan"), read by
tools/blender_app.py (build.py test sets them per layer).

SCRIPT is a Python file run inside Blender by runner.py (see its docstring: a
`run(gui)` generator; `yield` lets Blender handle events and redraw). A script that
raises fails the test with the Blender-side traceback (GuiError); a run past its time
limit is killed with its whole process group (Blender and the X server) and fails.
"""
from __future__ import annotations

import json
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from tools import blender_app as app

ROOT = app.ROOT
RUNNER = Path(__file__).with_name("runner.py")
SIZE = app.SIZE


class GuiError(AssertionError):
    pass


def fresh_user(dest: Path) -> Path:
    """A new Blender user folder whose preferences have the splash off (saved once per
    application: an older Blender does not read a newer one's preferences)."""
    blender = app.get()
    template = blender.gui_user
    if not (template / "config" / "userpref.blend").exists():
        tmp = Path(tempfile.mkdtemp(prefix="gui-user.", dir=template.parent))
        expr = ("import bpy; p = bpy.context.preferences; p.view.show_splash = False; "
                "p.use_preferences_save = False; bpy.ops.wm.save_userpref()")
        r = subprocess.run([str(blender.launcher), "-b", "--python-expr", expr], env=app.app_env(tmp),
                           capture_output=True, text=True, timeout=120)
        if r.returncode or not (tmp / "config" / "userpref.blend").exists():
            raise GuiError(f"could not save preferences:\n{r.stdout[-2000:]}{r.stderr[-2000:]}")
        try:
            tmp.rename(template)
        except OSError:  # another run made it meanwhile
            shutil.rmtree(tmp, ignore_errors=True)
    dest.mkdir(parents=True, exist_ok=True)
    shutil.copytree(template / "config", dest / "config", dirs_exist_ok=True)
    return dest


@dataclass
class GuiResult:
    out: Path
    result: dict
    shots: list[str]
    size: tuple[int, int]
    version: str
    log: str = field(repr=False, default="")

    def shot(self, name: str) -> Path:
        return self.out / f"{name}.png"

    def image(self, name: str):
        """The screenshot NAME as (H, W, 3) uint8, top row first, cropped to the window."""
        import numpy as np
        from matplotlib.image import imread
        px = imread(self.shot(name))
        px = (px[..., :3] * 255 + 0.5).astype(np.uint8) if px.dtype != np.uint8 else px[..., :3]
        return px[:self.size[1], :self.size[0]]

    def ys(self, y: int) -> int:
        """Image row of window y (Blender's window coordinates start at the bottom)."""
        return self.size[1] - 1 - int(y)

    def crop(self, name: str, rect):
        """The pixels of window rectangle [x, y, w, h] (as gui.rect gives it)."""
        x, y, w, h = rect
        top = self.size[1] - (y + h)
        return self.image(name)[top:top + h, x:x + w]


def run_gui(script: Path, out: Path, user: Path, params: dict | None = None,
            timeout: float = 180.0, size=SIZE, args=(), env: dict | None = None) -> GuiResult:
    """Run SCRIPT in the real Blender under Xvfb; fail with its traceback or on timeout.
    ENV: more environment for Blender (e.g. an empty kernel cache)."""
    why = app.gui_missing()
    if why:
        raise GuiError(f"GUI harness unavailable: {why}")
    out.mkdir(parents=True, exist_ok=True)
    log_path = out / "blender.log"
    params = {"VOXEL_GUI_OUT": str(out), "VOXEL_GUI_SCRIPT": str(Path(script).resolve()),
              "VOXEL_GUI_PARAMS": json.dumps(params or {}), **(env or {})}
    t0 = time.monotonic()
    with app.xserver(size) as x, \
            app.start(["--no-window-focus", *args, "--python", RUNNER], display=x.display,
                      log=log_path, user=user, size=size, env=params) as bl:
        (out / "pids.json").write_text(json.dumps({"blender": bl.pid, "x": x.pid}))
        try:
            app.wait(bl, timeout, log_path)
        except app.TimedOut as e:
            raise GuiError(f"Blender GUI run timed out after {timeout:.0f} s "
                           f"(killed):\n{app.tail(log_path)}") from e
    elapsed = time.monotonic() - t0
    res_path = out / "result.json"
    if not res_path.exists():
        raise GuiError(f"Blender exited ({bl.returncode}) without a result after "
                       f"{elapsed:.1f} s:\n{app.tail(log_path)}")
    data = json.loads(res_path.read_text())
    if not data["ok"]:
        raise GuiError(f"the script failed inside Blender:\n{data['error']}\n"
                       f"--- Blender log ---\n{app.tail(log_path)}")
    return GuiResult(out, data["result"], data["shots"], tuple(data["size"]), data["version"],
                     log_path.read_text(errors="replace"))

