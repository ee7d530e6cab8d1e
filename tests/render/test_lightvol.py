"""The renderer's camera-centred toroidal light volume (lightvol.glsl's light_volume,
light.glsl's light_sample for this layout):
it must give exactly what the NumPy sampler gives, also at negative coordinates and
across the wrap, and open daylight outside the resident window."""
from __future__ import annotations

import numpy as np

from voxel_addon import light
from voxel_addon.light import scenes
from voxel_addon.render import glsl
from voxel_addon.render.device.mgl import MglDevice
from voxel_addon.render.frame import BINDING, FrameBlock
from voxel_addon.render.lightvol import LightVolume, window

N = 96  # sample points



def sample_gl(dev, vol, pts, nrm):
    frag = f"""#include "include/lightvol.glsl"
        //@ push vec3 pts[{N}]
        //@ push vec3 nrm[{N}]
        //@ out 0 vec4 color
        void main() {{
            int i = int(gl_FragCoord.x);
            color = light_volume(pts[i], nrm[i], 0.0);  // (no spare: the reference)
        }}"""
    vert = """//@ in vec2 pos
        void main() { gl_Position = vec4(pos, 0.0, 1.0); }"""
    p = glsl.program("probe.vert", "probe.frag", texts=(vert, frag))
    ctx = dev.ctx
    prog = ctx.program(vertex_shader=glsl.source(p, "vert"), fragment_shader=glsl.source(p, "frag"))
    prog[glsl.FRAME_BLOCK].binding = BINDING
    block = FrameBlock()
    block.set(**vol.frame_values())
    dev.frame(block.pack())
    prog["pts"].write(pts.astype("f4").tobytes())
    prog["nrm"].write(nrm.astype("f4").tobytes())
    vol.tex.obj.use(0)
    prog["light_vol"].value = 0
    quad = ctx.buffer(np.array([-1, -1, 1, -1, -1, 1, 1, 1], "f4").tobytes())
    vao = ctx.vertex_array(prog, [(quad, "2f", "pos")])
    fbo = ctx.framebuffer([ctx.renderbuffer((N, 1), 4, dtype="f4")])
    fbo.use()
    vao.render(ctx.TRIANGLE_STRIP)
    out = np.frombuffer(fbo.read(components=4, dtype="f4"), "f4").reshape(N, 4)
    for x in (fbo, vao, quad, prog):
        x.release()
    return out


def test_torus_matches_numpy_sampler(gl):
    b = scenes.terrain(48, 48, 4)
    L = light.solve(b)
    cx0, cy0 = -2, -1                 # negative chunks; 3 slots a side (48: no power of 2)
    dev = MglDevice(gl)
    vol = LightVolume(dev, 3)
    vol.upload_area(L[:32, :32], cx0, cy0)
    vol.set_window(cx0, cy0, cx0 + 2, cy0 + 2)
    org = np.array([16 * cx0, 16 * cy0, 0.0])
    rng = np.random.default_rng(3)
    pts = org + rng.uniform((1, 1, 30), (31, 31, 120), (N, 3))
    nrm = np.eye(3)[rng.integers(0, 3, N)] * rng.choice([-1, 1], (N, 1))
    got = sample_gl(dev, vol, pts, nrm)
    want = light.sample(L[:32, :32], pts, nrm, origin=org)
    assert want.std() > 0.05
    assert np.allclose(got, want, atol=1e-5)
    # outside the resident window: open daylight
    far = org + np.array([40.0, 8.0, 70.0]) + np.zeros((N, 3))
    assert np.allclose(sample_gl(dev, vol, far, nrm), [0, 0, 0, 1], atol=1e-6)
    vol.release()
    dev.close()


def test_light_window_is_bounded():
    # distance 32: 65 x 65 chunks shown, the light volume holds 17 x 17 around the centre
    assert window((-30, -40, 35, 25), 8) == (-6, -16, 11, 1)
    assert window((0, 0, 4, 4), 8) == (0, 0, 4, 4)


def test_packed_light_uploads_the_same_texels(gl):
    """The viewport keeps chunk light as core.chunk.pack_layers: the volume unpacks it."""
    from voxel_addon.core.chunk import cut, pack_layers
    b = scenes.terrain(32, 32, 4)
    L = light.solve(b)
    parts = cut(L, 0, 0)
    dev = MglDevice(gl)
    vols = [LightVolume(dev, 2), LightVolume(dev, 2)]
    for k, a in parts.items():
        vols[0].upload(k, a)
        vols[1].upload(k, pack_layers(a))
    got = [np.frombuffer(v.tex.obj.read(), np.uint16) for v in vols]
    assert got[0].std() > 0 and np.array_equal(got[0], got[1])
    assert pack_layers(parts[(0, 0)])[-1].nbytes < parts[(0, 0)].nbytes  # it is smaller
    # chunk (1, 0) in layer 1: voxel (x, y, z) at texel (x + 16 (z & 15), y + 16 (z >> 4))
    lay = got[0].reshape(4, 256, 256)[1]
    a = parts[(1, 0)]
    for x, y, z in ((0, 0, 0), (15, 3, 17), (5, 15, 255), (9, 9, 100)):
        assert lay[y + 16 * (z >> 4), x + 16 * (z & 15)] == a[x, y, z]
    for v in vols:
        v.release()
    dev.close()
