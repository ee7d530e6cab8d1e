"""The faintest light still moves: values 2 push a 1 sideways (full.py seeds the
daylight's sideways flood only in the layers where it can spread). Both solvers
against the brute-force Jacobi reference (model.relax)."""
import numpy as np
import pytest

from voxel_addon.core.blocks import REGISTRY as R
from voxel_addon.light import full, model

STONE, LEAVES = R.id("stone"), R.id("leaves")


def _reference(b):
    bt = b.T
    lanes = model.start(bt)
    model.relax(lanes, model.tables()[0][bt], steps=10_000)
    return model.pack(lanes).T


@pytest.mark.parametrize("backend", ["numpy", "opencl"])
def test_daylight_of_two_spreads_sideways(backend, request):
    """A sky shaft through 13 leaves (D 14 .. 2) ends at a side tunnel: the
    lowest daylit layer holds D = 2 and its tunnel neighbour must get 1."""
    if backend == "opencl":
        request.getfixturevalue("cl_device")
    b = np.zeros((12, 10, 256), np.uint16, order="F")
    b[:, :, :40] = STONE
    b[5, 5, 27:40] = LEAVES
    b[6:9, 5, 27] = 0
    L = full.solve(b, backend)
    assert L[5, 5, 27] >> 12 == 2 and L[6, 5, 27] >> 12 == 1
    assert np.array_equal(L, _reference(b))


@pytest.mark.parametrize("backend", ["numpy", "opencl"])
def test_daylight_of_one_goes_down_its_column(backend, request):
    """14 leaves leave D = 1, which spreads nowhere but still fills the air column
    below (the column pass must not stop where nothing can spread any more)."""
    if backend == "opencl":
        request.getfixturevalue("cl_device")
    b = np.zeros((12, 10, 256), np.uint16, order="F")
    b[:, :, :60] = STONE
    b[5, 5, 46:60] = LEAVES
    b[5, 5, 40:46] = 0
    L = full.solve(b, backend)
    assert L[5, 5, 46] >> 12 == 1 and L[5, 5, 40] >> 12 == 1
    assert np.array_equal(L, _reference(b))
