import pytest


@pytest.fixture(params=["tile", "slices"])
def greedy_path(request, cl_device):
    """Runs an OpenCL test with each greedy kernel (meshing/cl.py `path`): both must give
    the NumPy reference's output whichever device the user's platform has."""
    from voxel_addon.meshing import cl as mcl
    mcl.PATH = request.param
    yield request.param
    mcl.PATH = None
