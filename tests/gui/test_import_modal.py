"""File › Import › Voxel World in the real Blender window: the modal job, Esc
cancelling it half-way, and a full run that leaves the UI handling events."""
from __future__ import annotations


def test_import_is_modal_and_esc_cancels(gui, tmp_path):
    from voxel_addon.world import World
    path = tmp_path / "w.sqlite"
    n = 80  # a region big enough that its objects take several of the job's ticks
    with World.create(path, seed=2019, generator="overworld", loader=False) as w:
        w.generate_area([(cx, cy) for cx in range(-n // 16, n // 16) for cy in range(-n // 16, n // 16)])
    res = gui("import_modal.py", timeout=300, world=str(path), region=[-n, -n, n, n])
    r = res.result
    assert r["first"] == ["RUNNING_MODAL"], r
    assert r["half_made"] and r["running_before_esc"], r  # stopped in the objects stage
    assert not r["running_after_esc"] and r["clean_after_esc"], r["diff_after_esc"]
    assert r["second"] == ["RUNNING_MODAL"], r
    assert r["ticks"] >= 3, r  # the window ran while the job worked
    assert r["collections"] == [f"Voxel Bake {-n} {-n} {n} {n}"], r
    want = sorted(f"tile_{x}_{y}" for x in range(-n, n, 16) for y in range(-n, n, 16))
    assert r["objects"] == want, r
