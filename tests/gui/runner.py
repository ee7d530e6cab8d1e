"""Blender side of the GUI harness (harness.py starts Blender with `--python` this file).

Loads the test script named by VOXEL_GUI_SCRIPT and drives its `run(gui)` generator
from a timer, so Blender handles events and redraws between steps:

    def run(gui):
        area = gui.area("VIEW_3D")
        gui.move(*gui.center(area))         # simulated events (--enable-event-simulate)
        gui.key("N")                        # PRESS + RELEASE
        yield 0.3                           # let Blender run 0.3 s (None: one tick)
        yield from gui.screenshot("open")   # redraw, then grab the X screen as PNG
        gui.result["tabs"] = ...            # JSON-able values for the pytest side
        gui.pixels("open")                  # that screenshot as a NumPy array

gui.params holds the keyword arguments the pytest side passed; gui.use_repo_addon()
registers the checkout's add-on (tests of code not yet in a zip).

Every step (until the generator ends) runs inside the window's context. When it
ends, or raises, result.json is written ({"ok", "result", "error", "shots"}), a
final screenshot is taken and Blender exits.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time
import traceback
from pathlib import Path

import bpy

OUT = Path(os.environ["VOXEL_GUI_OUT"])
TICK = 0.02
sys.path.insert(0, str(Path(__file__).parent))  # pixels.py for scripts (not the repo root:
# the extension under test must come from its installed copy)


class Gui:
    """What a test script gets: window, areas, simulated events, screenshots."""

    def __init__(self, params: dict):
        self.params = params
        self.result: dict = {}
        self.shots: list[str] = []
        self.window = bpy.context.window_manager.windows[0]

    # -- where things are (window coordinates: pixels, origin bottom-left) --
    def area(self, kind: str = "VIEW_3D"):
        return next(a for a in self.window.screen.areas if a.type == kind)

    def region(self, area, kind: str = "WINDOW"):
        return next(r for r in area.regions if r.type == kind)

    @staticmethod
    def rect(region) -> list[int]:
        """[x, y, width, height] of an area or region in window coordinates."""
        return [region.x, region.y, region.width, region.height]

    @staticmethod
    def center(region) -> tuple[int, int]:
        return region.x + region.width // 2, region.y + region.height // 2

    def context(self, area=None, region=None):
        """A temp_override for operators that need an area/region."""
        kw = {"window": self.window, "screen": self.window.screen}
        if area is not None:
            kw["area"] = area
            kw["region"] = region or self.region(area)
        return bpy.context.temp_override(**kw)

    # -- simulated input (needs Blender started with --enable-event-simulate) --
    def event(self, kind: str, value: str = "PRESS", x=None, y=None, **mods):
        if x is None:
            x, y = self._pos
        self._pos = (int(x), int(y))
        self.window.event_simulate(type=kind, value=value, x=int(x), y=int(y), **mods)

    _pos = (0, 0)

    def move(self, x, y):
        self.event("MOUSEMOVE", "NOTHING", x, y)

    def key(self, kind: str, **mods):
        self.event(kind, "PRESS", **mods)
        self.event(kind, "RELEASE", **mods)

    def click(self, x, y, button: str = "LEFTMOUSE", **mods):
        self.move(x, y)
        self.event(button, "PRESS", x, y, **mods)
        self.event(button, "RELEASE", x, y, **mods)

    def type(self, text: str):
        """Type text where the mouse is (key events carrying the characters)."""
        for ch in text:
            kind = ch.upper() if ch.isascii() and ch.isalpha() else "A"
            self.event(kind, "PRESS", unicode=ch)
            self.event(kind, "RELEASE")

    # -- what a person sees --
    def redraw(self):
        bpy.ops.wm.redraw_timer(type="DRAW_WIN_SWAP", iterations=1)

    def until_drawn(self, area, live, timeout: float):
        """Redraw `area` until the live view `live` says every wanted chunk is drawn at
        full quality (or `timeout` s pass), then let it settle; returns its scalar
        stats and error (use as `stats = yield from gui.until_drawn(...)`)."""
        t0 = time.monotonic()
        while time.monotonic() - t0 < timeout:
            area.tag_redraw()
            s = live.stats
            if s["frames"] > 3 and s["drawn"] >= s["wanted"] > 0 and s["quality"] == "full":
                break
            yield 0.2
        yield 1.0
        area.tag_redraw()
        yield 0.5
        return {**{k: v for k, v in live.stats.items() if isinstance(v, (int, float, str))},
                "error": live.error}

    def screenshot(self, name: str):
        """Generator: two ticks and a full redraw, then the X screen into NAME.png."""
        yield None
        yield None
        with self.context():
            self.redraw()
        _grab(OUT / f"{name}.png")
        self.shots.append(name)

    def pixels(self, name: str):
        """Screenshot NAME as (H, W, 3) uint8, top row first (cropped to the window)."""
        import pixels
        w, h = self.size
        return pixels.read_ppm(OUT / f"{name}.ppm")[:h, :w]

    def use_repo_addon(self):
        """Register the checkout's voxel_addon (not an installed zip), with the
        packages of this Blender's .blender/<suite>/site (pyopencl, moderngl, ...;
        VOXEL_BLENDER_SITE) importable."""
        root = Path(__file__).resolve().parents[2]
        for p in (Path(os.environ.get("VOXEL_BLENDER_SITE") or root / ".blender" / "site"), root):
            if str(p) not in sys.path and p.exists():
                sys.path.insert(0, str(p))
        import voxel_addon
        voxel_addon.register()
        return voxel_addon

    @property
    def size(self) -> tuple[int, int]:
        return self.window.width, self.window.height


def _grab(path: Path) -> None:
    """The whole X screen: NAME.ppm (for gui.pixels) and NAME.png."""
    ppm = path.with_suffix(".ppm")
    subprocess.run(f"xwd -root -silent | xwdtopnm > '{ppm}' 2>/dev/null", shell=True, check=True)
    subprocess.run(["pnmtopng", str(ppm)], stdout=open(path, "wb"), stderr=subprocess.DEVNULL,
                   check=True)


def _load(path: Path):
    ns = {"__name__": "voxel_gui_script", "__file__": str(path)}
    exec(compile(path.read_text(), str(path), "exec"), ns)
    return ns["run"]


def _finish(gui: Gui, error: str | None) -> None:
    try:
        _grab(OUT / "final.png")
        gui.shots.append("final")
    except Exception:  # noqa: BLE001 - the result matters more than the last picture
        error = (error or "") + "\nfinal screenshot failed:\n" + traceback.format_exc()
    data = {"ok": error is None, "result": gui.result, "error": error, "shots": gui.shots,
            "size": list(gui.size), "version": bpy.app.version_string}
    try:
        text = json.dumps(data, default=lambda o: o.tolist())  # NumPy values too
    except (TypeError, AttributeError):
        data["result"], data["ok"] = repr(gui.result), False
        data["error"] = (error or "") + f"\ngui.result is not JSON-able: {gui.result!r}"
        text = json.dumps(data)
    (OUT / "result.json").write_text(text)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0 if error is None else 1)


def main() -> None:
    params = json.loads(os.environ.get("VOXEL_GUI_PARAMS", "{}"))
    gui = Gui(params)
    state = {"gen": None, "wake": 0.0}

    def step():
        try:
            if state["gen"] is None:
                gui.window = bpy.context.window_manager.windows[0]
                with gui.context():
                    gen = _load(Path(os.environ["VOXEL_GUI_SCRIPT"]))(gui)
                if not hasattr(gen, "__next__"):  # a plain function: done
                    _finish(gui, None)
                state["gen"] = gen
            if time.monotonic() < state["wake"]:
                return TICK
            with gui.context():
                wait = next(state["gen"])
            state["wake"] = time.monotonic() + (wait or 0.0)
            return TICK
        except StopIteration:
            _finish(gui, None)
        except BaseException:  # noqa: BLE001 - reported to the pytest side
            _finish(gui, traceback.format_exc())
        return None

    # first step once the window exists and has drawn
    bpy.app.timers.register(step, first_interval=float(os.environ.get("VOXEL_GUI_DELAY", "0.5")))


main()
