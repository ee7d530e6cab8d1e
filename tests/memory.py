"""Peak memory of a call, for the tests that bound what a decoder may allocate."""
from __future__ import annotations

import tracemalloc


def peak_of(fn) -> int:
    """Peak traced bytes while fn runs (tracemalloc sees every bytes/NumPy buffer)."""
    tracemalloc.start()
    try:
        fn()
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return peak
