"""The live view's GPU side (viewport.py draws with it): per GL context a `Gpu`
(moderngl attached to Blender's context, a Renderer, the composite programs, which
chunk versions it uploaded) and per region a `Kept` frame (colour, depth already in
Blender's projection) that a still view redraws from without the pipeline."""
from __future__ import annotations

import numpy as np

from ..core.errors import VoxelError

MIN_GL = 410
KEPT_MAX = 8         # kept frames per GL context (one per region; quad view has four)


class Gpu:
    """The GL objects of one GL context: moderngl on Blender's context, a Renderer,
    the composite program; which chunk versions it has uploaded."""

    def __init__(self, native):
        import moderngl
        from _moderngl import DefaultLoader
        from ..render.pipeline import Renderer
        from ..render.settings import Settings
        # create_context() without a loader may take GLX on an EGL Blender (offscreen.py)
        self.ctx = moderngl.create_context(context=DefaultLoader())
        if self.ctx.version_code < MIN_GL:
            v = self.ctx.info.get("GL_VERSION", "?")
            self.ctx = None
            raise VoxelError(f"the voxel view needs OpenGL 4.1 or newer (this is {v})")
        self.native = native
        self.windows: set = set()  # the windows drawn with this context
        self.r = Renderer(self.ctx, Settings())
        self.versions: dict = {}
        self.feed = None
        self._comp: dict = {}
        self._vao: dict = {}
        self._kept_prog = None
        self.kept: dict = {}     # region pointer -> Kept
        self.gen = 0             # bumped whenever the uploaded chunks change

    def sync(self, feed) -> int:
        """Upload what changed in the feed; returns the number of chunks drawn."""
        r = self.r
        if self.feed is not feed:  # another world or distance: nothing of ours stays
            self.feed = feed
            self.versions = {k: None for k in self.versions}
        gone = [k for k in self.versions if k not in feed.chunks]
        new = [p for k, p in feed.chunks.items() if self.versions.get(k) != p.version]
        if gone or new:
            self.gen += 1
        if gone:
            r.remove_chunks(gone)
            for k in gone:
                del self.versions[k]
        if new:
            r.update_chunks(new)
            for p in new:
                self.versions[p.key] = p.version
        return len(self.versions)

    def program(self, samples, layers, keep=0):
        key = (samples, layers, keep)
        p = self._comp.get(key)
        if p is None:
            p = self._comp[key] = self.r.dev.program(
                "fullscreen.vert", "viewport.frag", {"SAMPLES": samples, "LAYERS": layers, "KEEP": keep}).obj
            _units(p)
        return p

    def composite(self, f, host, host_vp, sky, kept=None):
        """The frame into Blender's framebuffer (bound again here), depth tested; with
        `kept` (a region's Kept) into those targets first and drawn from there."""
        from ..render import glstate
        gl = glstate.gl()
        blend = f.blend_depth
        prog = self.program(f.targets.samples, 1 if blend is not None else 0, int(kept is not None))
        f.color.obj.use(_UNIT["color"])
        f.depth.obj.use(0)
        if blend is not None:
            blend.obj.use(9)
        prog["host_vp"].write(np.asarray(host_vp, np.float32).T.tobytes())
        prog["host_range"].value = tuple(host["depth_range"])
        prog["host_zero_one"].value = bool(host["clip"] and host["clip"][1] == 0x935F)
        prog["sky"].value = bool(sky)
        if kept is None:
            self._into_host(host)
            self._vao_of(prog).render(mode=self.ctx.TRIANGLES, vertices=3)
            return
        kept.fbo.use()  # (its viewport too)
        gl.Disable(0x0B71)  # DEPTH_TEST
        gl.Disable(0x0BE2)  # BLEND
        self._vao_of(prog).render(mode=self.ctx.TRIANGLES, vertices=3)
        self.draw_kept(kept, host)

    def draw_kept(self, kept, host):
        """A region's kept frame into Blender's framebuffer: what composite() wrote
        there, without the pipeline (needs no frame block nor G-buffer)."""
        prog = self._kept_prog
        if prog is None:
            prog = self._kept_prog = self.r.dev.program("fullscreen.vert", "viewport_kept.frag").obj
            _units(prog)
        kept.color.use(_UNIT["kept_color"])
        kept.depth.use(_UNIT["kept_depth"])
        self._into_host(host)
        self._vao_of(prog).render(mode=self.ctx.TRIANGLES, vertices=3)

    def _into_host(self, host):
        from ..render import glstate
        gl = glstate.gl()
        gl.BindFramebuffer(0x8CA9, host["fb"][0])
        gl.Viewport(*host["viewport"])
        gl.Enable(0x0B71)       # DEPTH_TEST
        gl.DepthFunc(0x0203)    # LEQUAL
        gl.DepthMask(1)

    def _vao_of(self, prog):
        vao = self._vao.get(prog.glo)
        if vao is None:
            vao = self._vao[prog.glo] = self.ctx.vertex_array(prog, [])
        return vao

    def kept_for(self, region, size):
        """The kept targets of a region (made or resized; the least recently used go
        beyond KEPT_MAX: regions of closed areas)."""
        k = self.kept.pop(region, None)
        old = [k] if k is not None and k.size != size else []
        if old:
            k = None
        self.kept[region] = k = k or Kept(self.ctx, size)
        while len(self.kept) > KEPT_MAX:
            old.append(self.kept.pop(next(iter(self.kept))))
        if old:  # moderngl rebinds its last framebuffer after making one: not a released one
            self.r.dev._idle.use()
            for x in old:
                x.release()
        return k

    def release(self):
        for k in self.kept.values():
            k.release()
        self.kept.clear()
        self._kept_prog = None
        for v in self._vao.values():
            v.release()
        self._vao.clear()
        self._comp.clear()  # (programs belong to the Renderer's cache)
        if self.r is not None:
            self.r.release()
            self.r = None

    def orphan(self):
        """Forget a set whose GL context is not current (it went with its window, or
        is another window's): its VAOs, framebuffers and queries are that context's
        alone (deleting their names here would hit this context's own), while textures,
        buffers and programs live in the object space all Blender's contexts share:
        free those from the current one."""
        import gc
        import moderngl as mgl
        shared = {mgl.Texture, mgl.Texture3D, mgl.TextureArray, mgl.TextureCube, mgl.Buffer,
                  mgl.Program, mgl.ComputeShader, mgl.Renderbuffer, mgl.Sampler}
        ctx = self.ctx
        for o in gc.get_objects():  # type(), not isinstance: a removed bpy struct raises
            if type(o) in shared and o.ctx is ctx:
                o.release()
        self._vao.clear()
        self._comp.clear()
        self.r = None


# texture units of the composite passes: among those glstate.kept() saves and restores
_UNIT = {"color": 1, "g_depth": 0, "prev_depth": 9, "kept_color": 1, "kept_depth": 0}


def _units(prog):
    for k, u in _UNIT.items():
        if k in prog:
            prog[k].value = u


class Kept:
    """A region's last composited frame, at the region's size: colour (alpha 0 where
    Blender's own picture stays) and depth in Blender's projection. While nothing that
    changes the picture changed (`look`), a redraw draws these and skips the pipeline."""
    __slots__ = ("size", "color", "depth", "fbo", "look", "quality")

    def __init__(self, ctx, size):
        self.size, self.look, self.quality = size, None, "full"
        self.color = ctx.texture(size, 4)
        self.depth = ctx.texture(size, 1, dtype="f4")
        for t in (self.color, self.depth):
            t.filter = (ctx.NEAREST, ctx.NEAREST)
        self.fbo = ctx.framebuffer([self.color, self.depth])

    def release(self):
        for x in (self.fbo, self.color, self.depth):
            x.release()
        self.look = None
