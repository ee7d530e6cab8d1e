"""Sampler AO in an inner corner; GLSL light_sample / light_shade == NumPy (real EGL GL)."""
import numpy as np
import pytest

from voxel_addon import resources
from voxel_addon.core import chunk
from voxel_addon.core.blocks import REGISTRY as R
from voxel_addon.light import daytime, full, sampler, scenes


def test_inner_corner_is_darker():
    b = chunk.empty(np.uint16, 32, 16)
    b[:, :, :10] = R.id("stone")
    b[20:, :, :20] = R.id("stone")  # a wall: floor and wall meet in a concave edge
    L = full.solve(b, "numpy")
    up = (0, 0, 1)
    s = sampler.sample(L, [(5.5, 8.5, 10.0), (19.5, 8.5, 10.0), (20.0, 8.5, 10.0)], [up] * 3)
    assert s[0, 3] == 1.0
    assert s[2, 3] == pytest.approx(0.5)  # half the interpolation is the wall's dark centre
    assert s[2, 3] < s[1, 3] <= s[0, 3]


def test_glsl_matches_numpy(gl):
    import moderngl
    ctx = gl
    b = scenes.terrain(24, 24, 4)
    L = full.solve(b, "numpy")
    zlo = 40
    vol = L[:, :, zlo:zlo + 48]
    lanes = np.ascontiguousarray((np.stack([(vol >> s) & 15 for s in (0, 4, 8, 12)], -1)
                                  .astype(np.float32) / 15).transpose(2, 1, 0, 3))
    tex = ctx.texture3d(vol.shape, 4, lanes.tobytes(), dtype="f4")
    rng = np.random.default_rng(1)
    n = 64
    origin = np.array([0.0, 0.0, zlo])
    pts = rng.uniform((0, 0, zlo - 2), (24, 24, zlo + 50), (n, 3))
    nrm = np.eye(3)[rng.integers(0, 3, n)] * rng.choice([-1, 1], (n, 1))
    src = resources.shader("include/light.glsl")
    prog = ctx.program(vertex_shader="""#version 330
        in vec2 pos; void main() { gl_Position = vec4(pos, 0.0, 1.0); }""",
                       fragment_shader="#version 330\n" + src + """
        uniform sampler3D vol; uniform vec3 origin; uniform vec3 pts[64]; uniform vec3 nrm[64];
        uniform DayLight dl;
        out vec4 color;
        void main() {
            int i = int(gl_FragCoord.x);
            vec4 l = light_sample(vol, origin, pts[i], nrm[i]);
            color = gl_FragCoord.y < 1.0 ? l
                  : vec4(light_shade(vec3(0.8, 0.6, 0.4), l.rgb, 0.25, l.a, nrm[i], dl), 1.0);
        }""")
    p = daytime.at(9.25)
    prog["origin"].value = tuple(origin)
    prog["pts"].write(pts.astype("f4").tobytes())
    prog["nrm"].write(nrm.astype("f4").tobytes())
    for k in ("ambient", "direct", "light_dir"):
        prog[f"dl.{k}"].value = tuple(getattr(p, k))
    prog["dl.u"].value = p.u
    tex.use(0)
    prog["vol"].value = 0
    quad = ctx.buffer(np.array([-1, -1, 1, -1, -1, 1, 1, 1], "f4").tobytes())
    vao = ctx.vertex_array(prog, [(quad, "2f", "pos")])
    fbo = ctx.framebuffer([ctx.renderbuffer((n, 2), 4, dtype="f4")])
    fbo.use()
    vao.render(moderngl.TRIANGLE_STRIP)
    got = np.frombuffer(fbo.read(components=4, dtype="f4"), "f4").reshape(2, n, 4)
    want = sampler.sample(L[:, :, zlo:zlo + 48], pts, nrm, origin)
    assert np.allclose(got[0], want, atol=1e-5)
    shaded = sampler.shade(np.tile([0.8, 0.6, 0.4], (n, 1)), want[:, :3], np.full(n, 0.25),
                           want[:, 3], nrm, p)
    assert np.allclose(got[1, :, :3], shaded, atol=1e-5)
    assert want.std() > 0.05  # the points are not all in one flat light level
