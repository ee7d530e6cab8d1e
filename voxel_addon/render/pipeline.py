"""The frame: shadow map → G-buffer → depth-peeled layers → deferred light → sky,
SSAO, god rays → distance blur (thesis fig. 5.15). Works on any moderngl context
it is given (standalone EGL for the CLI and tests, Blender's inside its offscreen).
"""
from __future__ import annotations

import math
import time
from typing import NamedTuple

import numpy as np

from ..core import chunk
from ..core.blocks import REGISTRY
from . import camera as cam
from . import sky
from .geometry import Geometry, Stats
from . import oit
from .passes import GeometryPass, Pass, Peel
from .lightvol import LightVolume
from .frame import BINDING, FrameBlock
from .programs import UNITS, Programs
from .settings import DEBUG_VIEWS, Settings

_BIAS = np.array([[.5, 0, 0, .5], [0, .5, 0, .5], [0, 0, .5, .5], [0, 0, 0, 1]])


class Renderer:
    def __init__(self, ctx, settings: Settings | None = None):
        self.ctx = ctx
        self.s = settings or Settings()
        self.progs = Programs(ctx)
        self.geo = Geometry(ctx)
        self.vol = LightVolume(ctx, 1)  # nothing resident yet: open daylight everywhere
        self.frame = FrameBlock(ctx)
        self._none = ctx.detect_framebuffer(0)  # GL's framebuffer 0: always valid to bind
        self._idle = ctx.framebuffer(ctx.renderbuffer((1, 1)))  # bound while targets change
        self.targets: dict = {}
        self.stats: dict = {}
        self.area = None             # (cx0, cy0, cx1, cy1): the box of the shown chunks
        self.edge_water = None       # set_area: the fraction of the area's edge that is
                                     # open water (source.open_sea)
        self.lights: dict = {}       # (cx, cy) -> its light (None: open daylight; or packed)
        self._vol_key = None         # the light window last made resident
        self._fs: dict = {}          # program -> empty VAO for fullscreen passes
        self._graphs: dict = {}      # switches -> the frame's passes, for these targets
        # llvmpipe implements anisotropic filtering as an EWA scan (Heckbert) over the
        # whole texel footprint of a pixel, derived from the coordinate differences of
        # the 2x2 quad and not bounded by the maximum anisotropy. Nearly edge-on sliver
        # triangles (waving shears plant planes and leaf faces that would otherwise be
        # exactly edge-on) and MSAA-covered pixels whose centre lies outside the
        # triangle get footprints of thousands of texels: the landscape took 5-10 s per
        # frame, 98 % in the plant and leaf passes' texture fetches (waving or MSAA
        # off: under 1 s). Software GL samples isotropically; GPUs bound the probes.
        # (Set max_anisotropy to force it, e.g. to measure.)
        r = ctx.info.get("GL_RENDERER", "").lower()
        self.software = any(k in r for k in ("llvmpipe", "softpipe", "swrast"))
        self.max_anisotropy = 1.0 if self.software else float(getattr(ctx, "max_anisotropy", 16.0))
        self._textures()

    # ------------------------------------------------------------------ data
    def _textures(self):
        from .. import textures
        rgba = textures.texture_array(origin="bottom")
        glow = textures.glow_array(origin="bottom")
        n = rgba.shape[0]
        self.tex = self.ctx.texture_array((16, 16, n), 4, rgba.tobytes())
        self.glow = self.ctx.texture_array((16, 16, n), 1, glow.tobytes())
        # moderngl cannot write a texture array's levels, so GL builds the chain
        self.tex.build_mipmaps()
        self.tex.filter = (0x2702, 0x2600)  # linear-mipmap-nearest min, nearest mag
        self.tex.repeat_x = self.tex.repeat_y = True
        self.tex.anisotropy = self._aniso = 1.0  # per frame from the settings (draw)
        self.glow.filter = (0x2600, 0x2600)
        scale = np.zeros(64, np.float32)
        for i, b in enumerate(REGISTRY.blocks):
            if b.shape != "none":
                for layer in set(REGISTRY.face_texture[i].tolist()):
                    scale[layer] = max(scale[layer], b.glow)
        # water's layers are marked (block.frag: glow 1, depth colour; shade.glsl: waves)
        for layer in set(REGISTRY.face_texture[REGISTRY.id("water")].tolist()):
            scale[layer] = -1.0
        self.glow_scale = scale

    def update_chunks(self, payloads) -> None:
        """Show or replace chunks, each an object with .key (cx, cy), .mesh (a
        meshing.ChunkMesh built with the chunk's one-voxel ring of neighbours) and
        .light (its (16, 16, 256) uint16 packed light, None: open daylight, or
        core.chunk.pack_layers of it: kept so, a third of the memory). Only these are
        uploaded: meshes into free slots of the geometry, light into the volume once
        the light window (around the camera, prepare) needs it."""
        meshes = {}
        for p in payloads:
            k = (int(p.key[0]), int(p.key[1]))
            light = p.light
            shape = light[0] if isinstance(light, tuple) else np.shape(light)
            if light is not None and tuple(shape) != (16, 16, 256):
                raise ValueError(f"chunk {k}: light must be (16, 16, 256), got {shape}")
            meshes[k] = p.mesh
            self.lights[k] = light
            self.vol.forget(k)
        self.geo.update(meshes)
        self._shown()

    def remove_chunks(self, keys) -> None:
        """Stop showing these chunks (unknown keys are ignored); nothing else moves."""
        keys = [(int(k[0]), int(k[1])) for k in keys]
        self.geo.remove(keys)
        for k in keys:
            self.lights.pop(k, None)
            self.vol.forget(k)
        self._shown()

    def set_area(self, blocks: np.ndarray, light: np.ndarray, cx0: int, cy0: int,
                 ring: bool = False, method: str = "greedy", backend: str | None = None,
                 light_at: tuple[int, int] | None = None, closed: bool = True):
        """Show the chunks [cx0, cx0+w) x [cy0, cy0+h) from a block array and their light
        instead of what was shown.

        blocks is (16w, 16h, 256), or with ring=True (16w+2, 16h+2, 256) including a
        one-voxel ring of neighbours (else outside counts as air); light is the packed
        light of whole chunks from light_at (default (cx0, cy0)), e.g. (16w, 16h, 256);
        chunks it does not cover get open daylight. closed: the ring counts as air all
        the same, so the area's outer wall has faces (seen from outside, or from a side
        view, the area is a closed block, not a slab open into its caves), and caves
        that reach the wall end in stone (_close); ring=True then only matters for
        closed=False.
        """
        from .. import meshing
        if ring:
            self.edge_water = _edge_water(blocks)
        if ring and closed:
            blocks = _close(blocks)
        elif not ring:
            pad = np.zeros((blocks.shape[0] + 2, blocks.shape[1] + 2, 256), np.uint16, order="F")
            pad[1:-1, 1:-1] = blocks
            blocks = pad
        # one batched call for the whole area (meshing README: build_chunks); backend
        # None: the OpenCL twin when there is a device (same meshes, much faster)
        meshes = meshing.build_chunks(blocks, (cx0, cy0), method=method, backend=backend)
        lights = chunk.cut(light, *(light_at or (cx0, cy0)))
        self.remove_chunks([k for k in self.geo.keys if k not in meshes])
        self.update_chunks(_Chunk(k, m, lights.get(k)) for k, m in meshes.items())

    def set_meshes(self, meshes: dict) -> None:
        """{(cx, cy): meshing.ChunkMesh} to draw instead of what was shown; the light
        known for chunks that stay is kept (set_light)."""
        self.remove_chunks([k for k in self.geo.keys if k not in meshes])
        self.geo.update(meshes)
        self._shown()

    def set_light(self, light: np.ndarray, cx0: int, cy0: int) -> None:
        """Packed light of whole chunks from (cx0, cy0), e.g. (16w, 16h, 256); the
        volume takes the part inside the light window (outside it surfaces get open
        daylight, the fog hides them)."""
        for k, v in chunk.cut(light, cx0, cy0).items():
            self.lights[k] = v
            self.vol.forget(k)
        self._vol_key = None

    def _shown(self) -> None:
        """The shown chunks changed: their box (self.area), the light window again."""
        self.area = self.geo.bounds()
        self._vol_key = None

    def _sync_light(self, camera) -> None:
        """The light window (Settings.light_radius chunks around the camera's chunk,
        within the shown area) resident in the toroidal volume: only chunks that
        entered it or whose light changed are uploaded."""
        a, r = self.area, self.s.light_radius
        cx, cy = math.floor(camera.x) >> 4, math.floor(camera.y) >> 4
        if a is None:
            win = (cx, cy, cx, cy)
        else:
            x0, y0 = max(a[0], cx - r), max(a[1], cy - r)
            win = (x0, y0, max(x0, min(a[2], cx + r + 1)), max(y0, min(a[3], cy + r + 1)))
        key = (win, r)
        if key == self._vol_key:
            return
        n = 1 if a is None else max(1, min(2 * r + 1, max(a[2] - a[0], a[3] - a[1])))
        if self.vol.n < n:  # grown by doubling: a streamed area grows chunk by chunk
            self.vol.release()
            self.vol = LightVolume(self.ctx, min(2 * r + 1, max(n, 2 * self.vol.n)))
            self._graphs.clear()
        for x in range(win[0], win[2]):
            for y in range(win[1], win[3]):
                if not self.vol.resident((x, y)):
                    self.vol.upload((x, y), self.lights.get((x, y)))
        self.vol.set_window(*win)
        self._vol_key = key

    # ------------------------------------------------------------------ targets
    def _targets(self, w, h, need=(3, True, True, True)):
        """The frame's targets at (w, h): the ones every frame uses, and those of the
        effects in need (peel layers, SSAO, distance blur, shadows), each made the
        first time a frame uses it and kept until the size changes (the viewport's
        defaults leave a third of them unused: ~30 MB at 1057x618 with MSAA 2)."""
        ms = max(1, min(self.s.msaa, self.ctx.max_samples))
        key = (w, h, ms, self.s.shadow_size, self.s.transparency == "oit")
        if self.targets.get("key") != key:
            self._release_targets()
            self.targets = self._base_targets(w, h, ms, key)
        self._more_targets(self.targets, *need)
        return self.targets

    def _tex(self, w, h, comp=4, dtype="f2"):
        x = self.ctx.texture((w, h), comp, dtype=dtype)
        x.repeat_x = x.repeat_y = False
        return x

    def _gbuf(self, w, h, ms):
        c = self.ctx
        d = c.depth_texture((w, h), samples=ms if ms > 1 else 0)
        a = c.texture((w, h), 4, samples=ms if ms > 1 else 0)
        nrm = c.texture((w, h), 4, samples=ms if ms > 1 else 0)
        return {"depth": d, "albedo": a, "normal": nrm, "fbo": c.framebuffer([a, nrm], d)}

    def _base_targets(self, w, h, ms, key):
        c, tex = self.ctx, self._tex
        t = {"key": key, "ms": ms, "size": (w, h)}
        t["g"] = self._gbuf(w, h, ms)
        t["peel"], t["layers"], t["layer_fbo"] = [], [], []
        t["opaque"], t["front"] = tex(w, h), tex(w, h, 4, "f4")
        t["shaded_fbo"] = c.framebuffer([t["opaque"], t["front"]])
        t["comp"] = tex(w, h)
        t["comp_fbo"] = c.framebuffer([t["comp"]])
        t["out"] = c.texture((w, h), 4)
        t["out_fbo"] = c.framebuffer([t["out"]])
        if key[-1]:  # only while OIT is chosen: peeling frames never pay for its targets
            t["oit"] = oit.targets(c, (w, h), ms, t["g"]["depth"])
        return t

    def _more_targets(self, t, layers, ssao, dof, shadows):
        """Add the targets of these effects that t does not have yet."""
        c, tex, (w, h), ms = self.ctx, self._tex, t["size"], t["ms"]
        while len(t["peel"]) < layers:
            t["peel"].append(self._gbuf(w, h, ms))
        # OIT resolves into layer 0
        while len(t["layers"]) < max(layers, 1 if t["key"][-1] else 0):
            t["layers"].append(tex(w, h))
            t["layer_fbo"].append(c.framebuffer([t["layers"][-1]]))
        if ssao and "ao" not in t:
            t["ao"], t["ao2"] = tex(w, h, 1, "f1"), tex(w, h, 1, "f1")
            t["ao_fbo"] = [c.framebuffer([t["ao"]]), c.framebuffer([t["ao2"]])]
        if dof and "blur" not in t:
            t["blur"], t["blur2"] = tex(w, h), tex(w, h)
            t["blur_fbo"] = [c.framebuffer([t["blur"]]), c.framebuffer([t["blur2"]])]
        if shadows and "shadow" not in t:
            sm = c.depth_texture((self.s.shadow_size,) * 2)
            sm.compare_func = "<="
            sm.filter = (0x2601, 0x2601)
            sm.repeat_x = sm.repeat_y = False
            t["shadow"], t["shadow_fbo"] = sm, c.framebuffer(depth_attachment=sm)

    def _release_targets(self):
        # moderngl rebinds its last bound framebuffer after making one: not a released one
        self._idle.use()
        def rel(x):
            if isinstance(x, dict):
                for v in x.values():
                    rel(v)
            elif isinstance(x, list):
                for v in x:
                    rel(v)
            elif hasattr(x, "release"):
                x.release()
        self._graphs.clear()
        rel({k: v for k, v in self.targets.items() if k != "key"})
        self.targets = {}

    # ------------------------------------------------------------------ frame
    def render(self, camera: cam.Camera, hours: float, size) -> np.ndarray:
        """Render to an (h, w, 3) uint8 image (row 0 = top)."""
        w, h = size
        fbo = self.draw(camera, hours, (w, h))
        data = fbo.read(components=3)
        return np.frombuffer(data, np.uint8).reshape(h, w, 3)[::-1].copy()

    def draw(self, camera: cam.Camera, hours: float, size):
        """Run the frame; returns the framebuffer holding the final RGBA8 image."""
        t0 = time.perf_counter()
        f = self.prepare(camera, hours, size)
        self.submit(f)
        f.stats["cpu_ms"] = (time.perf_counter() - t0) * 1e3
        self.stats = f.stats
        return f.T["out_fbo"]

    def prepare(self, camera: cam.Camera, hours: float, size) -> "_Frame":
        """A frame's work that is not drawing, all before the first draw: its values
        into the one uniform block, culling and the batches of every pass (the heavy
        draws leave the calling thread's caches cold; see Geometry.batches). Programs,
        textures and GL switches of each pass are made once (_graph, passes.py) for
        the switches and targets. One prepared frame at a time: the frame block and the
        command buffers are shared, so submit it before preparing the next."""
        s = self.s
        s.check()
        w, h = size
        # the whole height of the area stays in view; the caller's camera is left alone
        camera = camera.fitted(w / h, s.fov, s.distance * 16 * 1.5 + 256.0)
        self._sync_light(camera)  # before _graph: it may make a bigger volume
        self.tex.use(UNITS["tex"])  # the arrays stay bound: no pass uses their units
        self.glow.use(UNITS["glow_tex"])
        aniso = max(1.0, min(float(s.anisotropy), self.max_anisotropy))
        if aniso != self._aniso:
            self.tex.anisotropy = self._aniso = aniso
        # (the sky in steps of 15 s of the day: a dragged slider reuses the cached table)
        sp = sky.params(round(hours * 240.0) / 240.0, s.exposure)
        debug = DEBUG_VIEWS.index(s.debug)
        vp, inv_vp = cull_vp, _ = camera.matrices()
        draw_cam = camera
        if s.debug == "culling":  # from above; regions still culled for the real camera
            draw_cam = _top_camera(camera)
            vp, inv_vp = draw_cam.matrices()
        shadows = s.shadows and debug in (0, 4, 6) and sp["light_dir"][2] > 0.02
        geo = self.geo
        if geo.gpu:
            view = geo.gpu_batches(cull_vp, geo.parts)
            seen = geo.seen("blend", cull_vp)
        else:
            view = geo.batches(geo.cull(cull_vp), geo.parts)
            seen = view.get("blend") is not None
        use_oit = seen and s.transparency == "oit"  # one forward pass instead (oit.py)
        layers = s.peel_layers if seen and not use_oit else 0
        ssao = s.ssao and debug in (0, 6)
        sun_px, sun_vis, sun_r = _sun_on_screen(vp, draw_cam, sp["light_dir"], w, h, s.fov)
        gods = s.godrays and debug in (0, 6) and sun_vis
        dof = s.dof and debug == 0 and not camera.ortho  # parallel rays: no distance blur
        T = self._targets(w, h, (layers, ssao, dof, shadows))
        G = self._graph(T, (T["ms"], debug, shadows, layers, ssao, gods, dof, s.smooth_mag,
                            s.msaa_alpha, s.per_sample, s.fog, s.fill_holes, geo.indirect_ok,
                            use_oit))

        # the frame's values, for every program at once
        F = self.frame
        fog_end = (s.distance + 0.5) * 16.0  # thick by the nearest edge of the shown area
        if shadows:
            light_vp, texel, bias = self._shadow_matrix(camera, sp["light_dir"])
            F.set(shadow_vp=light_vp, shadow_mat=_BIAS @ light_vp, shadow_texel=texel,
                  shadow_bias=bias)
            names = G.shadow.names
            cast = (geo.gpu_batches(light_vp, names, "shadow") if geo.gpu
                    else geo.batches(geo.cull(light_vp), names, "shadow"))
        sky_on = debug in (0, 6)  # debug views show black where there is no surface
        for k in ("zenith", "horizon", "halo", "disc"):
            F.set(**{f"sky_{k}": sp[k] if sky_on else (0.0, 0.0, 0.0)})
        F.set(**sky_values(s, sp, hours, sky_on, debug, camera, self.area, h))
        F.set(vp=vp, inv_vp=inv_vp, cam_pos=(draw_cam.x, draw_cam.y, draw_cam.z),
              cam_fwd=draw_cam._fwd(), ortho=draw_cam.ortho,
              far_dist=camera.far, shadow_eye=(camera.x, camera.y, camera.z),
              # orthographic: no eye to fade from; the map covers the view box
              shadow_fade=1e9 if camera.ortho else s.shadow_fade,
              day_ambient=sp["ambient"], day_u=sp["u"],
              day_direct=sp["direct"], sky_stars=sp["stars"] if sky_on and s.stars else 0.0,
              sky_light_dir=sp["light_dir"], time=s.time, waving=s.waving,
              godray_strength=s.godray_strength * sky.godray_scale(sp), sun_px=sun_px,
              sun_radius=sun_r,
              sun_visible=sun_vis, fog_start=fog_end * 0.55, fog_end=fog_end,
              dof_start=fog_end * 0.8, dof_end=fog_end * 1.15, ssao_radius=s.ssao_radius)
        F.upload()
        F.buf.bind_to_uniform_block(BINDING)
        if geo.gpu:
            geo.barrier()
        for prog in G.volume:
            self.vol.uniforms(prog)
        return _Frame(T, G, view, cast if shadows else None, geo, layers, use_oit, ssao, dof)

    def submit(self, f: "_Frame") -> None:
        """Run the passes of a prepared frame."""
        G, geo, stats, fs = f.G, self.geo, f.stats, self._fullscreen
        if f.cast is not None:  # shadows on: cleared even with no caster in view
            G.shadow.draw(geo, f.cast, stats, shadow=True)  # blend casts none (§5.4.1)
        G.g.draw(geo, f.view, stats)
        G.transparency.geometry(geo, f.view, stats)
        G.shade.run(fs)
        G.transparency.shade(geo, f.view, stats, fs)
        for p in G.post:  # SSAO and its blur, composite, distance blur, final
            p.run(fs)

    # ------------------------------------------------------------------ helpers
    def _graph(self, T, key) -> "_Graph":
        """The passes of a frame for these targets and one combination of switches:
        programs compiled (cached by Programs), targets and textures bound to each pass
        (memoised until the targets or the light volume change)."""
        G = self._graphs.get(key)
        if G is not None:
            return G
        ms, debug, shadows, layers, ssao, gods, dof, smooth, msaa_alpha, per_sample, fog, \
            fill, indirect, use_oit = key
        c, get = self.ctx, self.progs.get
        cut = {"ALPHA_TEST": 1, "MSAA_ALPHA": msaa_alpha}
        g = {"SAMPLES": ms, "SMOOTH_MAG": smooth, "DEBUG_AGG": debug == 5,
             "UNIFORM_ORIGIN": not indirect}
        d = {"SAMPLES": ms, "PER_SAMPLE": per_sample, "SHADOWS": shadows,
             "FOG": fog and debug == 0, "DEBUG": debug if debug != 6 else 0}
        blocks = [("opaque", {}), ("cutout", cut), ("cutout2", cut)]

        def block(defines):
            prog = get("block.vert", "block.frag", defines)
            if "glow_scale" in prog:
                prog["glow_scale"].write(self.glow_scale.tobytes())
            return prog

        def full(frag, defines=None):
            return get("fullscreen.vert", frag, defines)

        sm = {"shadow_map": T["shadow"]} if shadows else {}  # (a target made when used)

        def gbuf(x):
            return dict(g_depth=x["depth"], g_albedo=x["albedo"], g_normal=x["normal"],
                        light_vol=self.vol.tex, **sm)

        dt_cf = c.DEPTH_TEST | c.CULL_FACE
        gb, peel = T["g"], T["peel"]
        G = _Graph()
        G.shadow = GeometryPass(c, T["shadow_fbo"], [
            (n, block({"SHADOW": 1, "ALPHA_TEST": n != "opaque", "UNIFORM_ORIGIN": not indirect}))
            for n, _ in blocks], dt_cf) if shadows else None
        G.g = GeometryPass(c, gb["fbo"], [(n, block({**g, **x})) for n, x in blocks], dt_cf)
        G.shade = Pass(c, T["shaded_fbo"], full("deferred.frag", {**d, "FILL_HOLES": fill}),
                       clear=True, **gbuf(gb))
        if use_oit:  # resolved into layer 0: the composite blends it as one peel layer
            o = T["oit"]
            G.transparency = oit.OIT(
                Pass(c, o["fbo"], block({**g, **d, "OIT": 1}), c.DEPTH_TEST | c.BLEND,
                     clear=True, light_vol=self.vol.tex, **sm),
                Pass(c, T["layer_fbo"][0], full("oit_resolve.frag", {"SAMPLES": ms}),
                     accum=o["accum"], reveal=o["reveal"]))
        else:  # no blending, the nearest remaining layer each time
            layer = full("deferred.frag", {**d, "LAYER": 1}) if layers else None
            G.transparency = Peel(
                [Pass(c, p["fbo"], block({**g, "PEEL": i + 1}), c.DEPTH_TEST, clear=True,
                      opaque_depth=gb["depth"],
                      prev_depth=peel[i - 1]["depth"] if i else gb["depth"])
                 for i, p in enumerate(peel[:layers])],
                [Pass(c, f, layer, clear=True, **gbuf(p))
                 for f, p in zip(T["layer_fbo"][:layers], peel)])
        post = []
        if ssao:
            post += [Pass(c, T["ao_fbo"][0], full("ssao.frag"), front=T["front"]),
                     Pass(c, T["ao_fbo"][1], full("blur.frag", {"VERTICAL": 0}), src=T["ao"]),
                     Pass(c, T["ao_fbo"][0], full("blur.frag", {"VERTICAL": 1}), src=T["ao2"])]
        # composite: sky, layers, god rays
        post.append(Pass(c, T["comp_fbo"], full("composite.frag", {
            "LAYERS": G.transparency.layers, "SSAO": ssao, "GODRAYS": gods}),
            opaque=T["opaque"], front=T["front"], **({"ao": T["ao"]} if ssao else {}),
            **{f"layer{i}": x for i, x in enumerate(T["layers"])}))
        if dof:  # distance blur
            post += [Pass(c, T["blur_fbo"][0], full("blur.frag", {"BILATERAL": 1, "VERTICAL": 0}),
                          src=T["comp"]),
                     Pass(c, T["blur_fbo"][1], full("blur.frag", {"BILATERAL": 1, "VERTICAL": 1}),
                          src=T["blur"])]
        G.final = Pass(c, T["out_fbo"], full("final.frag", {"DOF": dof}),
                       sharp=T["comp"], **({"blurred": T["blur2"]} if dof else {}))
        G.post = post + [G.final]
        G.volume = [G.shade.prog] + G.transparency.volume_programs()
        self._graphs[key] = G
        return G

    def _fullscreen(self, prog):
        vao = self._fs.get(prog.glo)
        if vao is None:  # attribute-less triangle: the vertex shader makes the corners
            vao = self._fs[prog.glo] = self.ctx.vertex_array(prog, [])
        vao.render(mode=self.ctx.TRIANGLES, vertices=3)

    def _shadow_matrix(self, camera: cam.Camera, light_dir):
        """Ortho light matrix fitted to the view frustum up to the shadow fade distance.

        Returns (matrix, world size of a shadow texel, depth bias in depth units).
        Python floats throughout: a few dozen products, where NumPy's per-call cost
        was most of the frame's matrix work."""
        if camera.ortho:  # the view box, in depth where the shown area is
            lo, hi = camera.near, camera.far
            if self.area:
                cx0, cy0, cx1, cy1 = self.area
                d = [camera.depth((x, y, z)) for x in (16 * cx0, 16 * cx1)
                     for y in (16 * cy0, 16 * cy1) for z in (0.0, 256.0)]
                lo, hi = max(lo, min(d)), min(hi, max(d))
            pts = camera.corners(max(hi, lo + 1.0), lo)
        else:
            pts = camera.corners(self.s.shadow_fade + 2.0)
        n = len(pts)
        mid = [sum(p[k] for p in pts) / n for k in range(3)]
        rows = cam._view_rows(mid, [-v for v in light_dir])  # light space: +z to the light
        lc = [[r[0] * x + r[1] * y + r[2] * z + r[3] for r in rows] for x, y, z in pts]
        lo = [min(c[k] for c in lc) for k in range(3)]
        hi = [max(c[k] for c in lc) for k in range(3)]
        # the near plane reaches back to the top of the shown area so off-screen casters
        # between the light and the view still cast; depth precision stays bounded
        top = hi[2]
        if self.area:
            cx0, cy0, cx1, cy1 = self.area
            r = rows[2]
            top = max(top, max(r[0] * x + r[1] * y + r[2] * z + r[3]
                               for x in (16 * cx0, 16 * cx1) for y in (16 * cy0, 16 * cy1)
                               for z in (0.0, 256.0)))
        near, far = -top - 1.0, -lo[2] + 1.0
        # ortho(lo.x, hi.x, lo.y, hi.y, near, far) @ view, row by row
        sx, sy, sz = 2 / (hi[0] - lo[0]), 2 / (hi[1] - lo[1]), -2 / (far - near)
        ox, oy = -(hi[0] + lo[0]) / (hi[0] - lo[0]), -(hi[1] + lo[1]) / (hi[1] - lo[1])
        oz = -(far + near) / (far - near)
        m = np.array([[v * sx for v in rows[0][:3]] + [rows[0][3] * sx + ox],
                      [v * sy for v in rows[1][:3]] + [rows[1][3] * sy + oy],
                      [v * sz for v in rows[2][:3]] + [rows[2][3] * sz + oz],
                      [0.0, 0.0, 0.0, 1.0]])
        texel = max(hi[0] - lo[0], hi[1] - lo[1]) / self.s.shadow_size
        return m, texel, 0.05 / (far - near)  # 0.05 blocks of depth bias

    def release(self):
        for vao in self._fs.values():
            vao.release()
        self._fs.clear()
        self._release_targets()
        self.geo.release()
        self.vol.release()
        self.frame.release()
        self._none.use()  # else moderngl would rebind a released framebuffer of ours later
        for x in (self._idle, *self._idle.color_attachments):
            x.release()
        self.progs.release()
        self.tex.release()
        self.glow.release()


class _Frame:
    """What prepare() made for submit(): targets, passes, batches, switches. A host
    that composites the frame itself (blender/viewport) reads `color` (the final RGBA8
    texture), `depth` (the opaque G-buffer depth, multisampled under MSAA: T["ms"]
    samples) and `blend_depth` (the nearest transparent surface's depth when peeling
    drew one, else None; OIT writes no depth)."""
    __slots__ = ("T", "G", "view", "cast", "stats", "layers", "use_oit", "ssao", "dof")

    def __init__(self, T, G, view, cast, geo, layers, use_oit, ssao, dof):
        self.T, self.G, self.view, self.cast = T, G, view, cast
        self.layers, self.use_oit, self.ssao, self.dof = layers, use_oit, ssao, dof
        self.stats = Stats(geo)

    @property
    def color(self):
        return self.T["out"]

    @property
    def depth(self):
        return self.T["g"]["depth"]

    @property
    def blend_depth(self):
        return self.T["peel"][0]["depth"] if self.layers else None


class _Graph:
    """A frame's passes (passes.py) for one set of targets and switches."""
    __slots__ = ("shadow", "g", "shade", "transparency", "post", "final", "volume")

    def programs(self) -> list:
        return [p for x in (self.shadow, self.g, self.shade, self.transparency, *self.post)
                if x is not None for p in x.programs()]


def _edge_water(blocks: np.ndarray) -> float:
    """The fraction of an area's outermost columns (inside its ring) whose top is water."""
    water = REGISTRY.id("water")
    cols = np.concatenate([blocks[1, 1:-1], blocks[-2, 1:-1], blocks[1:-1, 1], blocks[1:-1, -2]])
    solid = cols != 0
    top = 255 - np.argmax(solid[:, ::-1], axis=1)
    return float((cols[np.arange(len(cols)), top] == water).mean())


def _close(blocks: np.ndarray) -> np.ndarray:
    """A copy of an area with its one-voxel ring: the ring is air (water next to
    water: the sea beyond the area continues it, include/water.glsl) and the caves
    (air below the column's top) of the area's outermost voxels are stone, so every
    face of the outer wall is drawn, from outside and from inside a cave."""
    b = np.array(blocks, order="F")
    stone, water = REGISTRY.id("stone"), REGISTRY.id("water")
    for inner, outer in (((1, slice(None)), (0, slice(None))), ((-2, slice(None)), (-1, slice(None))),
                         ((slice(None), 1), (slice(None), 0)), ((slice(None), -2), (slice(None), -1))):
        wall = b[inner]                                # (n, 256) columns of one side
        solid = wall != 0
        top = np.where(solid.any(1), 255 - np.argmax(solid[:, ::-1], axis=1), -1)
        cave = (~solid) & (np.arange(256)[None, :] < top[:, None])
        wall[cave] = stone
        b[inner] = wall
        b[outer] = np.where(wall == water, water, 0)
    return b


def sky_values(s: Settings, sp: dict, hours: float, sky_on: bool, debug: int, camera,
               area, h: int) -> dict:
    """The frame block's sky, haze, clouds, sea, fade and display values (issue 20).
    The sea beyond the area shows where the world has one (Settings.sea_level; the CLI
    also asks source.open_sea whether the shown area's edge is at sea)."""
    zero = np.full((sky.NE * sky.NA, 4), math.log(sky.EPS))
    fade_end = s.fade_distance or (s.distance + 0.5) * 16.0
    box = [16.0 * v for v in area] if area else [0.0, 0.0, 0.0, 0.0]
    fov = camera.fov or s.fov
    return dict(
        sky_a=sp["sky_a"] if sky_on else zero, sky_b=sp["sky_b"] if sky_on else zero,
        sun_dir=sp["sun_dir"], sky_pole=sp["pole"],
        fog_density=0.0014 * s.haze if sky_on else 0.0, fog_height=s.fog_height,
        cloud_sun=sp["cloud_sun"], cloud_sky=sp["cloud_sky"], cloud_cover=s.cloud_cover,
        cloud_z=s.cloud_height, cloud_drift=sky.drift(hours, s.cloud_speed),
        # (the haze thins upwards from the sea, or from the generators' usual 62)
        sea_z=(s.sea_level if s.sea_level >= 0 else 62) + 0.95, area_box=box,
        star_px=2.0 * math.tan(math.radians(fov) / 2.0) / max(h, 1),
        fade_start=fade_end * (1.0 - s.fade_width) if s.fade else 1e9,
        fade_end=fade_end if s.fade else 2e9,
        # (the albedo views show the G-buffer's encoded colours as they are)
        display=(2 if s.tonemap else 1) if debug in (0, 6) else (1 if debug == 4 else 0),
        clouds=s.clouds and sky_on, cloud_shadows=s.cloud_shadows,
        sea=s.sea and sky_on and s.sea_level >= 0,
        water_fx=s.water and debug in (0, 6))


def _top_camera(camera: cam.Camera) -> cam.Camera:
    return cam.Camera(camera.x, camera.y, 250.0, camera.yaw, -89.9, camera.fov or 70.0,
                      camera.aspect, 1.0, 400.0)  # (an orthographic camera has no fov)


class _Chunk(NamedTuple):
    """What update_chunks takes (the world layer's Payload has these too)."""
    key: tuple
    mesh: object
    light: np.ndarray | None


def _sun_on_screen(vp, camera, light_dir, w, h, fov):
    if camera.ortho:  # parallel rays: the sun is no point on the screen
        return (0.0, 0.0), False, 0.0
    p = vp[:, :3] @ (camera.pos + np.asarray(light_dir) * 1000.0) + vp[:, 3]
    vis = p[3] > 0
    ndc = p[:2] / p[3] if vis else np.zeros(2)
    px = ((ndc[0] * 0.5 + 0.5) * w, (ndc[1] * 0.5 + 0.5) * h)
    r = math.tan(0.05) / math.tan(math.radians(fov) / 2) * h / 2
    return px, bool(vis), float(r)
