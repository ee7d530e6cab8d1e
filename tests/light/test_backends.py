"""OpenCL == NumPy on generated-like terrain; region == per-chunk windows; incremental
relight == full relight after random edits."""
import numpy as np
import pytest

from voxel_addon.core.blocks import REGISTRY as R
from voxel_addon.light import full as solve, incremental as update, scenes


@pytest.mark.parametrize("seed", [1, 2])
def test_backends_equal_on_terrain(cl_device, seed):
    b = scenes.terrain(64, 48, seed)
    assert np.array_equal(solve.solve(b, "numpy"), solve.solve(b, "opencl"))


def test_backends_equal_on_overworld(cl_device):
    try:
        from voxel_addon.generation import make_generator
        gen = make_generator("overworld", 7, backend="numpy")
    except (ImportError, AttributeError) as e:
        pytest.skip(f"overworld generator not available yet: {e}")
    keys = [(cx, cy) for cy in range(-1, 2) for cx in range(-1, 2)]
    arrs = gen.generate(keys)
    b = np.zeros((48, 48, 256), np.uint16, order="F")
    for (cx, cy), a in zip(keys, arrs):
        b[(cx + 1) * 16:(cx + 2) * 16, (cy + 1) * 16:(cy + 2) * 16] = a
    assert np.array_equal(solve.solve(b, "numpy"), solve.solve(b, "opencl"))


def test_interior_is_exact():
    """The centre chunk of a 3x3 window equals the same chunk solved in a wider
    region (light never travels 16 voxels), and region_light tiles agree."""
    b = scenes.terrain(96, 80, 5)  # 6 x 5 chunks -> 4 x 3 interior
    reg = solve.region_light(b, "numpy", tile=3)
    wide = solve.solve(b, "numpy")
    assert np.array_equal(reg, wide[16:-16, 16:-16])
    for cx, cy in [(1, 1), (4, 3), (2, 2)]:
        win = b[(cx - 1) * 16:(cx + 2) * 16, (cy - 1) * 16:(cy + 2) * 16]
        assert np.array_equal(solve.chunk_light(win, "numpy"),
                              wide[cx * 16:(cx + 1) * 16, cy * 16:(cy + 1) * 16])


def test_incremental_equals_full():
    b = scenes.terrain(48, 48, 3)
    L = solve.solve(b, "numpy")
    rng = np.random.default_rng(0)
    ids = [0, 0, 0, R.id("stone"), R.id("stone"), R.id("lamp_red"), R.id("lamp_white"),
           R.id("water"), R.id("glass"), R.id("leaves"), R.id("glowing_mushroom")]
    lamps = []
    for k in range(60):
        if lamps and k % 4 == 0:  # remove a lamp placed earlier: darkening
            x, y, z = lamps.pop()
            new = 0
        else:
            x, y = (int(v) for v in rng.integers(0, 48, 2))
            top = int(np.flatnonzero(b[x, y])[-1])
            z = int(rng.integers(max(top - 25, 0), min(top + 3, 255)))
            new = int(rng.choice(ids))
            if new in (R.id("lamp_red"), R.id("lamp_white")):
                lamps.append((x, y, z))
        update.edit(b, L, x, y, z, new)
        if k % 6 == 5:
            assert np.array_equal(L, solve.solve(b, "numpy")), f"after edit {k}"
    # Cutting a sky shaft darkens the whole column below.
    b2 = b.copy()
    b2[10, 10, :] = R.id("stone")
    b2[10, 10, 20:] = 0
    L2 = solve.solve(b2, "numpy")
    update.edit(b2, L2, 10, 10, 200, R.id("stone"))
    assert np.array_equal(L2, solve.solve(b2, "numpy"))
    update.edit(b2, L2, 10, 10, 200, 0)
    assert np.array_equal(L2, solve.solve(b2, "numpy"))


def _reference(b):
    """Brute force: start values, then Jacobi relaxation (model.relax) to the fixpoint."""
    from voxel_addon.light import model
    bt = b.T
    lanes = model.start(bt)
    model.relax(lanes, model.tables()[0][bt], steps=10_000)
    return model.pack(lanes).T


def _random_scene(rng, w, h):
    """Dense random blocks of every light class under a random height: lots of
    emitters, attenuators and opaque walls, in an odd-sized array."""
    kinds = [0] * 6 + [R.id(n) for n in ("stone", "stone", "water", "leaves", "glass",
                                         "ore", "glowing_mushroom", "lamp_red",
                                         "lamp_white", "lamp_blue", "log")]
    b = np.zeros((w, h, 256), np.uint16, order="F")
    b[:, :, :40] = rng.choice(kinds, size=(w, h, 40))
    b[:, :, :3] = R.id("stone")
    return b


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_solvers_equal_brute_force_on_random_scenes(cl_device, seed):
    """Sparse NumPy flood and OpenCL sweeps both equal Jacobi iteration to the fixpoint
    (odd widths exercise the OpenCL x padding)."""
    rng = np.random.default_rng(seed)
    b = _random_scene(rng, 21 + seed, 13 + 2 * seed)
    ref = _reference(b)
    assert np.array_equal(solve.solve(b, "numpy"), ref)
    assert np.array_equal(solve.solve(b, "opencl"), ref)


def test_region_tiles_equal_brute_force_with_walled_in_emitters():
    """region_light's tiles (written straight into the result, their ring cut off)
    equal the brute force, with emitters of every strength walled in by stone, next
    to a single open voxel and out in the open (the solve seeds only emitters with
    a non-opaque neighbour)."""
    rng = np.random.default_rng(4)
    b = _random_scene(rng, 64, 48)
    rock = b[:, :, 3:20]
    rock[:] = R.id("stone")
    lit = [R.id(n) for n in ("ore", "glowing_mushroom", "lamp_red", "lamp_white")]
    where = rng.random(rock.shape) < 0.08
    rock[where] = rng.choice(lit, size=int(where.sum()))
    holes = rng.random(rock.shape) < 0.02  # a few open voxels next to some of them
    rock[holes] = 0
    ref = _reference(b)[16:-16, 16:-16]
    for tile in (1, 2, 8):
        assert np.array_equal(solve.region_light(b, "numpy", tile=tile), ref), tile


def test_incremental_equals_full_every_edit():
    """Every kind of edit (brightening: lamp, digging; darkening: walls, lamp removal),
    including boxes clipped by the array's edges, checked after each edit."""
    rng = np.random.default_rng(7)
    b = _random_scene(rng, 33, 30)
    b[:, :, 40:44] = 0
    L = solve.solve(b, "numpy")
    ids = [0, 0, R.id("stone"), R.id("water"), R.id("leaves"), R.id("glass"), R.id("ore"),
           R.id("lamp_red"), R.id("lamp_white"), R.id("glowing_mushroom")]
    for k in range(80):
        x, y = int(rng.integers(0, 33)), int(rng.integers(0, 30))
        z = int(rng.integers(0, 50))
        update.edit(b, L, x, y, z, int(rng.choice(ids)))
        assert np.array_equal(L, solve.solve(b, "numpy")), f"after edit {k}"


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_incremental_darkening_equals_full(seed):
    """The light-removal pass: lamps of different colours placed close together (their
    light overlaps), then removed or swapped for another colour, daylight shafts into a
    cave closed and reopened, attenuating blocks over lit air; checked after every edit
    against a full solve, and equal to the brute-force reference at the end."""
    rng = np.random.default_rng(100 + seed)
    w, h = 34, 31
    b = np.zeros((w, h, 256), np.uint16, order="F")
    b[:, :, :30] = R.id("stone")
    b[3:w - 3, 3:h - 3, 10:26] = 0  # a cave under a 4-voxel roof
    shafts = [(int(rng.integers(4, w - 4)), int(rng.integers(4, h - 4))) for _ in range(5)]
    for x, y in shafts:  # holes in the roof: daylight falls into the cave
        b[x, y, 26:30] = 0
    L = solve.solve(b, "numpy")
    lamps_ = [R.id(n) for n in ("lamp_red", "lamp_green", "lamp_blue", "lamp_white",
                               "lamp_yellow", "glowing_mushroom", "ore")]
    dim = [R.id(n) for n in ("water", "leaves", "glass", "stone", "log")]
    placed = []
    for k in range(90):
        kind = k % 5
        if kind in (0, 1) or not placed:  # a lamp near others (overlapping colours)
            if placed and rng.random() < 0.7:
                px, py, pz = placed[int(rng.integers(len(placed)))]
                x, y = px + int(rng.integers(-3, 4)), py + int(rng.integers(-3, 4))
                z = min(max(pz + int(rng.integers(-2, 3)), 10), 25)
            else:
                x, y, z = int(rng.integers(3, w - 3)), int(rng.integers(3, h - 3)), \
                    int(rng.integers(10, 26))
            x, y = min(max(x, 0), w - 1), min(max(y, 0), h - 1)
            update.edit(b, L, x, y, z, int(rng.choice(lamps_)))
            placed.append((x, y, z))
        elif kind == 2:  # remove a lamp, or swap it for another colour
            x, y, z = placed.pop(int(rng.integers(len(placed))))
            new = int(rng.choice(lamps_)) if rng.random() < 0.3 else 0
            update.edit(b, L, x, y, z, new)
            if new:
                placed.append((x, y, z))
        elif kind == 3:  # close or reopen a shaft (at the roof, or lower in the cave)
            x, y = shafts[int(rng.integers(len(shafts)))]
            z = int(rng.integers(20, 30))
            update.edit(b, L, x, y, z, 0 if b[x, y, z] else int(rng.choice(dim)))
        else:  # a dimming or blocking block next to a lit voxel
            x, y = int(rng.integers(0, w)), int(rng.integers(0, h))
            z = int(rng.integers(10, 27))
            update.edit(b, L, x, y, z, int(rng.choice(dim + [0])))
        assert np.array_equal(L, solve.solve(b, "numpy")), f"after edit {k} (kind {kind})"
    assert np.array_equal(L, _reference(b))


def test_the_default_is_numpy_on_a_cpu_device_and_named_backends_hold(cl_device):
    """pocl is a CPU device: there the NumPy flood costs ~4.5x less CPU than the
    kernel, so an unnamed backend means NumPy; a named one is what runs."""
    from voxel_addon import opencl
    assert opencl.on_cpu()  # CI's device is pocl
    assert solve.pick(None) == "numpy"
    assert solve.pick("opencl") == "opencl" and solve.pick("numpy") == "numpy"


def test_one_work_group_build_per_kernel_whatever_the_area(cl_device, tmp_path, monkeypatch):
    """pocl compiles a kernel's work-group function per local size at its first launch;
    left to choose, it picked one per area shape (~1 s CPU per new shape on a fresh
    install). Two shapes in a fresh process and kernel cache: one function per kernel."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    from voxel_addon import opencl
    from voxel_addon.light import cl as lcl
    code = ("import numpy as np\nfrom voxel_addon.light import cl\n"
            "for w, h in ((18, 18), (50, 34)):\n"
            "    b = np.zeros((w, h, 48), np.uint16, order='F'); b[:, :, :20] = 1\n"
            "    cl.solve_slab(b)\n")
    root = Path(__file__).resolve().parents[2]
    env = dict(os.environ, PYTHONPATH=str(root), POCL_CACHE_DIR=str(tmp_path / "pocl"),
               PYOPENCL_CACHE_DIR=str(tmp_path / "pyopencl"))
    subprocess.run([sys.executable, "-c", code], env=env, check=True, timeout=300)
    built = {}
    for so in (tmp_path / "pocl").rglob("light_*.so"):
        built.setdefault(so.parent.parent.name, []).append(so.parent.name)
    assert len(built) == 5 and all(len(v) == 1 for v in built.values()), built
    monkeypatch.setattr(opencl, "on_cpu", lambda: False)
    assert lcl._local() is None  # a GPU: its driver chooses (and builds once anyway)
