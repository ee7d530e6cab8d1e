"""The frame: shadow map -> G-buffer -> depth-peeled layers -> deferred light -> sky,
SSAO, god rays -> distance blur (thesis fig. 5.15), on a device (render/device): a
moderngl context (the CLI, tests: `Renderer(ctx)` wraps it) or Blender's gpu module.
The chunks it shows come and go one at a time (`update_chunks`, `remove_chunks`).
"""
from __future__ import annotations

import math
import time
from typing import NamedTuple

import numpy as np

from ..core import chunk
from ..core.blocks import REGISTRY
from . import camera as cam
from . import far as far_mod
from . import graph, shadow, sky, targets, walls
from .blocktex import BlockTextures
from .far import FarRing, near_edge
from .device import Device
from .frame import FrameBlock
from .geometry import PASSES, Geometry, Stats
from .models import NAMES as MODEL_PASSES, Models, edges as model_edges
from .lightvol import LightVolume
from .settings import Settings
from .targets import Shape, Targets
from .walls import Walls


_EYE = np.eye(4)
_EYE.flags.writeable = False
_NO_SKY = np.full((sky.NE * sky.NA, 4), math.log(sky.EPS))  # the sky tables of a debug view
_NO_SKY.flags.writeable = False  # (one object: the frame block packs it once)


class Renderer:
    def __init__(self, dev, settings: Settings | None = None):
        """dev: a render.device.Device, or a moderngl context (wrapped, and closed
        with the renderer)."""
        self._own = not isinstance(dev, Device)
        if self._own:
            from .device.mgl import MglDevice
            dev = MglDevice(dev)
        self.dev = dev
        self.s = settings or Settings()
        self.geo = Geometry(dev)
        self.vol = LightVolume(dev, 1)  # nothing resident yet: open daylight everywhere
        self.blocks = BlockTextures(dev)
        self.models = Models(dev)    # Minecraft model quads with the stack's sprites
        self.walls = Walls(dev)
        self.edges: dict = {}        # (cx, cy) -> its border columns' heights (walls.edges)
        self._walls_dirty = True
        self.frame = FrameBlock()
        self.targets: Targets | None = None
        self.stats: dict = {}
        self.area = None             # (cx0, cy0, cx1, cy1): the box of the shown chunks
        self.edge_water = None       # set_area: the fraction of the area's edge that is
                                     # open water (source.open_sea)
        self.lights: dict = {}       # (cx, cy) -> its light (None: open daylight; or packed)
        self._vol_key = None         # the light window last made resident
        self._graphs: dict = {}      # Switches -> Graph, for these targets and volume
        self.far = FarRing(dev)      # far terrain tiles (render/far.py), drawn when s.far > 0
        self._near_dirty = True

    @property
    def software(self) -> bool:
        return self.dev.software

    # ------------------------------------------------------------------ data
    def update_chunks(self, payloads) -> None:
        """Show or replace chunks, each an object with .key (cx, cy), .mesh (a
        meshing.ChunkMesh built with the chunk's one-voxel ring of neighbours) and
        .light (its (16, 16, 256) uint16 packed light, None: open daylight, or
        core.chunk.pack_layers of it: kept so, a third of the memory). Only these are
        uploaded: their batches are built again, their light goes into the volume once
        the light window (around the camera, prepare) needs it."""
        meshes, models = {}, {}
        for p in payloads:
            k = (int(p.key[0]), int(p.key[1]))
            light = p.light
            shape = light[0] if isinstance(light, tuple) else np.shape(light)
            if light is not None and tuple(shape) != (16, 16, 256):
                raise ValueError(f"chunk {k}: light must be (16, 16, 256), got {shape}")
            meshes[k] = p.mesh
            models[k] = getattr(p.mesh, "models", None)   # (world/models.py)
            self.lights[k] = light
            self.vol.forget(k)
        self.geo.update(meshes)
        self.models.update(models)
        self._edges(meshes)
        self._shown()

    def remove_chunks(self, keys) -> None:
        """Stop showing these chunks (unknown keys are ignored); nothing else moves."""
        keys = [(int(k[0]), int(k[1])) for k in keys]
        self.geo.remove(keys)
        self.models.remove(keys)
        for k in keys:
            self.lights.pop(k, None)
            self.edges.pop(k, None)
            self.vol.forget(k)
        self._shown()

    def set_area(self, blocks: np.ndarray, light: np.ndarray, cx0: int, cy0: int,
                 ring: bool = False, method: str = "greedy", backend: str | None = None,
                 light_at: tuple[int, int] | None = None, data: np.ndarray | None = None,
                 closed: bool = True):
        """Show the chunks [cx0, cx0+w) x [cy0, cy0+h) from a block array and their light
        instead of what was shown.

        blocks is (16w, 16h, 256), or with ring=True (16w+2, 16h+2, 256) including a
        one-voxel ring of neighbours (else outside counts as air); light is the packed
        light of whole chunks from light_at (default (cx0, cy0)), e.g. (16w, 16h, 256);
        chunks it does not cover get open daylight. data: the blocks' small data (the
        same shape, or None): `color` blocks of different colours stay apart. closed:
        the ring counts as air all the same, so the area's outer wall has faces (seen
        from outside, or from a side view, the area is a closed block, not a slab open
        into its caves), and caves that reach the wall end in stone (_close); ring=True
        then only matters for closed=False.
        """
        from .. import meshing
        if ring:
            self.edge_water = _edge_water(blocks)
        if ring and closed:
            closed_blocks = _close(blocks)
            if data is not None:  # (the ring and the filled caves carry no data)
                data = np.where(closed_blocks == blocks, data, 0).astype(data.dtype, order="F")
            blocks = closed_blocks
        elif not ring:
            pad = np.zeros((blocks.shape[0] + 2, blocks.shape[1] + 2, 256), np.uint16, order="F")
            pad[1:-1, 1:-1] = blocks
            blocks = pad
            if data is not None:
                d = np.zeros_like(pad)
                d[1:-1, 1:-1] = data
                data = d
        # one batched call for the whole area (meshing README: build_chunks); backend
        # None: the OpenCL twin when there is a device (same meshes, much faster)
        meshes = meshing.build_chunks(blocks, (cx0, cy0), method=method, backend=backend,
                                      data=data)
        lights = chunk.cut(light, *(light_at or (cx0, cy0)))
        self.remove_chunks([k for k in self.geo.keys if k not in meshes])
        self.update_chunks(_Chunk(k, m, lights.get(k)) for k, m in meshes.items())

    def set_palette(self, rgb) -> None:
        """The world's colour palette ((n, 3) uint8, core.colors): the `color` block's
        tint, indexed by the meshes' per-vertex colour (meshing.ChunkMesh.colors)."""
        if self.blocks.set_palette(rgb):
            self._graphs.clear()

    def set_models(self, models: dict) -> None:
        """Minecraft model quads to draw instead of those shown: {(cx, cy): .mesh
        (mcres.mesh.Mesh by duck typing, world voxels), .images ({sprite id: RGBA, top
        row first})}, as world/models.py makes them; after set_area (whose meshes
        carry none). The greedy meshes should leave the voxels they draw out."""
        self.models.remove(list(self.models.chunks))
        self.models.update(models)
        for k, cm in models.items():   # (their tops stand on the area's wall too)
            k = (int(k[0]), int(k[1]))
            if k in self.edges:
                self.edges[k] = walls.raise_to(self.edges[k], model_edges(cm, k))
        self._walls_dirty = True

    def set_meshes(self, meshes: dict) -> None:
        """{(cx, cy): meshing.ChunkMesh} to draw instead of what was shown; the light
        known for chunks that stay is kept (set_light)."""
        self.remove_chunks([k for k in self.geo.keys if k not in meshes])
        self.geo.update(meshes)
        self.models.update({k: getattr(m, "models", None) for k, m in meshes.items()})
        self._edges(meshes)
        self._shown()

    def set_light(self, light: np.ndarray, cx0: int, cy0: int) -> None:
        """Packed light of whole chunks from (cx0, cy0), e.g. (16w, 16h, 256); the
        volume takes the part inside the light window (outside it surfaces get open
        daylight, the fog hides them)."""
        for k, v in chunk.cut(light, cx0, cy0).items():
            self.lights[k] = v
            self.vol.forget(k)
        self._vol_key = None

    def update_far(self, meshes) -> None:
        """Show or replace far tiles (voxel_addon/far/mesh.py FarMeshes, by duck
        typing); drawn out to Settings.far chunks where no chunk is."""
        self.far.update(meshes)

    def remove_far(self, keys) -> None:
        self.far.remove(keys)

    def _shown(self) -> None:
        """The shown chunks changed: their box (self.area), the light window and the
        outer wall again."""
        self.area = self.geo.bounds()
        self._vol_key = None
        self._near_dirty = True
        self._walls_dirty = True

    def _edges(self, meshes: dict) -> None:
        for (k, m), e in zip(meshes.items(), walls.edges_many(list(meshes.values()))):
            k = (int(k[0]), int(k[1]))
            cm = getattr(m, "models", None)
            self.edges[k] = e if cm is None else walls.raise_to(e, model_edges(cm, k))

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
            self.vol = LightVolume(self.dev, min(2 * r + 1, max(n, 2 * self.vol.n)))
            self._graphs.clear()
        for x in range(win[0], win[2]):
            for y in range(win[1], win[3]):
                if not self.vol.resident((x, y)):
                    self.vol.upload((x, y), self.lights.get((x, y)))
        self.vol.set_window(*win)
        self._vol_key = key

    def _targets(self, w, h, need) -> Targets:
        """The frame's targets at (w, h), with those of the effects in need."""
        shape = Shape((w, h), self._samples(), self.s.shadow_size, self.s.transparency == "oit")
        if self.targets is None or self.targets.shape != shape:
            self._release_targets()
            self.targets = Targets(self.dev, shape)
        self.targets.need(*need)
        return self.targets

    def _samples(self) -> int:
        """The frame's MSAA samples (the settings' within what the device has)."""
        return max(1, min(self.s.msaa, self.dev.max_samples))

    def _release_targets(self):
        self._graphs.clear()
        if self.targets is not None:
            self.targets.release()
            self.targets = None

    # ------------------------------------------------------------------ frame
    def render(self, camera: cam.Camera, hours: float, size) -> np.ndarray:
        """Render to an (h, w, 3) uint8 image (row 0 = top)."""
        out = self.draw(camera, hours, size)
        return np.ascontiguousarray(self.dev.read(out)[::-1, :, :3])

    def draw(self, camera: cam.Camera, hours: float, size):
        """Run the frame; returns the texture holding the final RGBA8 image."""
        t0 = time.perf_counter()
        f = self.prepare(camera, hours, size)
        self.submit(f)
        f.stats["cpu_ms"] = (time.perf_counter() - t0) * 1e3
        self.stats = f.stats
        return f.color

    def prepare(self, camera: cam.Camera, hours: float, size) -> "Frame":
        """A frame's work that is not drawing, all before the first draw (the heavy
        draws leave the calling thread's caches cold on software GL, where Python
        between them ran 2-3x slower): changed batches built, culling and the draw
        lists of every pass, the frame's values into the one uniform block, the
        graph of passes for the switches and targets."""
        s = self.s
        s.check()
        w, h = size
        # the whole height of the area stays in view; the caller's camera is left alone
        camera = camera.fitted(w / h, s.fov, s.distance * 16 * 1.5 + 256.0)
        self._sync_light(camera)  # before the graph: it may make a bigger volume
        if self._walls_dirty:  # (likewise a bigger texture)
            if self.walls.write(self.area, self.edges):
                self._graphs.clear()
            self._walls_dirty = False
        geo = self.geo
        geo.commit()
        if self.models.commit():  # new sprites: a new texture, bound by new passes
            self._graphs.clear()
        # (the sky in steps of 15 s of the day: a dragged slider reuses the cached table)
        sp = sky.params(round(hours * 240.0) / 240.0, s.exposure)
        vp, inv_vp = cull_vp, _ = camera.matrices()
        draw_cam = camera
        if s.debug == "culling":  # from above; regions still culled for the real camera
            draw_cam = _top_camera(camera)
            vp, inv_vp = draw_cam.matrices()
        shaded = s.debug in graph.SHADED
        shadows = bool(s.shadows and (shaded or s.debug == "light") and sp["light_dir"][2] > 0.02)
        vis = geo.cull(cull_vp, keep=True)
        view = dict(geo.batches(vis, PASSES, eye=(camera.x, camera.y, camera.z),  # (a copy)
                                reach={"cutout2": s.plants_reach} if s.plants_reach else None))
        models = bool(self.models.chunks)
        if models:
            view.update(self.models.batches(MODEL_PASSES, cull_vp))
        seen = view.get("blend") is not None or view.get("m_blend") is not None
        use_oit = seen and s.transparency == "oit"  # one forward pass instead (oit.py)
        layers = s.peel_layers if seen and not use_oit else 0
        ssao = s.ssao and shaded
        sun_px, sun_vis, sun_r = _sun_on_screen(vp, draw_cam, sp["light_dir"], w, h, s.fov)
        gods = s.godrays and shaded and sun_vis
        dof = s.dof and s.debug == "none" and not camera.ortho  # parallel rays: no blur
        F = self.frame
        fog_end = (s.distance + 0.5) * 16.0  # thick by the nearest edge of the shown area
        far = None
        if s.far > 0 and self.far.tiles and not draw_cam.ortho and s.debug != "culling":
            if self._near_dirty:
                self.far.set_near(self.geo.keys)
                self._near_dirty = False
            fog_end = s.far * 16.0  # the far ring's edge (it ends in the sky there)
            vp, inv_vp, fvp, far_inv, far_clip = self.far.view(
                camera, vp, near_edge(camera, self.area), fog_end)
            far = (self.far.visible(fvp, (camera.x, camera.y), fog_end), fvp)
            F.set(far_inv_vp=far_inv, far_split=far_mod.SPLIT)
        else:
            F.set(far_inv_vp=_EYE, far_split=0.0)
        light_vp = None
        if shadows:
            light_vp, texel, bias = shadow.fit(camera, sp["light_dir"], self.area,
                                               s.shadow_fade, s.shadow_size)
            F.set(shadow_vp=light_vp, shadow_mat=shadow.BIAS @ light_vp, shadow_texel=texel,
                  shadow_bias=bias)
        for k in ("zenith", "horizon", "halo", "disc"):  # debug views: black where no surface
            F.set(**{f"sky_{k}": sp[k] if shaded else (0.0, 0.0, 0.0)})
        F.set(**sky_values(s, sp, hours, shaded, camera, self.area, h,
                           fog_end if far is not None else 0.0))
        F.set(vp=vp, inv_vp=inv_vp, cam_pos=(draw_cam.x, draw_cam.y, draw_cam.z),
              cam_fwd=draw_cam.fwd(), ortho=draw_cam.ortho,
              far_dist=camera.far if far is None else far_clip, shadow_eye=(camera.x, camera.y, camera.z),
              # orthographic: no eye to fade from; the map covers the view box
              shadow_fade=1e9 if camera.ortho else s.shadow_fade,
              day_ambient=sp["ambient"], day_u=sp["u"],
              day_direct=sp["direct"], sky_stars=sp["stars"] if shaded and s.stars else 0.0,
              sky_light_dir=sp["light_dir"], time=s.time, waving=s.waving,
              godray_strength=s.godray_strength * sky.godray_scale(sp), sun_px=sun_px,
              sun_radius=sun_r,
              sun_visible=sun_vis, fog_start=fog_end * 0.55, fog_end=fog_end,
              dof_start=fog_end * 0.8, dof_end=fog_end * 1.15, ssao_radius=s.ssao_radius,
              # (far terrain continues the ground beyond the area: no wall there)
              walls=s.walls and self.area is not None and far is None, wall_layer=self.walls.stone_layer(),
              **self.vol.frame_values())
        F.set(starry=F.values["sky_stars"] > 0.0, far_water=F.values["water_fx"] and far is not None)
        # the frame's switches are the programs' constants (graph.FIXED): on llvmpipe and
        # lavapipe a shader runs every branch for every pixel, so an effect switched off
        # at run time still cost its whole price (bench/README.md: issue 29)
        b = F.values["area_box"]  # (graph.Switches.sky: from inside, the sky only where no surface)
        # (SSAO darkens the opaque layer's colour, which then holds the sky in the fade band;
        # a draft frame, the live view's first frames after Show, compiles one lighting
        # program fewer without it: ~0.4 s sooner on screen from a fresh install)
        split = (targets.COVERED and s.debug == "none" and not draw_cam.ortho and not ssao
                 and not s.far_draft and self._samples() == 1
                 and b[0] <= draw_cam.x < b[2] and b[1] <= draw_cam.y < b[3])
        T = self._targets(w, h, (layers, ssao, dof, shadows, split))
        sw = graph.Switches(T.samples, s.debug, shadows, layers, ssao, gods, dof, s.smooth_mag,
                            s.msaa_alpha, s.per_sample, s.fog, s.fill_holes, use_oit, models,
                            graph.fixed(F.values), split)
        G = self._graphs.get(sw)
        if G is None:
            G = self._graphs[sw] = graph.build(self.dev, T, sw, self.blocks, self.vol.tex,
                                               self.walls.tex, self.models.tex)
        cast = None
        if shadows:
            cast = geo.batches(geo.cull(light_vp, keep=True), [n for n in G.shadow.names if n in PASSES],
                               "shadow")
            if models:
                cast = {**cast, **self.models.batches(G.shadow.names, light_vp)}
        self.dev.frame(F.pack())
        fr = Frame(T, G, view, cast, layers, use_oit)
        fr.far = far
        return fr

    def submit(self, f: "Frame", final: bool = True) -> None:
        """Run the passes of a prepared frame; without the final pass when its host
        folds that in (`Frame.final`: the Blender viewport's composite), so `color`
        stays unwritten."""
        G, stats = f.G, f.stats
        if f.cast is not None:  # shadows on: cleared even with no caster in view
            G.shadow.draw(f.cast, stats, shadow=True)  # blend casts none (§5.4.1)
        G.g.draw(f.view, stats)
        if f.far is not None:  # after the chunks: far pixels behind them fail the depth test
            self.far.draw(f.targets.g.target, f.far[0], f.far[1], stats, self.s.far_draft,
                          f.targets.samples)
        G.transparency.geometry(f.view, stats)
        G.shade.run()
        G.transparency.shade(f.view, stats)
        for p in G.post if final else G.post[:-1]:  # SSAO, composite, distance blur, final
            p.run()

    def release(self):
        self._release_targets()
        self.geo.release()
        self.models.clear()
        self.vol.release()
        self.walls.release()
        self.blocks.release()
        self.far.release()
        if self._own:
            self.dev.close()


class Frame:
    """What prepare() made for submit(): targets, passes, draw lists, switches. A host
    that composites the frame itself (the Blender viewport) reads `color` (the final
    RGBA8 texture), `depth` (the opaque G-buffer depth, `targets.samples` samples)
    and `blend_depth` (the nearest transparent surface's depth when peeling drew one,
    else None; OIT writes no depth)."""
    __slots__ = ("targets", "G", "view", "cast", "stats", "layers", "use_oit", "far")

    def __init__(self, T, G, view, cast, layers, use_oit):
        self.targets, self.G, self.view, self.cast = T, G, view, cast
        self.layers, self.use_oit = layers, use_oit
        self.stats = Stats()
        self.far = None  # (far tiles in view, the far projection) or None

    @property
    def color(self):
        return self.targets.out

    @property
    def final(self):
        """The final pass (shaders/final.frag): its input textures are `.tex`."""
        return self.G.post[-1]

    @property
    def depth(self):
        return self.targets.g.depth

    @property
    def blend_depth(self):
        return self.targets.peel[0].depth if self.layers else None


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


def sky_values(s: Settings, sp: dict, hours: float, sky_on: bool, camera, area,
               h: int, far: float = 0.0) -> dict:
    """The frame block's sky, haze, clouds, sea, fade and display values (issue 20).
    The sea beyond the area shows where the world has one (Settings.sea_level; the CLI
    also asks source.open_sea whether the shown area's edge is at sea). far: the far
    ring's reach in blocks when it is drawn: the fade moves out to it, the sea starts
    beyond it (far terrain has its own water)."""
    zero = _NO_SKY
    fade_end = s.fade_distance or far or (s.distance + 0.5) * 16.0
    fade = s.fade and not camera.ortho
    box = [16.0 * v for v in area] if area else [0.0, 0.0, 0.0, 0.0]
    if far:
        box = [camera.x - far, camera.y - far, camera.x + far, camera.y + far]
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
        # (an orthographic view has no eye: nothing is far from it, no horizon to fade to)
        fade_start=fade_end * (1.0 - s.fade_width) if fade else 1e9,
        fade_end=fade_end if fade else 2e9,
        # (the albedo views show the G-buffer's encoded colours as they are)
        display=(2 if s.tonemap else 1) if sky_on else (1 if s.debug == "light" else 0),
        clouds=s.clouds and sky_on, cloud_shadows=s.cloud_shadows,
        sea=s.sea and sky_on and s.sea_level >= 0, sea_from=max(s.sea_from, far),
        water_fx=s.water and sky_on, ssr=s.water and s.ssr and sky_on)


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
