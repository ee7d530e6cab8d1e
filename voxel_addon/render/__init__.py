"""The viewport pipeline. Use: Renderer(ctx, Settings()).set_area(...); .render(camera, hours, size)."""
from .camera import Camera
from .settings import Settings

__all__ = ["Camera", "Settings"]
