"""Far terrain to the horizon: levels of detail of the surface beyond the view distance, from stored chunks and the generator's 2D passes, kept in the world file, built in the background, meshed as heightfields (README.md). Depends on core, storage, textures."""
from .builder import Builder, signature  # noqa: F401
from .grid import DETAIL, FAR_MAX, LEVELS, TILE  # noqa: F401
