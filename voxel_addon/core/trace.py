"""A timeline of where the seconds go (issue 28's first minute): with VOXEL_TRACE set
(any non-empty value but 0), `span` and `mark` record (start, seconds, thread CPU
seconds, thread, what, details) in `events`; off, they cost one check. Benches read
`events` (tools/first_bench_job.py); nothing else does."""
from __future__ import annotations

import os
import threading
import time
from contextlib import contextmanager

ON = os.environ.get("VOXEL_TRACE", "").strip() not in ("", "0")
events: list = []  # (time.monotonic() at start, s, cpu_s, thread, what, {details})


def mark(what: str, **kw) -> None:
    if ON:
        events.append((time.monotonic(), 0.0, 0.0, threading.current_thread().name, what, kw))


@contextmanager
def span(what: str, **kw):
    if not ON:
        yield kw
        return
    t0, c0 = time.monotonic(), time.thread_time()
    try:
        yield kw  # the caller may add details found on the way
    finally:
        events.append((t0, time.monotonic() - t0, time.thread_time() - c0,
                       threading.current_thread().name, what, kw))


def since(t0: float) -> list:
    """The events as JSON-friendly rows, times relative to T0 (time.monotonic())."""
    return [[round(t - t0, 3), round(s, 3), round(c, 3), th, w, kw]
            for t, s, c, th, w, kw in sorted(events, key=lambda e: e[0])]
