"""The sky's shader functions against their references, evaluated on the real GL with
the frame block the pipeline writes: the noise and cloud cover (include/noise.glsl,
clouds.glsl) against render/clouds.py, the tabulated sky (include/atmosphere.glsl)
against the model (light/daytime.py sky_at)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from voxel_addon import resources
from voxel_addon.render import clouds, frame, glsl, sky
from voxel_addon.render.pipeline import sky_values
from voxel_addon.render.settings import Settings


class _Cam:
    fov = 70.0
    ortho = False


def evaluate(gl, points, expr: str, hours: float = 12.0, include: str = "include/clouds.glsl",
             **settings) -> np.ndarray:
    """GLSL `expr` (vec3, of `vec3 d`) for each row of points (n, 3), one pixel each."""
    n = len(points)
    block = frame.FrameBlock()
    sp = sky.params(hours)
    s = Settings(**settings)
    block.set(**sky_values(s, sp, hours, True, _Cam(), None, 360))
    block.set(sky_light_dir=sp["light_dir"], sky_stars=sp["stars"], sky_disc=sp["disc"],
              day_ambient=sp["ambient"], day_direct=sp["direct"])
    frag = (f'#include "include/frame.glsl"\n#include "{include}"\n'
            "//@ sampler sampler2D points\n//@ out 0 vec4 o\n"
            "void main() { vec3 d = texelFetch(points, ivec2(gl_FragCoord.xy), 0).xyz;\n"
            f"    o = vec4({expr}, 1.0); }}\n")
    p = glsl.program("fullscreen.vert", "probe.frag", texts=(None, frag))
    prog = gl.program(vertex_shader=glsl.source(p, "vert"), fragment_shader=glsl.source(p, "frag"))
    prog[glsl.FRAME_BLOCK].binding = frame.BINDING
    buf = gl.buffer(block.pack())
    buf.bind_to_uniform_block(frame.BINDING)
    data = np.c_[np.asarray(points, np.float32), np.zeros(n, np.float32)].astype("f4")
    tex = gl.texture((n, 1), 4, data.tobytes(), dtype="f4")
    tex.filter = (gl.NEAREST, gl.NEAREST)
    tex.use(0)
    prog["points"].value = 0
    fbo = gl.framebuffer([gl.renderbuffer((n, 1), 4, dtype="f4")])
    fbo.use()
    gl.vertex_array(prog, []).render(vertices=3)
    out = np.frombuffer(fbo.read(components=4, dtype="f4"), "f4").reshape(n, 4)[:, :3].copy()
    for x in (fbo, tex, prog, buf):
        x.release()
    return out


def test_noise_matches_numpy(gl):
    rng = np.random.default_rng(3)
    p = np.c_[rng.uniform(-300, 300, (256, 2)), np.zeros(256)]
    got = evaluate(gl, p, "vec3(gnoise2(d.xy, 7u), fbm2(d.xy * 0.1, 0x2545F491u, 5), 0.0)")
    assert np.abs(got[:, 0] - clouds.gnoise2(p[:, 0], p[:, 1], 7)).max() < 1e-4
    assert np.abs(got[:, 1] - clouds.fbm2(p[:, 0] * 0.1, p[:, 1] * 0.1, clouds.SEED, 5)).max() < 1e-4
    assert got[:, 0].std() > 0.1, "the noise is not flat"


@pytest.mark.parametrize("hours", [9.0, 12.25])
def test_cloud_cover_matches_numpy(gl, hours):
    rng = np.random.default_rng(4)
    p = np.c_[rng.uniform(-3000, 3000, (512, 2)), np.zeros(512)]
    s = Settings()
    got = evaluate(gl, p, "vec3(cloud_density(d.xy, 5), 0.0, 0.0)", hours)[:, 0]
    want = clouds.density(p[:, 0], p[:, 1], s.cloud_cover, sky.drift(hours, s.cloud_speed))
    assert np.abs(got - want).max() < 2e-3
    assert 0.05 < (want > 0.5).mean() < 0.9, "some sky is cloudy, some clear"


def test_sky_table_matches_the_model(gl):
    """The tabulated sky (log-interpolated between SKY_NE x SKY_NA nodes, the sun's Mie
    phase per pixel) stays within 20 % of the model, at noon and at dusk."""
    from voxel_addon.light import daytime
    src = resources.shader("include/atmosphere.glsl")
    assert f"#define SKY_NE {sky.NE}" in src and f"#define SKY_NA {sky.NA}" in src
    assert "#define SKY_EPS 1e-6" in src and sky.EPS == 1e-6
    rng = np.random.default_rng(5)
    for hours in (12.0, 18.25):
        el = np.arcsin(rng.uniform(0.02, 1.0, 300))
        az = rng.uniform(-math.pi, math.pi, 300)
        d = np.c_[np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)]
        got = evaluate(gl, d, "sky_radiance(d)", hours, "include/atmosphere.glsl")
        want = daytime.sky_at(hours, d, sky.params(hours)["exposure"])
        rel = np.abs(got - want).sum(1) / want.sum(1)
        assert np.median(rel) < 0.05 and rel.max() < 0.2, (hours, np.median(rel), rel.max())
