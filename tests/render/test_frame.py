"""The per-frame uniform block: frame.py packs every member where the real GL driver
reads it through the struct and accessors render/glsl.py generates (a shader reads
every member back out)."""
from __future__ import annotations

import numpy as np

from voxel_addon.render import frame, glsl


def test_block_layout_matches_the_driver(gl):
    members, size = frame.layout()
    assert "vp" in members and "sun_visible" in members and size % 16 == 0
    # one output pixel per vec4 / matrix column, generated from the member list
    lines, want, k = [], [], 0
    rng = np.random.default_rng(5)
    block = frame.FrameBlock()
    kinds = {n: kind for n, (_, _, kind) in members.items()}
    assert {"waving", "sun_visible", "ortho"} <= {n for n, kd in kinds.items() if kd == "b"}
    assert kinds.get("sky_a") == "a"  # vec4 arrays: one pixel per element
    for name, (_, n, kind) in members.items():
        if kind == "a":
            v = rng.uniform(-10, 10, (n // 4, 4))
            block.set(**{name: v})
            for i in range(n // 4):
                lines.append(f"if (k == {k}) r = {name}[{i}];")
                want.append(v[i])
                k += 1
            continue
        if kind == "b":  # bools: true for any non-zero
            v = rng.integers(0, 2, n)
        elif kind == "i":
            v = rng.integers(-100, 100, n)
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
    frag = ('#include "include/frame.glsl"\n//@ out 0 vec4 o\n'
            "void main() { int k = int(gl_FragCoord.x); vec4 r = vec4(-1.0);\n"
            + "\n".join(lines) + " o = r; }")
    p = glsl.program("fullscreen.vert", "probe.frag", texts=(None, frag))
    prog = gl.program(vertex_shader=glsl.source(p, "vert"), fragment_shader=glsl.source(p, "frag"))
    prog[glsl.FRAME_BLOCK].binding = frame.BINDING
    buf = gl.buffer(block.pack())
    buf.bind_to_uniform_block(frame.BINDING)
    fbo = gl.framebuffer([gl.renderbuffer((k, 1), 4, dtype="f4")])
    fbo.use()
    gl.vertex_array(prog, []).render(vertices=3)
    got = np.frombuffer(fbo.read(components=4, dtype="f4"), "f4").reshape(k, 4)
    assert np.allclose(got, np.array(want), atol=1e-5)
    fbo.release()
    prog.release()
    buf.release()



def test_pack_keeps_only_the_same_objects():
    """pack() reuses a member's floats while it is set again as the same object (the
    sky's tables of an hour) and packs new objects anew: the bytes are always those
    of a fresh block with the same values."""
    rng = np.random.default_rng(7)
    members, _ = frame.layout()
    mine = frame.FrameBlock()

    def values():
        out = {}
        for i, (name, (_, n, kind)) in enumerate(members.items()):
            v = rng.uniform(-10, 10, (n // 4, 4) if kind == "a" else n)
            out[name] = v.reshape(4, 4) if n == 16 else float(v[0]) if n == 1 else \
                tuple(v.tolist()) if i % 2 and kind != "a" else v  # (tuples and arrays)
        return out
    first = values()
    for step in range(3):
        v = values() if step else first
        if step == 2:  # some members the same objects as before, others new
            v.update({k: first[k] for k in list(first)[::2]})
        mine.set(**v)
        fresh = frame.FrameBlock()
        fresh.set(**v)
        assert mine.pack() == fresh.pack(), step


def test_conditions_follow_the_preprocessor():
    c = glsl.condition
    assert c("defined(A) && B > 1", {"A": 1, "B": 2}) and not c("defined(A) && B > 1", {"B": 2})
    assert c("!(defined(A) && B > 1)", {"B": 2}) and c("!defined(X) || Y", {"X": 1, "Y": 1})
    assert not c("LAYERS > 0", {}) and c("LAYERS > 0", {"LAYERS": 2})


def test_interface_follows_the_defines():
    p = glsl.program("block.vert", "block.frag", {"OIT": 1})
    assert [o[2] for o in p.iface.outputs] == ["out_accum", "out_reveal"]
    assert not [o for o in glsl.program("block.vert", "block.frag", {"SHADOW": 1}).iface.outputs]
    p = glsl.program("block.vert", "block.frag", {})
    assert [o[2] for o in p.iface.outputs] == ["out_albedo", "out_normal"]
    assert ("smooth", "vec2", "g_uv") in p.iface.varyings and p.iface.frame


def test_compiler_messages_name_the_file(gl):
    import pytest
    frag = '#include "include/common.glsl"\n//@ out 0 vec4 o\nvoid main() { o = nope; }\n'
    p = glsl.program("fullscreen.vert", "broken.frag", texts=(None, frag))
    with pytest.raises(Exception) as e:
        gl.program(vertex_shader=glsl.source(p, "vert"), fragment_shader=glsl.source(p, "frag"))
    assert "broken.frag:3" in p.where(str(e.value)), p.where(str(e.value))
