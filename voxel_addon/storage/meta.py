"""A world file's meta values (storage/worldfile.py's mixin): the generator's settings,
values set at once or staged for the next save, and palettes two writers add to
(a staged value built on one the file no longer holds: MetaMoved, nothing written)."""
from __future__ import annotations

import json

from ..core.errors import VoxelError


class MetaMoved(VoxelError):
    """A staged meta value was built on a value another process has replaced since
    (a palette it added to): nothing of that save was written; `meta` holds the
    file's value now, build on it again."""


def while_moved(attempt, what: str, moved=None):
    """attempt() (a save of staged meta with its base) and its answer, made again
    while another writer keeps moving the values it was built on (MetaMoved; moved()
    first, when given): a one-line VoxelError naming WHAT after 16 tries."""
    for _ in range(16):
        try:
            return attempt()
        except MetaMoved:
            if moved is not None:
                moved()
    raise VoxelError(f"other programs kept changing the world's {what}; try again")


class Meta:
    """WorldFile's meta half; it needs `path`, `db`, `meta`, `_lock`, `_staged`,
    `_bases`, `transaction()` and `_writable()` of WorldFile."""

    # a hostile or damaged meta row is a one-line VoxelError here, never a
    # KeyError or ValueError further up (info, the generator, Blender's panel)
    @property
    def seed(self) -> int:
        raw = self.meta.get("seed")
        try:
            return int(raw)
        except (TypeError, ValueError):
            what = "no seed" if raw is None else f"seed {raw[:40]!r} is no whole number"
            raise VoxelError(f"{self.path}: its generator settings are damaged ({what})") from None

    @property
    def generator(self) -> str:
        raw = self.meta.get("generator")
        if not raw:
            raise VoxelError(f"{self.path}: its generator settings are damaged (no generator)")
        return raw

    @property
    def generator_version(self) -> int:
        """The version of its generator the world was made with; a file without one
        predates versions: 1, what it was made with."""
        raw = self.meta.get("generator_version")
        try:
            return 1 if raw in (None, "") else int(raw)
        except (TypeError, ValueError):
            raise VoxelError(f"{self.path}: its generator version {raw[:40]!r} is not a "
                             "number") from None

    @property
    def generator_params(self) -> dict:
        raw = self.meta.get("generator_params") or "{}"
        try:
            params = json.loads(raw)
        except ValueError as e:  # RecursionError too deep: a ValueError's sibling
            raise VoxelError(f"{self.path}: its generator settings are damaged "
                             f"(not JSON: {e})") from None
        except RecursionError:
            raise VoxelError(f"{self.path}: its generator settings are damaged "
                             "(nested too deep)") from None
        if not isinstance(params, dict):
            raise VoxelError(f"{self.path}: its generator settings are damaged "
                             f"(not a JSON object: {raw[:40]!r})")
        return params

    def set_meta(self, key: str, value: str) -> None:
        with self.transaction():
            self.db.execute("INSERT OR REPLACE INTO meta VALUES (?, ?)", (key, str(value)))
        self.meta[key] = str(value)

    def update_meta(self, key: str, fn) -> str:
        """Meta KEY set to fn(the value the file holds now, or None) in a transaction of
        its own, and returned: an addition to a palette made on what is there, not on
        what this session read when it opened (another process may have added since)."""
        with self.transaction() as db:
            row = db.execute("SELECT value FROM meta WHERE key=?", (key,)).fetchone()
            value = str(fn(None if row is None else row[0]))
            db.execute("INSERT OR REPLACE INTO meta VALUES (?, ?)", (key, value))
        with self._lock:
            self.meta[key] = value
            self._staged.pop(key, None)
            self._bases.pop(key, None)
        return value

    def reload_meta(self, keys) -> None:
        """`meta` of KEYS as the file holds them now (what is staged for them
        dropped): after MetaMoved, to build on all of a palette's keys again, not
        only on those that moved."""
        keys = list(keys)
        with self._lock:
            got = dict(self.db.execute("SELECT key, value FROM meta WHERE key IN (%s)"
                                       % ",".join("?" * len(keys)), keys))
            for k in keys:
                self._staged.pop(k, None)
                self._bases.pop(k, None)
                if k in got:
                    self.meta[k] = got[k]
                else:
                    self.meta.pop(k, None)

    def stage_meta(self, key: str, value: str, base=False) -> None:
        """Set a meta value now (in memory) and write it with the next `save`, in
        its transaction: a palette goes to the file with the voxels that use it.
        BASE (a value or None: the key absent): the value it was built on; when the
        file holds another by then (a second writer added to the palette), that save
        raises MetaMoved and writes nothing, so voxels never index a palette that is
        not the one they were made for."""
        self._writable()
        with self._lock:
            self.meta[key] = self._staged[key] = str(value)
            if base is not False:
                self._bases.setdefault(key, base)  # the first base: what the file held

    def _moved_meta(self) -> list[str]:
        """Inside save's transaction: the staged keys whose stored value is no longer
        the one they were built on; those are dropped from the stage and `meta` takes
        the stored value (the caller builds on it again)."""
        moved = {}
        for k, base in list(self._bases.items()):
            row = self.db.execute("SELECT value FROM meta WHERE key=?", (k,)).fetchone()
            now = None if row is None else row[0]
            if now != base:
                moved[k] = now
        with self._lock:
            for k, now in moved.items():
                self._staged.pop(k, None)
                self._bases.pop(k, None)
                if now is None:
                    self.meta.pop(k, None)
                else:
                    self.meta[k] = now
        return sorted(moved)
