"""The harness itself: a failing script fails the test with the Blender-side
traceback, a script that never ends is killed at its time limit (Blender and its X
server), and events simulated in Blender reach its key map and text input."""
from __future__ import annotations

import json
import os

import pytest

from tests.gui.harness import GuiError


def _gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return False


def test_a_failing_script_reports_its_blender_traceback(app, gui, tmp_path):
    script = tmp_path / "bad.py"
    script.write_text("def run(gui):\n    yield 0.1\n    import bpy\n"
                      "    raise ValueError('broken on purpose ' + bpy.app.version_string)\n")
    with pytest.raises(GuiError) as e:
        gui(script, timeout=120)
    msg = str(e.value)
    # ... from the Blender the run asked for (VOXEL_BLENDER_APP)
    want = f"ValueError: broken on purpose {app.get().version}"
    assert "Traceback" in msg and want in msg and "bad.py" in msg


def test_a_script_past_its_time_limit_is_killed(gui, tmp_path):
    script = tmp_path / "forever.py"
    script.write_text("def run(gui):\n    while True:\n        yield 0.1\n")
    with pytest.raises(GuiError, match="timed out"):
        gui(script, timeout=12)
    pids = json.loads((tmp_path / "out" / "pids.json").read_text())
    assert _gone(pids["blender"]) and _gone(pids["x"]), pids


def test_simulated_keys_run_operators_and_type_text(gui, tmp_path):
    """Ctrl+Space over the viewport maximises it (screen.screen_full_area); text typed
    over a text editor lands in its text."""
    script = tmp_path / "keys.py"
    script.write_text(
        "import bpy\n"
        "def run(gui):\n"
        "    area = gui.area('VIEW_3D')\n"
        "    gui.result['before'] = len(gui.window.screen.areas)\n"
        "    gui.move(*gui.center(gui.region(area)))\n"
        "    gui.key('SPACE', ctrl=True)\n"
        "    yield 0.5\n"
        "    gui.result['after'] = len(gui.window.screen.areas)\n"
        "    area = gui.window.screen.areas[0]\n"
        "    area.type = 'TEXT_EDITOR'\n"
        "    area.spaces.active.text = bpy.data.texts.new('typed')\n"
        "    yield 0.3\n"
        "    gui.move(*gui.center(gui.region(area)))\n"
        "    gui.type('Voxel 42!')\n"
        "    yield 0.3\n"
        "    gui.result['text'] = bpy.data.texts['typed'].as_string()\n")
    r = gui(script, timeout=120).result
    assert r["before"] > 1 and r["after"] == 1, r
    assert r["text"] == "Voxel 42!", r
