"""bpy fixtures: the real bpy module (or the Blender binary running tests/run.py)."""
from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def bpy():
    try:
        import bpy as b
    except ImportError as e:
        pytest.skip(f"no bpy: {e}")
    return b
