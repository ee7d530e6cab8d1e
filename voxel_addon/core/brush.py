"""The cells an edit tool touches: brushes (cube or sphere, size 1-8) and boxes."""
from __future__ import annotations

from .chunk import HEIGHT
from .errors import VoxelError

SHAPES = ("CUBE", "SPHERE")
MAX_SIZE = 8


def cells(center, size: int = 1, shape: str = "CUBE") -> list[tuple[int, int, int]]:
    """Cells of a brush of `size` around `center` (an even size grows toward +x +y +z),
    without those outside z 0..255; a sphere keeps cells whose centres lie within
    size/2 of the brush's centre."""
    if not 1 <= size <= MAX_SIZE:
        raise VoxelError(f"brush size {size} is outside 1..{MAX_SIZE}")
    if shape not in SHAPES:
        raise VoxelError(f"brush shape {shape!r} is not one of {', '.join(SHAPES)}")
    x, y, z = (int(v) for v in center)
    lo, hi = -((size - 1) // 2), size // 2
    mid = (lo + hi) / 2
    r2 = (size / 2) ** 2
    out = []
    for dz in range(lo, hi + 1):
        if not 0 <= z + dz < HEIGHT:
            continue
        for dy in range(lo, hi + 1):
            for dx in range(lo, hi + 1):
                if shape == "SPHERE" and (dx - mid) ** 2 + (dy - mid) ** 2 + (dz - mid) ** 2 > r2:
                    continue
                out.append((x + dx, y + dy, z + dz))
    return out


# A larger box is refused: each voxel is relit on its own (~0.5 ms here), so this
# already takes some seconds.
MAX_BOX = 32 ** 3


def box(a, b) -> list[tuple[int, int, int]]:
    """Every cell of the box with corners a and b (inclusive), clipped to z 0..255."""
    lo = [min(int(p), int(q)) for p, q in zip(a, b)]
    hi = [max(int(p), int(q)) for p, q in zip(a, b)]
    lo[2], hi[2] = max(lo[2], 0), min(hi[2], HEIGHT - 1)
    n = 1
    for i in range(3):
        n *= max(0, hi[i] - lo[i] + 1)
    if n > MAX_BOX:
        raise VoxelError(f"the box has {n} cells; at most {MAX_BOX} in one edit")
    return [(x, y, z) for z in range(lo[2], hi[2] + 1) for y in range(lo[1], hi[1] + 1)
            for x in range(lo[0], hi[0] + 1)]
