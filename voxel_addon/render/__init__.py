"""The viewport pipeline. Use: Renderer(ctx, Settings()); .update_chunks(payloads) /
.remove_chunks(keys) (or .set_area(...) for a whole area); .render(camera, hours, size)."""
from .camera import Camera
from .settings import Settings

__all__ = ["Camera", "Settings"]
