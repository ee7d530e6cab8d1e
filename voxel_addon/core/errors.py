"""User-facing errors: the CLI prints their message on one line and exits 2.

`cause(e)` is the one place that names a file system or SQLite refusal (disk full,
read-only, locked, gone) in a few words; `explain` turns one into a VoxelError that
says what failed and what was kept. The CLI's top level and Blender's operators use
them, so a full disk is one line there, never a traceback.
"""
from __future__ import annotations

import errno
import os


class VoxelError(Exception):
    """A mistake in what the user asked for (bad name, bad coordinate, bad file)."""


# SQLite primary result codes (sqlite3.h): what we can say about each
_SQLITE = {5: "the file is locked by another program", 6: "the file is locked by another program",
           8: "the file or its folder is read-only", 10: "disk I/O error",
           11: "the file is damaged (cut short or overwritten)",
           26: "the file is not a world file (or is damaged)",
           13: "disk full", 14: "cannot open the file or its journal (folder missing or "
           "not writable)", 23: "permission denied"}
_ERRNO = {errno.ENOSPC: "disk full", errno.EDQUOT: "disk quota exceeded",
          errno.EFBIG: "file-size limit reached", errno.EROFS: "the file system is read-only",
          errno.EACCES: "permission denied", errno.EPERM: "permission denied",
          errno.ENOENT: "no such file or folder", errno.EIO: "disk I/O error"}


def cause(e: BaseException, path=None) -> str | None:
    """A few words for a file refusal E (sqlite3.Error, OSError), else None. An
    SQLite I/O error is looked into: a full file system or a file-size limit say so."""
    import sqlite3
    if isinstance(e, sqlite3.Error):
        code = getattr(e, "sqlite_errorcode", None)
        what = None if code is None else _SQLITE.get(code & 0xFF)
        if what is None and "locked" in str(e):
            what = _SQLITE[5]
        if path is not None and code is not None and code & 0xFF in (8, 10, 14):
            what = (_why_io(path) if code & 0xFF == 10 else _why_not_writable(path)) or what
        return what
    if isinstance(e, OSError) and e.errno in _ERRNO:
        return _ERRNO[e.errno]
    return None


def damaged(e: BaseException) -> bool:
    """Whether E says the file itself is damaged (SQLITE_CORRUPT, SQLITE_NOTADB: cut
    short or overwritten), not refused for the moment (locked, disk full): trying
    again will not help."""
    import sqlite3
    return isinstance(e, sqlite3.DatabaseError) and \
        (getattr(e, "sqlite_errorcode", None) or 0) & 0xFF in (11, 26)


def _why_not_writable(path) -> str | None:
    """Which of file system, folder and file says no (SQLite only says read-only)."""
    import stat
    p = os.path.abspath(path)
    try:
        if os.statvfs(os.path.dirname(p)).f_flag & os.ST_RDONLY:
            return "the file system is read-only"
        if not stat.S_IMODE(os.stat(os.path.dirname(p)).st_mode) & 0o222:
            return "the folder is read-only (no journal can be made beside the file)"
        if os.path.exists(p) and not stat.S_IMODE(os.stat(p).st_mode) & 0o222:
            return "the file is read-only"
    except OSError:
        pass
    return None


def _why_io(path) -> str | None:
    """SQLite reports a write that failed on EFBIG (and some ENOSPC) only as an I/O
    error: look at the file system and the limit."""
    d = os.path.dirname(os.path.abspath(path)) or "."
    try:
        st = os.statvfs(d)
        if st.f_blocks and st.f_bavail * st.f_frsize < (64 << 10):
            return "disk full"
    except OSError:
        pass
    try:
        import resource
        soft = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
        if soft != resource.RLIM_INFINITY:
            return f"file-size limit reached ({soft} bytes)"
    except (ImportError, OSError, ValueError):
        pass
    return None


def explain(e: BaseException, path=None, doing: str = "writing", kept: str = "") -> VoxelError | None:
    """A VoxelError for E (one line: what failed while DOING PATH, then KEPT: what
    stayed), E itself when it is one, or None when E is not a file refusal."""
    if isinstance(e, VoxelError):
        return e
    what = cause(e, path)
    if what is None:
        return None
    where = f" {os.path.basename(os.fspath(path))}" if path is not None else ""
    return VoxelError(f"{what} while {doing}{where}{': ' + kept if kept else ''}")


def message(e: BaseException, path=None) -> str:
    """One line for any failure an operator reports (Blender): E explained, else
    its type and text."""
    got = explain(e, path)
    return str(got) if got is not None else f"{type(e).__name__}: {e}"
