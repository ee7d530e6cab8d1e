"""The one place that answers "can we draw here, and with what": whether Blender's GPU
layer runs (background mode starts it with a 1x1 Workbench render), the device to
draw with (blender/liveview/device.py, on any backend), and Blender's GPU state kept
around our frames."""
from __future__ import annotations

from contextlib import contextmanager

from ...core.errors import VoxelError

_started = False
_device = None
_drawable = False  # the backend was found drawable: a process keeps its GPU backend


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
        raise VoxelError("Blender's GPU layer did not start")
    _started = True


def backend() -> str:
    """Blender's GPU backend: "OPENGL", "VULKAN", "METAL" (or "NONE")."""
    import gpu
    return gpu.platform.backend_type_get()


def problem() -> str | None:
    """Why the live view cannot draw here, as one sentence, or None (asked on every
    redraw: once it was None it stays None)."""
    global _drawable
    if _drawable:
        return None
    if not gpu_ready():
        return "the viewport needs Blender's window (no GPU in background mode)"
    if backend() not in ("OPENGL", "VULKAN", "METAL"):
        return f"the voxel view cannot draw on the {backend()} backend"
    _drawable = True
    return None


def device():
    """The device every frame in this Blender draws with (GPU objects belong to
    Blender's GPU module, which keeps them valid in every window's context)."""
    global _device
    if _device is None:
        from .device import GpuDevice
        start_gpu()
        _device = GpuDevice()
    return _device


def forget_device() -> None:
    """Drop the device's programs and buffers (unregister, a new file)."""
    global _device
    if _device is not None:
        _device.close()
        _device = None


STATE = ("blend", "depth_test", "depth_mask", "line_width", "viewport", "scissor")


def state() -> dict:
    """Blender's GPU state that our passes change, as the gpu module reports it."""
    import gpu
    s = gpu.state
    return {"blend": s.blend_get(), "depth_test": s.depth_test_get(),
            "depth_mask": s.depth_mask_get(), "line_width": s.line_width_get(),
            "viewport": tuple(s.viewport_get()), "scissor": tuple(s.scissor_get())}


@contextmanager
def kept():
    """Our frames change blend, depth and culling state through Blender's own state
    tracker; afterwards Blender gets the values it had (face culling: its default,
    off, which the module cannot report)."""
    import gpu
    before = state()
    try:
        yield before
    finally:
        s = gpu.state
        s.blend_set(before["blend"])
        s.depth_test_set(before["depth_test"])
        s.depth_mask_set(before["depth_mask"])
        s.face_culling_set("NONE")
        s.line_width_set(before["line_width"])
        s.viewport_set(*before["viewport"])
        s.scissor_set(*before["scissor"])
