"""The frame: shadow map → G-buffer → depth-peeled layers → deferred light → sky,
SSAO, god rays → distance blur (thesis fig. 5.15). Works on any moderngl context
it is given (standalone EGL for the CLI and tests, Blender's inside its offscreen).
"""
from __future__ import annotations

import math
import time

import numpy as np

from ..core.blocks import REGISTRY
from . import camera as cam
from . import sky
from .geometry import Geometry
from . import lightvol, oit
from .lightvol import LightVolume
from .programs import Programs, pack, set_uniforms as _set
from .settings import DEBUG_VIEWS, Settings

_TEX_UNIT = 6  # block texture array, +1 its glow
_BIAS = np.array([[.5, 0, 0, .5], [0, .5, 0, .5], [0, 0, .5, .5], [0, 0, 0, 1]])


def _m(a) -> bytes:
    return np.asarray(a, np.float32).T.tobytes()  # column-major for GL


class Renderer:
    def __init__(self, ctx, settings: Settings | None = None):
        self.ctx = ctx
        self.s = settings or Settings()
        self.progs = Programs(ctx)
        self.geo = Geometry(ctx)
        self.vol: LightVolume | None = None
        self.targets: dict = {}
        self.stats: dict = {}
        self.area = None
        self._fs: dict = {}          # program -> empty VAO for fullscreen passes
        self._static: set = set()    # programs whose constant uniforms are set
        self._box = (None, None)     # (area, its 8 corners) for the shadow near plane
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
        self.glow_scale = scale

    def set_area(self, blocks: np.ndarray, light: np.ndarray, cx0: int, cy0: int,
                 ring: bool = False, method: str = "greedy", backend: str | None = None,
                 light_at: tuple[int, int] | None = None):
        """Show the chunks [cx0, cx0+w) x [cy0, cy0+h) from a block array and their light.

        blocks is (16w, 16h, 256), or with ring=True (16w+2, 16h+2, 256) including a
        one-voxel ring of neighbours (else outside counts as air); light is the packed
        light of whole chunks from light_at (default (cx0, cy0)), e.g. (16w, 16h, 256).
        """
        from .. import meshing, opencl
        if backend is None:  # the OpenCL twin builds the same meshes, much faster
            backend = "opencl" if opencl.available() else "numpy"
        if not ring:
            pad = np.zeros((blocks.shape[0] + 2, blocks.shape[1] + 2, 256), np.uint16, order="F")
            pad[1:-1, 1:-1] = blocks
            blocks = pad
        # one batched call for the whole area (meshing README: build_chunks)
        meshes = meshing.build_chunks(blocks, (cx0, cy0), method=method, backend=backend)
        self.set_meshes(meshes)
        self.set_light(light, *(light_at or (cx0, cy0)))

    def set_meshes(self, meshes: dict) -> None:
        """{(cx, cy): meshing.ChunkMesh} to draw."""
        self.geo.set_chunks(meshes)
        ks = np.array(list(meshes), int).reshape(-1, 2)
        if len(ks):
            self.area = tuple(int(v) for v in (*ks.min(0), *(ks.max(0) + 1)))

    def set_light(self, light: np.ndarray, cx0: int, cy0: int) -> None:
        """Upload packed light of whole chunks from (cx0, cy0): the part inside
        lightvol.window (outside it surfaces get open daylight, the fog hides them)."""
        w, h = light.shape[0] // 16, light.shape[1] // 16
        if self.area is None:
            self.area = (cx0, cy0, cx0 + w, cy0 + h)
        x0, y0, x1, y1 = lightvol.window(self.area, self.s.light_radius)
        x0, y0 = max(x0, cx0), max(y0, cy0)
        x1, y1 = max(x0, min(x1, cx0 + w)), max(y0, min(y1, cy0 + h))  # may be empty
        n = max(x1 - x0, y1 - y0, 1)
        if self.vol is None or self.vol.n < n:
            if self.vol:
                self.vol.release()
            self.vol = LightVolume(self.ctx, n)
        i, j = 16 * (x0 - cx0), 16 * (y0 - cy0)
        self.vol.upload_area(light[i:i + 16 * (x1 - x0), j:j + 16 * (y1 - y0)], x0, y0)
        self.vol.set_window(x0, y0, x1, y1)

    # ------------------------------------------------------------------ targets
    def _targets(self, w, h):
        ms = max(1, min(self.s.msaa, self.ctx.max_samples))
        key = (w, h, ms, self.s.shadow_size)
        if self.targets.get("key") == key:
            return self.targets
        self._release_targets()
        c = self.ctx
        t = {"key": key, "ms": ms}

        def gbuf():
            d = c.depth_texture((w, h), samples=ms if ms > 1 else 0)
            a = c.texture((w, h), 4, samples=ms if ms > 1 else 0)
            nrm = c.texture((w, h), 4, samples=ms if ms > 1 else 0)
            return {"depth": d, "albedo": a, "normal": nrm,
                    "fbo": c.framebuffer([a, nrm], d)}

        def tex(comp=4, dtype="f2"):
            x = c.texture((w, h), comp, dtype=dtype)
            x.repeat_x = x.repeat_y = False
            return x

        t["g"] = gbuf()
        t["peel"] = [gbuf() for _ in range(3)]
        t["opaque"], t["front"] = tex(), tex(4, "f4")
        t["shaded_fbo"] = c.framebuffer([t["opaque"], t["front"]])
        t["layers"] = [tex() for _ in range(3)]
        t["layer_fbo"] = [c.framebuffer([x]) for x in t["layers"]]
        t["ao"], t["ao2"] = tex(1, "f1"), tex(1, "f1")
        t["ao_fbo"] = [c.framebuffer([t["ao"]]), c.framebuffer([t["ao2"]])]
        t["comp"], t["blur"], t["blur2"] = tex(), tex(), tex()
        t["comp_fbo"] = c.framebuffer([t["comp"]])
        t["blur_fbo"] = [c.framebuffer([t["blur"]]), c.framebuffer([t["blur2"]])]
        t["out"] = c.texture((w, h), 4)
        t["out_fbo"] = c.framebuffer([t["out"]])
        sm = c.depth_texture((self.s.shadow_size,) * 2)
        sm.compare_func = "<="
        sm.filter = (0x2601, 0x2601)
        sm.repeat_x = sm.repeat_y = False
        t["shadow"], t["shadow_fbo"] = sm, c.framebuffer(depth_attachment=sm)
        self.targets = t
        return t

    def _release_targets(self):
        def rel(x):
            if isinstance(x, dict):
                for v in x.values():
                    rel(v)
            elif isinstance(x, list):
                for v in x:
                    rel(v)
            elif hasattr(x, "release"):
                x.release()
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
        s = self.s
        s.check()
        w, h = size
        T = self._targets(w, h)
        ms = T["ms"]
        c = self.ctx
        self.tex.use(_TEX_UNIT)  # block textures: units no other pass uses
        self.glow.use(_TEX_UNIT + 1)
        aniso = max(1.0, min(float(s.anisotropy), self.max_anisotropy))
        if aniso != self._aniso:
            self.tex.anisotropy = self._aniso = aniso
        camera.aspect = w / h
        camera.fov = s.fov
        camera.far = s.distance * 16 * 1.5 + 256.0  # the whole height of the area stays in view
        sp = sky.params(hours)
        stats = {"triangles": 0, "draw_calls": 0}
        debug = DEBUG_VIEWS.index(s.debug)
        vp = camera.view_proj()
        cull_vp = vp
        draw_cam = camera
        if s.debug == "culling":  # top-down view; regions still culled for the real camera
            draw_cam = _top_camera(camera, s.distance)
            vp = draw_cam.view_proj()
        inv_vp = np.linalg.inv(vp)

        # shadow map
        shadows = s.shadows and debug in (0, 4, 6) and sp["light_dir"][2] > 0.02
        shadow_mat, texel, bias = np.eye(4), 0.0, 0.0
        if shadows:
            light_vp, texel, bias = self._shadow_matrix(camera, sp["light_dir"])
            shadow_mat = _BIAS @ light_vp
            T["shadow_fbo"].use()
            T["shadow_fbo"].clear(depth=1.0)
            c.enable(c.DEPTH_TEST | c.CULL_FACE)
            mask = self.geo.cull(light_vp)
            for name in ("opaque", "cutout", "cutout2"):  # blend casts no shadow (§5.4.1)
                prog = self.progs.get("block.vert", "block.frag",
                                      {"SHADOW": 1, "ALPHA_TEST": name != "opaque"})
                self._block_uniforms(prog, light_vp)
                self.geo.draw(name, prog, mask, stats, "shadow")
            stats["shadow_triangles"] = stats["triangles"]

        # opaque G-buffer
        g = T["g"]
        g["fbo"].use()
        g["fbo"].clear(0, 0, 0, 0, depth=1.0)
        c.enable(c.DEPTH_TEST)
        defs = {"SAMPLES": ms, "SMOOTH_MAG": s.smooth_mag, "DEBUG_AGG": debug == 5}
        cut = {"ALPHA_TEST": 1, "MSAA_ALPHA": s.msaa_alpha}
        mask = self.geo.cull(cull_vp)
        for name, extra in (("opaque", {}), ("cutout", cut), ("cutout2", cut)):
            c.enable(c.CULL_FACE) if name != "cutout2" else c.disable(c.CULL_FACE)
            prog = self.progs.get("block.vert", "block.frag", {**defs, **extra})
            self._block_uniforms(prog, vp)
            self.geo.draw(name, prog, mask, stats)

        # transparent layers: depth peeling, no blending, nearest remaining layer each time
        blend = self.geo.parts.get("blend")
        seen = blend is not None and bool(mask[blend["rows"]].any())
        use_oit = seen and s.transparency == "oit"  # one forward pass instead (oit.py)
        layers = s.peel_layers if seen and not use_oit else 0
        c.disable(c.CULL_FACE)
        for i in range(layers):
            p = T["peel"][i]
            p["fbo"].use()
            p["fbo"].clear(0, 0, 0, 0, depth=1.0)
            prog = self.progs.get("block.vert", "block.frag", {**defs, "PEEL": i + 1})
            self._block_uniforms(prog, vp)
            g["depth"].use(2)
            _set(prog, opaque_depth=2)
            if i > 0:
                T["peel"][i - 1]["depth"].use(3)
                _set(prog, prev_depth=3)
            self.geo.draw("blend", prog, mask, stats)
        c.disable(c.DEPTH_TEST | c.CULL_FACE)

        # deferred light per layer; the fog is thick by the nearest edge of the shown area
        fog_end = (s.distance + 0.5) * 16.0
        common = dict(inv_vp=inv_vp, cam_pos=draw_cam.pos, day_ambient=sp["ambient"],
                      day_direct=sp["direct"], day_u=sp["u"], far_dist=camera.far,
                      fog_start=fog_end * 0.55, fog_end=fog_end,
                      shadow_mat=shadow_mat, shadow_fade=float(s.shadow_fade), shadow_eye=camera.pos,
                      shadow_texel=texel, shadow_bias=bias)
        common = {k: pack(v) if isinstance(v, np.ndarray) else v for k, v in common.items()}
        sp = {**sp, "sky": {f"sky_{k}": pack(sp[k]) for k in ("zenith", "horizon", "halo",
                                                               "disc", "light_dir")}}
        ddefs = {"SAMPLES": ms, "PER_SAMPLE": s.per_sample, "SHADOWS": shadows,
                 "FOG": s.fog and debug == 0, "DEBUG": debug if debug != 6 else 0}
        self._deferred(T["shaded_fbo"], g, {**ddefs, "FILL_HOLES": s.fill_holes}, common, sp, T)
        for i in range(layers):
            self._deferred(T["layer_fbo"][i], T["peel"][i], {**ddefs, "LAYER": 1}, common, sp, T)
        if use_oit:  # resolved into layer 0: the composite blends it as one peel layer
            oit.draw(self, T, T["layer_fbo"][0], mask, {**defs, **ddefs}, common, sp, stats,
                     vp, shadows)
            layers = 1

        # SSAO
        ssao = s.ssao and debug in (0, 6)
        if ssao:
            prog = self.progs.get("fullscreen.vert", "ssao.frag")
            T["ao_fbo"][0].use()
            T["front"].use(0)
            _set(prog, front=0, vp=vp, inv_vp=inv_vp, cam_pos=draw_cam.pos, radius=1.0,
                 far_dist=camera.far)
            self._fullscreen(prog)
            self._blur(T["ao"], T["ao_fbo"][1], T["ao2"], T["ao_fbo"][0], {})

        # composite: sky, layers, god rays
        sun_px, sun_vis, sun_r = _sun_on_screen(vp, draw_cam, sp["light_dir"], w, h, s.fov)
        gods = s.godrays and debug in (0, 6) and sun_vis
        prog = self.progs.get("fullscreen.vert", "composite.frag",
                              {"LAYERS": layers, "SSAO": ssao, "GODRAYS": gods})
        T["comp_fbo"].use()
        T["opaque"].use(0)
        T["front"].use(1)
        _set(prog, opaque=0, front=1)
        for i in range(layers):
            T["layers"][i].use(2 + i)
            _set(prog, **{f"layer{i}": 2 + i})
        if ssao:
            T["ao"].use(5)
            _set(prog, ao=5)
        self._sky_uniforms(prog, sp)
        _set(prog, inv_vp=inv_vp, cam_pos=draw_cam.pos, sun_px=sun_px, sun_radius=sun_r,
             sun_visible=sun_vis, godray_strength=float(s.godray_strength))
        if debug not in (0, 6):
            _set(prog, sky_zenith=np.zeros(3), sky_horizon=np.zeros(3), sky_halo=np.zeros(3),
                 sky_disc=np.zeros(3), sky_stars=0.0)
        self._fullscreen(prog)

        # distance blur, final
        dof = s.dof and debug == 0
        if dof:
            self._blur(T["comp"], T["blur_fbo"][0], T["blur"], T["blur_fbo"][1], {"BILATERAL": 1})
        prog = self.progs.get("fullscreen.vert", "final.frag", {"DOF": dof})
        T["out_fbo"].use()
        T["comp"].use(0)
        _set(prog, sharp=0)
        if dof:
            T["blur2"].use(1)
            _set(prog, blurred=1, dof_start=fog_end * 0.7, dof_end=fog_end * 1.1)
        self._fullscreen(prog)
        stats["cpu_ms"] = (time.perf_counter() - t0) * 1e3
        self.stats = stats
        return T["out_fbo"]

    # ------------------------------------------------------------------ helpers
    def _block_uniforms(self, prog, mvp):
        _set(prog, mvp=mvp, time=float(self.s.time), waving=self.s.waving)
        if prog.glo not in self._static:  # per-program constants, set once
            self._static.add(prog.glo)
            _set(prog, tex=_TEX_UNIT, glow_tex=_TEX_UNIT + 1)
            if prog.get("glow_scale", None) is not None:
                prog["glow_scale"].write(self.glow_scale.tobytes())

    def _sky_uniforms(self, prog, sp):
        _set(prog, sky_stars=sp["stars"], **sp["sky"])

    def _deferred(self, fbo, g, defs, common, sp, T):
        prog = self.progs.get("fullscreen.vert", "deferred.frag", defs)
        fbo.use()
        fbo.clear(0, 0, 0, 0)
        g["depth"].use(0)
        g["albedo"].use(1)
        g["normal"].use(2)
        _set(prog, g_depth=0, g_albedo=1, g_normal=2, **common)
        if defs.get("SHADOWS"):
            T["shadow"].use(3)
            _set(prog, shadow_map=3)
        self.vol.bind(prog, 4)
        self._sky_uniforms(prog, sp)
        self._fullscreen(prog)

    def _blur(self, src, tmp_fbo, tmp, dst_fbo, defs):
        """Separable blur: src -> tmp (horizontal) -> dst_fbo (vertical)."""
        prog = self.progs.get("fullscreen.vert", "blur.frag", defs)
        for fbo, tex, step in ((tmp_fbo, src, (1.0, 0.0)), (dst_fbo, tmp, (0.0, 1.0))):
            fbo.use()
            tex.use(0)
            _set(prog, src=0, step_px=step)
            self._fullscreen(prog)

    def _fullscreen(self, prog):
        vao = self._fs.get(prog.glo)
        if vao is None:  # attribute-less triangle: the vertex shader makes the corners
            vao = self._fs[prog.glo] = self.ctx.vertex_array(prog, [])
        vao.render(mode=self.ctx.TRIANGLES, vertices=3)

    def _shadow_matrix(self, camera: cam.Camera, light_dir):
        """Ortho light matrix fitted to the view frustum up to the shadow fade distance.

        Returns (matrix, world size of a shadow texel, depth bias in depth units)."""
        near_cam = cam.Camera(**{**camera.__dict__, "far": self.s.shadow_fade + 2.0})
        corners = cam.frustum_corners(np.linalg.inv(near_cam.view_proj()))
        d = np.asarray(light_dir, float)
        view = cam.look_at(corners.mean(0), -d)  # light space: +z points toward the light
        lc = corners @ view[:3, :3].T + view[:3, 3]
        lo, hi = lc.min(0), lc.max(0)
        # the near plane reaches back to the top of the shown area so off-screen casters
        # between the light and the view still cast; depth precision stays bounded
        top = hi[2]
        if self.area:
            if self._box[0] != self.area:
                cx0, cy0, cx1, cy1 = self.area
                self._box = (self.area, np.array([[x, y, z] for x in (16 * cx0, 16 * cx1)
                                                  for y in (16 * cy0, 16 * cy1)
                                                  for z in (0.0, 256.0)], float))
            box = self._box[1]
            top = max(top, float((box @ view[:3, :3].T + view[:3, 3])[:, 2].max()))
        near, far = -top - 1.0, -lo[2] + 1.0
        proj = cam.ortho(lo[0], hi[0], lo[1], hi[1], near, far)
        texel = max(hi[0] - lo[0], hi[1] - lo[1]) / self.s.shadow_size
        return proj @ view, texel, 0.05 / (far - near)  # 0.05 blocks of depth bias

    def release(self):
        for vao in self._fs.values():
            vao.release()
        self._fs.clear()
        self._release_targets()
        self.geo.release()
        if self.vol:
            self.vol.release()
        self.progs.release()
        self.tex.release()
        self.glow.release()


def _top_camera(camera: cam.Camera, distance: int) -> cam.Camera:
    top = cam.Camera(camera.x, camera.y, 250.0, camera.yaw, -89.9, camera.fov, camera.aspect,
                     1.0, 400.0)
    return top


def _sun_on_screen(vp, camera, light_dir, w, h, fov):
    p = vp[:, :3] @ (camera.pos + np.asarray(light_dir) * 1000.0) + vp[:, 3]
    vis = p[3] > 0
    ndc = p[:2] / p[3] if vis else np.zeros(2)
    px = ((ndc[0] * 0.5 + 0.5) * w, (ndc[1] * 0.5 + 0.5) * h)
    r = math.tan(0.05) / math.tan(math.radians(fov) / 2) * h / 2
    return px, bool(vis), float(r)
