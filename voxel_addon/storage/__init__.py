"""The SQLite world file (SPEC §3, F3): schema, codecs, edits, format checks. Depends only on core."""
from .worldfile import FORMAT_VERSION, CorruptChunk, Exists, MetaMoved, WorldFile  # noqa: F401
