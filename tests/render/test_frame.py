"""The per-frame uniform block: the offsets frame.py reads from frame.glsl by the std140
rules must be where the real GL driver puts the members (a shader reads every member
back out)."""
from __future__ import annotations

import re

import numpy as np

from voxel_addon import resources
from voxel_addon.render import frame


def test_block_layout_matches_the_driver(gl):
    members, size = frame.layout()
    assert "vp" in members and "sun_visible" in members and size % 16 == 0
    # one output pixel per vec4 / matrix column, generated from the member list
    lines, want, k = [], [], 0
    rng = np.random.default_rng(5)
    block = frame.FrameBlock(gl)
    bools = set(re.findall(r"\bbool\s+(\w+)\s*;", resources.shader("include/frame.glsl")))
    assert {"waving", "sun_visible", "ortho"} <= bools
    arrays = frame.arrays()
    assert arrays.get("sky_a", 0) > 0
    for name, (_, n, kind) in members.items():
        if name in arrays:  # vec4 NAME[N]: one pixel per element
            v = rng.uniform(-10, 10, (arrays[name], 4))
            block.set(**{name: v})
            for i in range(arrays[name]):
                lines.append(f"if (k == {k}) r = {name}[{i}];")
                want.append(v[i])
                k += 1
            continue
        if kind == "i":
            v = rng.integers(-100, 100, n)
            if name in bools:  # bools: GLSL gives true for any non-zero
                v = rng.integers(0, 2, n)
        else:
            v = rng.uniform(-10, 10, n)
        block.set(**{name: v.reshape(4, 4) if n == 16 else v[0] if n == 1 else v})
        if n == 16:
            m = v.reshape(4, 4)
            for c in range(4):
                lines.append(f"if (k == {k}) r = {name}[{c}];")
                want.append(m[:, c])
                k += 1
        else:
            expr = f"float({name})" if n == 1 else f"vec{n}({name})"
            lines.append(f"if (k == {k}) r = vec4({expr}{', 0.0' * (4 - n)});")
            want.append(np.r_[v, np.zeros(4 - n)])
            k += 1
    block.upload()
    src = resources.shader("include/frame.glsl")
    prog = gl.program(
        vertex_shader="""#version 410 core
            void main() { vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0,
                                        float((gl_VertexID & 2) << 1) - 1.0);
                          gl_Position = vec4(p, 0.0, 1.0); }""",
        fragment_shader="#version 410 core\n" + src + """
            out vec4 o;
            void main() { int k = int(gl_FragCoord.x); vec4 r = vec4(-1.0);
            """ + "\n".join(lines) + " o = r; }")
    prog["Frame"].binding = frame.BINDING
    block.buf.bind_to_uniform_block(frame.BINDING)
    fbo = gl.framebuffer([gl.renderbuffer((k, 1), 4, dtype="f4")])
    fbo.use()
    gl.vertex_array(prog, []).render(vertices=3)
    got = np.frombuffer(fbo.read(components=4, dtype="f4"), "f4").reshape(k, 4)
    assert np.allclose(got, np.array(want), atol=1e-5)
    fbo.release()
    prog.release()
    block.release()
