"""The chunks of the shown world, shared by every window: payloads from a world.Stream
(nearest first, made in its background thread)."""
from __future__ import annotations


class Feed:
    def __init__(self, path, world, distance):
        from ...world import Stream
        self.path, self.world, self.distance = path, world, distance
        self.chunks: dict = {}   # key -> Payload (.key, .mesh, .light, .version)
        self.stream = Stream(world, distance)
        self.wanted = 0          # chunks the stream means to show

    def update(self, at, direction, budget) -> bool:
        """Take in what is ready within budget seconds (at: (x, y) of the view point, or
        None to keep it); returns whether more is on its way."""
        if at is not None:
            self.stream.set_view(at[0], at[1], direction)
        ready, gone = self.stream.drain(budget)
        for p in ready:
            self.chunks[p.key] = packed(p)
        for k in gone:
            self.chunks.pop(k, None)
        if self.stream.error is not None:
            raise self.stream.error
        self.wanted = self.stream.counts[0]
        return len(self.chunks) < self.wanted

    def close(self) -> None:
        self.stream.close()
        self.chunks.clear()


def packed(p):
    """The payload with its light as its non-uniform layers (core.chunk.pack_layers,
    ~0.1 ms): the feed and the renderers keep it for every shown chunk, while the
    world keeps its own copy packed too; full arrays were ~130 MB at distance 16."""
    from ...core.chunk import pack_layers
    if p.light is None or isinstance(p.light, tuple):
        return p
    return p._replace(light=pack_layers(p.light))
