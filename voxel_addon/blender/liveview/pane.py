"""A window's share of the live view (view.py): a Renderer on the shared device, the
chunk and far-tile versions it uploaded, the kept frames of its regions. Each window
gets its own: framebuffers belong to one GL context, and a platform may give each
window its own."""
from __future__ import annotations

from . import composite

KEPT_MAX = 8         # kept frames per window (one per region; quad view has four)


class Pane:
    """What one window draws with: a Renderer on the shared device, which chunk
    versions it uploaded, the kept frames of its regions."""

    def __init__(self, dev):
        from ...render.pipeline import Renderer
        from ...render.settings import Settings
        self.dev = dev
        self.r = Renderer(dev, Settings())
        self.versions: dict = {}
        self.far_versions: dict = {}  # far tile key -> version uploaded
        self.feed = None
        self.kept: dict = {}     # region pointer -> composite.Kept
        self.gen = 0             # bumped whenever the uploaded chunks change
        self.fed = None          # (feed, feed.gen, palette) at the last sync

    def sync(self, feed) -> int:
        """Upload what changed in the feed; returns the number of chunks drawn."""
        r = self.r
        colors = getattr(feed.world, "colors", None)
        colors = colors() if colors is not None else None  # (cached by the world)
        fed = (feed, feed.gen, colors)
        last = self.fed
        if last is not None and last[0] is feed and last[1] == feed.gen and last[2] is colors:
            return len(self.versions)  # nothing new (a still view): no walk over every chunk
        self.fed = fed
        if self.feed is not feed:  # another world or distance: nothing of ours stays
            self.feed = feed
            self.versions = {k: None for k in self.versions}
            self.far_versions = {k: None for k in self.far_versions}
        if colors is not None:
            r.set_palette(colors)  # (compared there)
        gone = [k for k in self.versions if k not in feed.chunks]
        new = [p for k, p in feed.chunks.items() if self.versions.get(k) != p.version]
        if gone or new:
            self.gen += 1
        if gone:
            r.remove_chunks(gone)
            for k in gone:
                del self.versions[k]
        if new:
            r.update_chunks(new)
            for p in new:
                self.versions[p.key] = p.version
        gone = [k for k in self.far_versions if k not in feed.tiles]
        new = [m for k, m in feed.tiles.items() if self.far_versions.get(k) != m.version]
        if gone or new:
            self.gen += 1
            r.remove_far(gone)
            r.update_far(new)
            for k in gone:
                del self.far_versions[k]
            for m in new:
                self.far_versions[m.key] = m.version
        return len(self.versions)

    def kept_for(self, region, size) -> composite.Kept:
        """The kept targets of a region (made or resized; the least recently used go
        beyond KEPT_MAX: regions of closed areas)."""
        k = self.kept.pop(region, None)
        if k is not None and k.size != size:
            k.release(self.dev)
            k = None
        self.kept[region] = k = k or composite.Kept(self.dev, size)
        while len(self.kept) > KEPT_MAX:
            self.kept.pop(next(iter(self.kept))).release(self.dev)
        return k

    def release(self) -> None:
        for k in self.kept.values():
            k.release(self.dev)
        self.kept.clear()
        if self.r is not None:
            self.r.release()
            self.r = None
