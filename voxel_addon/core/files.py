"""Output files written whole: under a temporary name beside them, then renamed, so a
killed run leaves no half file under the real name (a file that is there is complete)
and a failure (a full disk, a read-only folder) is one line naming the output and
leaves no part of it."""
from __future__ import annotations

import shutil
from pathlib import Path

from .errors import VoxelError, cause


def write_whole(path, data, after: str = "") -> None:
    """Write DATA (bytes, or a Path to copy) to PATH whole; AFTER ends the error's line
    (what the failure left unchanged)."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.part")
    try:
        if isinstance(data, Path):
            shutil.copyfile(data, tmp)
        else:
            tmp.write_bytes(data)
        tmp.replace(path)
    except OSError as e:
        try:
            tmp.unlink(missing_ok=True)
        except OSError:  # a read-only folder: nothing was made either
            pass
        raise VoxelError(f"cannot write {path} ({cause(e, path) or e.strerror}){after}") from None
