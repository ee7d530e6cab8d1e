"""The world model: block registry, chunks, the chunk map and its loader thread. Depends on nothing else in the package."""
