"""Packed viewport vertices: the GLSL decode (real GL via EGL, transform feedback)
reproduces the NumPy mesh; chunk ranges cover every quad once."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon import meshing, resources
from voxel_addon.core.blocks import ANIMATIONS, REGISTRY
from voxel_addon.meshing import mesh as M
from voxel_addon.meshing import scenes

from .helpers import random_window


def _chunk():
    b = random_window(3, shape=(18, 18, 256), band=(90, 140))
    b[:, :, 140:150] = scenes.blocks("landscape")[0:18, 0:18, 70:80]
    return np.asfortranarray(b)



def _decode_on_gpu(ctx, verts):
    import moderngl
    src = "#version 450\n" + resources.shader("include/vertex.glsl") + """
in uint v_packed;
out vec3 o_pos; out vec3 o_nrm; out vec2 o_uv; out vec3 o_misc;
void main() {
    Vertex v = decode(v_packed);
    o_pos = v.position; o_nrm = v.normal; o_uv = v.uv;
    o_misc = vec3(v.layer, v.face, v.anim);
}
"""
    fbo = ctx.simple_framebuffer((4, 4))   # transform feedback needs a bound framebuffer
    fbo.use()
    prog = ctx.program(vertex_shader=src, varyings=["o_pos", "o_nrm", "o_uv", "o_misc"])
    vbo = ctx.buffer(verts.tobytes())
    vao = ctx.vertex_array(prog, [(vbo, "u4", "v_packed")])
    out = ctx.buffer(reserve=len(verts) * 11 * 4)
    vao.transform(out, mode=moderngl.POINTS, vertices=len(verts))
    return np.frombuffer(out.read(), np.float32).reshape(-1, 11)


def test_glsl_decode_matches_numpy(gl):
    cm = meshing.build_chunk(_chunk())
    q = cm.quads
    assert set(np.unique(q["face"])) >= set(range(12)), "every face code is exercised"
    r = _decode_on_gpu(gl, cm.vertices)
    mesh = meshing.to_mesh(q)
    p = mesh.positions.copy()
    p[:, 2] -= np.repeat(q["z"] // cm.region_h * cm.region_h, 4)
    assert np.allclose(r[:, :3], p, atol=1e-6)
    assert np.allclose(r[:, 3:6], mesh.normals, atol=1e-6)
    assert np.allclose(r[:, 6:8], M.uv_of(np.repeat(q["face"], 4).astype(int), p), atol=1e-6)
    # uvs tile: equal to the bake mesh's uvs up to whole texture repeats
    d = r[:, 6:8] - mesh.uvs
    assert np.allclose(d, np.round(d), atol=1e-6)
    anim = np.array([ANIMATIONS.index(b.animation) for b in REGISTRY.blocks])
    assert (r[:, 8] == np.repeat(q["layer"], 4)).all()
    assert (r[:, 9] == np.repeat(q["face"], 4)).all()
    assert (r[:, 10] == np.repeat(anim[q["block"]], 4)).all()


def test_pack_unpack_and_ranges():
    b = _chunk()
    cm = meshing.build_chunk(b, region_h=16)
    assert cm.vertices.dtype == np.uint32 and meshing.BYTES_PER_VERTEX == 4
    q = cm.quads
    assert len(cm.vertices) == 4 * len(q)
    u = meshing.unpack(cm.vertices)
    assert (u["face"] == np.repeat(q["face"], 4)).all()
    assert (u["layer"] == np.repeat(q["layer"], 4)).all()
    # ranges: regions and passes tile the vertex array in order, each quad in its region
    first, count = cm.ranges[..., 0].ravel(), cm.ranges[..., 1].ravel()
    assert first[0] == 0 and (first[1:] == (first + count)[:-1]).all()
    assert count.sum() == len(cm.vertices)
    for r in range(cm.ranges.shape[0]):
        for p in range(len(meshing.PASSES)):
            f, n = cm.ranges[r, p]
            sel = q[f // 4:(f + n) // 4]
            assert (sel["z"] // 16 == r).all()
            assert (meshing.vertex.PASS_OF[sel["block"]] == p).all()
    # same quads as meshing the chunk with the region split
    ref = meshing.quads(b, split=16)
    assert len(ref) == len(q)
    idx = meshing.quad_indices(3)
    assert idx.tolist() == [0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7, 8, 9, 10, 8, 10, 11]


def test_two_sided_mesh_duplicates_plants():
    b = np.zeros((3, 3, 256), np.uint16, order="F")
    b[1, 1, 10] = REGISTRY.id("flowers")
    b[0, 0, 10] = REGISTRY.id("cactus")
    q = meshing.quads(b, border="air")
    one = meshing.to_mesh(q)
    two = meshing.to_mesh(q, two_sided=True)
    assert len(two.face) == len(one.face) + 2      # flowers: 2 planes; cactus single-sided
    assert np.allclose(two.normals[-4:], -one.normals[4 * np.nonzero(q["block"] == 9)[0][-1]])


@pytest.mark.parametrize("backend", ["numpy", "opencl"])
def test_region_rebuild_spliced_equals_full_build(backend, request):
    """An edit's remesh: only the render regions around the changed voxel are meshed
    again (regions=) and spliced into the old mesh; equal to meshing it all again,
    also at region borders (z 63/64, 127/128) and the world's bottom and top."""
    if backend == "opencl":
        request.getfixturevalue("cl_device")
    from voxel_addon.light import scenes as light_scenes
    from voxel_addon.meshing import build_chunks, splice
    R = REGISTRY
    rng = np.random.default_rng(4)
    b = light_scenes.terrain(34, 34, 3)
    ids = [0, R.id("stone"), R.id("glass"), R.id("water"), R.id("leaves"), R.id("lamp_red")]
    old = build_chunks(np.asfortranarray(b), (0, 0), backend=backend)
    for t in range(30):
        x, y = (int(v) for v in rng.integers(1, 33, 2))
        top = int(np.flatnonzero(b[x, y])[-1])
        z = int(rng.choice([63, 64, 127, 128, 0, 255])) if t % 5 == 0 else \
            int(np.clip(top + rng.integers(-3, 3), 1, 254))
        b[x, y, z] = rng.choice(ids)
        r0, r1 = max(z - 1, 0) // 64, min(z + 1, 255) // 64 + 1
        part = build_chunks(np.asfortranarray(b), (0, 0), backend=backend, regions=(r0, r1))
        full = build_chunks(np.asfortranarray(b), (0, 0), backend=backend)
        for k, m in full.items():
            s = splice(old[k], part[k], r0, r1)
            assert np.array_equal(s.vertices, m.vertices), (t, k, z)
            assert np.array_equal(s.ranges, m.ranges) and np.array_equal(s.quads, m.quads)
        old = full
