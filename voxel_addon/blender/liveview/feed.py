"""The chunks of the shown world, shared by every window: payloads from a world.Stream
(nearest first, made in its background thread), and the far tiles beyond them from
a far.Builder (its own thread, nearest first) when the view's `far` is on."""
from __future__ import annotations

import math

# far tiles made that are worth a redraw while the near stream has nothing new (a
# frame holds the GIL ~0.3 s on llvmpipe: the ring of far 128, 208 tiles, in ~4)
FAR_NEWS = 48


class Feed:
    def __init__(self, path, world, distance):
        from ...world import Stream
        from ...world.build import warm
        self.path, self.world, self.distance = path, world, distance
        self.chunks: dict = {}   # key -> Payload (.key, .mesh, .light, .version)
        # a fresh install's first OpenCL builds take 10-20 s (2 cores): the first
        # chunks come from NumPy meanwhile, OpenCL takes over once built (issue 28)
        warm(world)
        self.stream = Stream(world, distance)
        self.wanted = 0          # chunks the stream means to show
        self.far = 0             # far distance (chunks; 0: no far ring)
        self.tiles: dict = {}    # far tile key -> far.mesh.FarMesh (.version)
        self.gen = 0             # bumped whenever chunks or tiles change (Pane.sync)
        self.far_wanted = 0      # tiles the far builder means to show
        self._far = None         # the far.Builder
        self._far_at = None      # the view chunk it was last given
        self._at = None
        self.far_loading = False

    def set_far(self, far: int) -> None:
        """The far ring out to `far` chunks (0: none): a builder is made or let go."""
        far = int(far)
        if far == self.far:
            return
        self.far, self._far_at = far, None
        if far and self._far is None:
            from ...far import Builder
            # the world's loader generates with the same generator: one at a time
            self._far = Builder.of(self.world)
        elif not far and self._far is not None:
            self._far.close()
            self._far = None
            self.tiles.clear()
            self.far_wanted = 0
            self.gen += 1

    def _update_far(self, budget) -> bool:
        b = self._far
        if b is None:
            return False
        if self._at is not None:
            c = (math.floor(self._at[0]) >> 4, math.floor(self._at[1]) >> 4)
            if c != self._far_at:  # the ring is chosen per view chunk
                self._far_at = c
                b.set_view(self._at[0], self._at[1], self.far, self.distance)
        ready, gone = b.drain(budget)
        for m in ready:
            self.tiles[m.key] = m
        for k in gone:
            self.tiles.pop(k, None)
        if ready or gone:
            self.gen += 1
        if b.error is not None:
            raise b.error
        self.far_wanted, done = b.counts
        return done < self.far_wanted or bool(ready)

    def far_made(self) -> bool:
        """Whether the far builder has made every tile the view wants (it needs no
        more CPU: what it queued may be drawn at once)."""
        b = self._far
        if b is None:
            return False
        w, r = b.counts
        return r >= w

    def far_news(self) -> bool:
        """Far tiles worth a redraw of their own: FAR_NEWS made, or the ring's last
        ones (the view's redraws otherwise wait for new chunks: far tiles made while
        the near stream waits, e.g. for a fresh install's kernels, would wait too)."""
        b = self._far
        if b is not None and b.error is not None:
            return True  # a frame shows it (_update_far raises it)
        if b is None or not b.queued:
            return False
        w, r = b.counts
        return b.queued >= FAR_NEWS or r >= w

    def update(self, at, direction, budget) -> bool:
        """Take in what is ready within budget seconds (at: (x, y) of the view point, or
        None to keep it); returns whether more is on its way."""
        if at is not None:
            self.stream.set_view(at[0], at[1], direction)
            self._at = at
        far_loading = self._update_far(budget / 2)
        ready, gone = self.stream.drain(budget)
        for p in ready:
            self.chunks[p.key] = packed(p)
        for k in gone:
            self.chunks.pop(k, None)
        if ready or gone:
            self.gen += 1
        if self.stream.error is not None:
            raise self.stream.error
        self.wanted = self.stream.counts[0]
        self.far_loading = far_loading
        return len(self.chunks) < self.wanted or far_loading

    def close(self) -> None:
        self.set_far(0)
        self.stream.close()
        self.chunks.clear()
        self.gen += 1


def packed(p):
    """The payload with its light as its non-uniform layers (core.chunk.pack_layers,
    ~0.1 ms): the feed and the renderers keep it for every shown chunk, while the
    world keeps its own copy packed too; full arrays were ~130 MB at distance 16."""
    from ...core.chunk import pack_layers
    if p.light is None or isinstance(p.light, tuple):
        return p
    return p._replace(light=pack_layers(p.light))
