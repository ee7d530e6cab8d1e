"""glstate on the real GL (EGL): a host's state is put back exactly, and inside
kept() the pipeline sees a fresh moderngl context's state whatever the host left,
so it draws the same image as on a context of its own."""
from __future__ import annotations

import numpy as np

from voxel_addon.render import Camera, Settings, glstate

from .test_render import floor, renderer

SIZE = (96, 64)
CAM = Camera(16, 4, 70, 90, -30)
PLACES = ("fb", "viewport", "scissor")  # set by the pipeline itself before each use


def _hostile(gl, keep):
    """A host (like Blender) leaving plenty set: blending, culling, a sampler object
    overriding texture filters, wire polygons, a bound pixel-unpack buffer, odd
    pixel-store values, zero-to-one clip depth. Objects go into keep (stay alive)."""
    g = glstate.gl()
    # moderngl rebinds its last bound framebuffer after creating one, here a released
    # one of an earlier Renderer (GL_INVALID_OPERATION): not what is tested
    host = gl.simple_framebuffer((20, 10))
    glstate.errors()
    host.use()
    smp = gl.sampler(filter=(gl.NEAREST, gl.NEAREST), repeat_x=False, repeat_y=False)
    buf = gl.buffer(reserve=64)
    tex = gl.texture((2, 2), 4)
    prog = gl.program(vertex_shader="#version 330\nvoid main() { gl_Position = vec4(0.0); }",
                      fragment_shader="#version 330\nout vec4 c; void main() { c = vec4(1.0); }")
    vao = gl.vertex_array(prog, [])
    keep += [host, smp, buf, tex, vao, prog]
    g.UseProgram(prog.glo)
    g.BindVertexArray(vao.glo)
    for u in range(8):
        smp.use(u)
        tex.use(u)
    g.Enable(0x0BE2)                       # BLEND
    g.BlendFuncSeparate(1, 1, 1, 1)        # ONE, ONE
    g.BlendEquationSeparate(0x8008, 0x8008)  # MAX
    g.Enable(0x0B44)                       # CULL_FACE
    g.CullFace(0x0404)                     # FRONT
    g.Enable(0x0C11)                       # SCISSOR_TEST
    g.Scissor(1, 2, 3, 4)
    g.DepthFunc(0x0204)                    # GREATER
    g.PolygonMode(0x0408, 0x1B01)          # LINE
    g.ProvokingVertex(0x8E4D)              # FIRST
    g.ClipControl(0x8CA1, 0x935F)          # ZERO_TO_ONE
    g.PixelStorei(0x0CF2, 7)               # UNPACK_ROW_LENGTH
    g.PixelStorei(0x0CF5, 1)               # UNPACK_ALIGNMENT
    g.BindBuffer(0x88EC, buf.glo)          # PIXEL_UNPACK_BUFFER
    g.Disable(0x8F9D)                      # PRIMITIVE_RESTART
    g.ClearColor(0.1, 0.2, 0.3, 0.4)
    g.ActiveTexture(0x84C0 + 3)
    assert glstate.errors() == []


def _without(s, keys=PLACES):
    return {k: v for k, v in s.items() if k not in keys}


def test_kept_restores_the_host_and_renders_as_on_a_fresh_context(gl):
    from voxel_addon import light
    r = renderer(gl, floor(top="grass"), shadows=True)
    ref = r.render(CAM, 12.0, SIZE)
    r.release()
    blocks = floor(top="grass")
    keep: list = []
    _hostile(gl, keep)
    host = glstate.snapshot()
    with glstate.kept():
        inside = glstate.snapshot()
        from voxel_addon.render.pipeline import Renderer
        r = Renderer(gl, Settings(msaa=1, dof=False, godrays=False, shadows=True, clouds=False))
        r.set_area(blocks, light.solve(blocks), 0, 0)
        img = r.render(CAM, 12.0, SIZE)
        r.release()
    assert glstate.errors() == []
    assert glstate.snapshot() == host, "the host's GL state is back"
    assert np.array_equal(img, ref), "the pipeline drew as on its own context"
    assert img.std() > 10  # a real picture (sky and ground), not one colour
    glstate.reset()  # (the hostile host state must not reach the next test)
    for k in keep:
        k.release()
    assert _without(inside) == _without(_fresh_snapshot())


def _fresh_snapshot():
    """The state of a brand-new moderngl context (the oracle for reset()), taken in
    a subprocess: switching contexts here would disturb the shared test context."""
    import ast
    import subprocess
    import sys
    from pathlib import Path
    code = ("import moderngl; from voxel_addon.render import glstate; "
            "c = moderngl.create_standalone_context(backend='egl'); print(repr(glstate.snapshot()))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         cwd=Path(__file__).resolve().parents[2]).stdout
    return ast.literal_eval(out.strip().splitlines()[-1])


def test_the_hostile_state_breaks_an_unprotected_frame(gl):
    """Without kept() the same host state spoils the frame: the test above can fail.
    (A fresh Renderer each time: a frame whose draws all fail would read back the
    previous frame still in the output texture.)"""
    r = renderer(gl, floor(top="grass"), shadows=True)
    ref = r.render(CAM, 12.0, SIZE)
    r.release()
    keep: list = []
    _hostile(gl, keep)
    g = glstate.gl()  # (texture uploads would fail outright with these two)
    g.BindBuffer(0x88EC, 0)
    g.PixelStorei(0x0CF2, 0)
    try:
        r = renderer(gl, floor(top="grass"), shadows=True)
        img = r.render(CAM, 12.0, SIZE)
        r.release()
    finally:
        glstate.reset()
        for k in keep:
            k.release()
    assert np.abs(img.astype(int) - ref).mean() > 20


def test_snapshot_sees_each_change(gl):
    """Every kind of state snapshot() claims to cover is really read back."""
    g = glstate.gl()
    keep: list = []
    with glstate.kept():
        base = glstate.snapshot()
        _hostile(gl, keep)
        changed = glstate.snapshot()
        glstate.reset()
    diff = {k for k in base if base[k] != changed[k]}
    for k in keep:
        k.release()
    assert {"caps", "program", "vao", "blend_func", "blend_eq", "cull_mode", "depth_func", "polygon_mode",
            "provoking", "clip", "pixel_store", "buffers", "textures", "clear_color",
            "active_texture"} <= diff, diff
    assert glstate.errors() == []
    assert g is glstate.gl()



def test_a_gl41_context_is_not_asked_for_gl43_state(tmp_path):
    """macOS's GL 4.1 answers INVALID_ENUM for storage / dispatch-indirect buffers and
    fixed-index restart: on a 4.1 context (Mesa's override) the snapshot leaves them
    out, and round-trips without a GL error."""
    import os
    import subprocess
    import sys
    from pathlib import Path
    root = Path(__file__).resolve().parents[2]
    code = ("import moderngl, json\n"
            "from voxel_addon.render import glstate\n"
            "ctx = moderngl.create_standalone_context(backend='egl')\n"
            "s = glstate.snapshot()\n"
            "glstate.reset(); glstate.restore(s)\n"
            "print(json.dumps([ctx.version_code, sorted(s['caps']), sorted(s['buffers']),"
            " sorted(s['indexed']), glstate.errors()]))\n")
    env = dict(os.environ, PYTHONPATH=str(root), MESA_GL_VERSION_OVERRIDE="4.1",
               MESA_GLSL_VERSION_OVERRIDE="410")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    import json
    version, caps, bufs, indexed, errs = json.loads(r.stdout)
    assert version == 410 and errs == []
    assert not set(glstate.GL43) & set(caps + bufs + indexed)
    assert 0x8A11 in indexed and 0x8892 in bufs  # the 4.1 state is still saved
