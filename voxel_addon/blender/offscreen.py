"""The render pipeline on Blender's own GL context (issue 6, "or Blender's").

A `View` owns a gpu.types.GPUOffScreen and, created inside its first bind, a moderngl
context attached to Blender's GL context plus a Renderer on it; both live as long as
the View (their GL objects belong to that GL context). Every frame runs inside
`offscreen.bind()` and `glstate.kept()`: Blender caches what it believes is bound and
skips "redundant" binds, so the pipeline gets a fresh-context state and Blender gets
its exact state back.

Only the OpenGL backend works this way (moderngl speaks GL): Vulkan or Metal Blender
raises VoxelError.
"""
from __future__ import annotations

import time

import numpy as np

from ..core.errors import VoxelError
from ..render import glstate

_started = False


def gpu_ready() -> bool:
    import gpu
    try:
        gpu.platform.backend_type_get()
    except SystemError:  # background mode before any render: "not available"
        return False
    return True


def start_gpu() -> None:
    """Start Blender's GPU layer in background mode (bpy module, blender -b): gpu
    calls are refused until a render has run, so render a 1x1 Workbench image of a
    temporary scene, then remove everything it added. Once per process."""
    global _started
    if _started or gpu_ready():
        _started = True
        return
    import bpy
    d = bpy.data
    images = set(d.images.keys())
    cam_data = d.cameras.new(".voxel_gpu")
    cam = d.objects.new(".voxel_gpu", cam_data)
    sc = d.scenes.new(".voxel_gpu")
    try:
        sc.collection.objects.link(cam)
        sc.camera = cam
        sc.render.engine = "BLENDER_WORKBENCH"
        sc.render.resolution_x = sc.render.resolution_y = 1
        sc.render.resolution_percentage = 100
        bpy.ops.render.render(scene=sc.name)
    finally:
        d.scenes.remove(sc)
        d.objects.remove(cam)
        d.cameras.remove(cam_data)
        for name in set(d.images.keys()) - images:  # the Render Result it made
            d.images.remove(d.images[name])
    if not gpu_ready():
        raise VoxelError("Blender's GPU layer did not start (no OpenGL?)")
    _started = True


def check_backend() -> None:
    import gpu
    b = gpu.platform.backend_type_get()
    if b != "OPENGL":
        raise VoxelError(f"the voxel view needs Blender's OpenGL backend, not {b} "
                         "(Preferences > System > GPU Backend)")


_current = None  # the platform's "current context" functions, found once


def _native():
    """The current native GL context handle (one View stays on one context)."""
    global _current
    if _current is None:  # find_library runs ldconfig: once, not on every redraw
        import ctypes
        import ctypes.util
        import sys
        names = {"win32": ("opengl32", "wglGetCurrentContext"),
                 "darwin": ("/System/Library/Frameworks/OpenGL.framework/OpenGL", "CGLGetCurrentContext")}
        _current = []
        for lib, fn in ([names[sys.platform]] if sys.platform in names else
                        [(ctypes.util.find_library("EGL"), "eglGetCurrentContext"),
                         (ctypes.util.find_library("GL"), "glXGetCurrentContext")]):
            try:
                f = getattr(ctypes.CDLL(lib), fn)
            except (OSError, AttributeError, TypeError):
                continue
            f.restype = ctypes.c_void_p
            _current.append(f)
    for f in _current:
        h = f()
        if h:
            return h
    return None


class View:
    """Renders the pipeline into a GPUOffScreen on Blender's GL context."""

    def __init__(self, settings=None):
        from ..render import Settings
        start_gpu()
        check_backend()
        self.settings = settings or Settings()
        self.off = None
        self.ctx = None
        self.r = None
        self.native = None
        self.info: dict = {}
        self._area = None       # (Area, method) to upload at the next frame
        self._dst = None        # moderngl view of the offscreen's framebuffer
        self.ms = 0.0           # wall time of the last frame (pipeline + copy + state)

    # ------------------------------------------------------------------ data
    def set_area(self, area, method: str = "greedy") -> None:
        """What to show: a render.source.Area (uploaded inside the next frame's bind)."""
        self._area = (area, method)

    # ------------------------------------------------------------------ frame
    def draw(self, camera, hours: float, size) -> "gpu.types.GPUOffScreen":
        """Render a frame; the final image lands in the offscreen's colour texture
        (`.texture_color`, for gpu_extras.presets.draw_texture_2d)."""
        self._frame(camera, hours, size, None)
        return self.off

    def render(self, camera, hours: float, size) -> np.ndarray:
        """Render a frame to an (h, w, 3) uint8 image, row 0 = top (Renderer.render)."""
        out = []
        self._frame(camera, hours, size, out)
        return out[0]

    def _frame(self, camera, hours, size, out):
        import gpu
        t0 = time.perf_counter()
        w, h = int(size[0]), int(size[1])
        if self.off is None or (self.off.width, self.off.height) != (w, h):
            self._free_offscreen()
            self.off = gpu.types.GPUOffScreen(w, h, format="RGBA8")
        with self.off.bind(), glstate.kept() as host:
            self._attach()
            if self._area is not None:
                a, method = self._area
                self.r.set_area(a.blocks, a.light, a.cx0, a.cy0, ring=True, method=method,
                                light_at=a.light_at)
                self._area = None
            tex = self.r.draw(camera, hours, (w, h))
            dst = host["fb"][0]  # the offscreen's framebuffer, bound by off.bind()
            if self._dst is None or self._dst.glo != dst:
                self._dst = self.ctx.detect_framebuffer(dst)
            self.ctx.copy_framebuffer(self._dst, self.r.targets.out_fb.obj)
            if out is not None:
                out.append(np.ascontiguousarray(self.r.dev.read(tex)[::-1, :, :3]))
        self.ms = (time.perf_counter() - t0) * 1e3

    def _attach(self):
        """The moderngl context on Blender's, created at the first bind and kept."""
        native = _native()
        if self.ctx is not None and native != self.native:
            # VAOs and framebuffers are not shared between GL contexts (a second
            # Blender window): this View's objects cannot be used here
            raise VoxelError("the voxel view was created in another OpenGL context")
        if self.ctx is not None:
            return
        import moderngl
        from _moderngl import DefaultLoader
        from ..render.pipeline import Renderer
        # create_context() without a loader takes its "detect" path through GLX when
        # any standalone context exists in the process; Blender's may be EGL
        self.ctx = moderngl.create_context(context=DefaultLoader())
        self.native = native
        self.r = Renderer(self.ctx, self.settings)
        c = self.ctx
        self.info = {"version": c.info["GL_VERSION"], "renderer": c.info["GL_RENDERER"],
                     "version_code": c.version_code, "max_samples": c.max_samples}

    # ------------------------------------------------------------------ cleanup
    def _free_offscreen(self):
        if self.off is not None:
            self.off.free()
            self.off = None
        self._dst = None

    def release(self) -> None:
        """Free the GL objects (on the View's GL context, as created)."""
        if self.r is not None:
            with self.off.bind(), glstate.kept():
                self.r.release()  # (not _dst: releasing a reference deletes Blender's FBO)
            self.r = None
        self._free_offscreen()
        self.ctx = None  # a context attached to Blender's is not ours to destroy


def image_pixels(img: np.ndarray) -> np.ndarray:
    """(h, w, 3) uint8, row 0 = top -> the flat float RGBA Blender's Image.pixels
    takes (row 0 = bottom)."""
    h, w = img.shape[:2]
    rgba = np.ones((h, w, 4), np.float32)
    rgba[..., :3] = img[::-1] / np.float32(255.0)
    return rgba.ravel()


def draw_callback(view: View, camera, hours: float, region) -> None:
    """A SpaceView3D POST_PIXEL draw handler body: render and show the frame.

    Not registered anywhere yet (the viewport handler is its own issue); the view
    camera would come from region_data.view_matrix, not a scene camera.
    """
    from gpu_extras.presets import draw_texture_2d
    off = view.draw(camera, hours, (region.width, region.height))
    draw_texture_2d(off.texture_color, (0, 0), region.width, region.height)
