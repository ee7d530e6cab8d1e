"""User-facing errors: the CLI prints their message on one line and exits 2."""


class VoxelError(Exception):
    """A mistake in what the user asked for (bad name, bad coordinate, bad file)."""
