"""core/trace: the first minute's timeline (issue 28) records only when switched on."""
from __future__ import annotations

import threading
import time

from voxel_addon.core import trace


def test_spans_and_marks_are_kept_only_when_on(monkeypatch):
    monkeypatch.setattr(trace, "events", [])
    monkeypatch.setattr(trace, "ON", False)
    with trace.span("off"):
        pass
    trace.mark("off")
    assert trace.events == []
    monkeypatch.setattr(trace, "ON", True)
    t0 = time.monotonic()
    with trace.span("work", n=3) as kw:
        kw["found"] = 1  # details added on the way are kept
        time.sleep(0.02)
    trace.mark("frame", ms=5)
    rows = trace.since(t0)
    assert [r[4] for r in rows] == ["work", "frame"]
    work, frame = rows
    assert work[0] >= 0 and work[1] >= 0.015 and work[2] < work[1]  # sleeping: no CPU
    assert work[3] == threading.current_thread().name and work[5] == {"n": 3, "found": 1}
    assert frame[1] == 0 and frame[5] == {"ms": 5} and frame[0] >= work[0]
