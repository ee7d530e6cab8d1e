"""The SQLite world file (SPEC §3, F3): schema, codecs, edits, format checks. Depends only on core."""
from .opening import Exists  # noqa: F401
from .schema import FORMAT_VERSION  # noqa: F401
from .meta import MetaMoved  # noqa: F401
from .worldfile import CorruptChunk, WorldFile, check_path  # noqa: F401
