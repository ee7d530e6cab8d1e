"""The Voxel Edit tool in the real Blender GUI (issue 13): Blender 4.3 under Xvfb with
simulated events (edit_job.py does the clicking and checks against oracles
computed from the view's matrices; this side starts it and reads the results)."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

JOB = Path(__file__).with_name("edit_job.py")


@pytest.fixture(scope="module")
def display(app):
    with app.xserver() as x:
        yield x.display


def run_case(app, display, out: Path, case: str):
    out.mkdir(parents=True, exist_ok=True)
    log = out / "blender.log"
    with app.start(["--factory-startup", "-P", JOB, "--", out, case], display=display,
                   log=log, user=out / "user") as p:
        code = app.wait(p, 400, log)
    res = out / f"{case}.json"
    assert res.exists(), app.tail(log, 6000)
    return code, log.read_text(errors="replace"), json.loads(res.read_text())


def _ok(log, res):
    bad = [c for c in res["checks"] if not c[1]]
    assert res["error"] is None, res["error"]
    assert not bad, bad
    assert "Traceback" not in log, log[-3000:]


@pytest.mark.parametrize("case", ["click", "drag", "blocked", "interleave", "pixels"])
def test_tool(app, display, tmp_path, case):
    _, log, res = run_case(app, display, tmp_path, case)
    _ok(log, res)
    assert len(res["checks"]) > 3


def test_kill_right_after_a_stroke_loses_nothing(app, display, tmp_path):
    from voxel_addon.core.blocks import REGISTRY
    from voxel_addon.storage import WorldFile
    code, _, res = run_case(app, display, tmp_path, "kill")
    assert code == -9, code       # killed, not exited
    x, y, z = res["figures"]["kill_cell"]
    wf = WorldFile(tmp_path / "w.sqlite", readonly=True)
    try:
        blocks, _ = wf.read_chunk((x >> 4, y >> 4))
        assert REGISTRY[int(blocks[x & 15, y & 15, z])].name == "lamp_red"
        assert wf.edit_count() >= 1
    finally:
        wf.close()
