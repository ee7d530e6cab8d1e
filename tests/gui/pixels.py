"""Reading Blender's UI from screenshot pixels (NumPy only: used inside Blender by
test scripts and by the pytest side). Images are (H, W, 3) uint8, top row first;
rectangles are image [x0, row0, x1, row1) (see rect_rows)."""
from __future__ import annotations

import numpy as np


def read_ppm(path) -> np.ndarray:
    """A binary PPM (P6, maxval 255) as (H, W, 3) uint8."""
    data = open(path, "rb").read()
    fields, pos = [], 0
    while len(fields) < 4:  # magic, width, height, maxval; '#' comments skipped
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1
            continue
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        fields.append(data[pos:end])
        pos = end
    if fields[0] != b"P6" or int(fields[3]) != 255:
        raise ValueError(f"not an 8-bit P6 PPM: {path}")
    w, h = int(fields[1]), int(fields[2])
    return np.frombuffer(data, np.uint8, w * h * 3, pos + 1).reshape(h, w, 3)


def rect_rows(rect, height: int) -> tuple[int, int, int, int]:
    """Window rectangle [x, y, w, h] (origin bottom-left) -> image (x0, row0, x1, row1)."""
    x, y, w, h = rect
    return x, height - (y + h), x + w, height - y


def runs(mask: np.ndarray, min_len: int = 1, max_gap: int = 0) -> list[tuple[int, int]]:
    """[start, end) of the True runs of a 1-D mask; gaps up to max_gap are bridged."""
    out: list[list[int]] = []
    for i in map(int, np.flatnonzero(mask)):
        if out and i - out[-1][1] <= max_gap:
            out[-1][1] = i + 1
        else:
            out.append([i, i + 1])
    return [(a, b) for a, b in out if b - a >= min_len]


def sidebar_tabs(img: np.ndarray, rect, scale: float) -> list[tuple[int, int]]:
    """Image rows [start, end) of the category tab labels at the sidebar's right edge.

    The labels are vertical bright text on the darker tab strip; each label is one
    run of rows holding text pixels, labels are separated by the tabs' margins. Text is
    what stands out from the strip (4.x draws inactive labels near white, 5.x mid
    grey, ~145 on ~65)."""
    x0, r0, x1, r1 = rect_rows(rect, img.shape[0])
    strip = img[r0:r1, x1 - int(22 * scale):x1 - int(3 * scale)].max(axis=2)
    text = (strip > min(150, np.median(strip) + 50)).sum(axis=1) >= 1
    return [(r0 + a, r0 + b) for a, b in runs(text, min_len=int(8 * scale), max_gap=int(5 * scale))]


def panel_blocks(img: np.ndarray, rect, scale: float, back) -> list[tuple[int, int]]:
    """Image rows [start, end) of the panels drawn in a sidebar region.

    A panel is an opaque rounded box in the theme's panel colour `back` (0..255 RGB);
    between panels the viewport shows through. A row belongs to a panel when the
    box's left margin (left of any widget) has that colour."""
    x0, r0, x1, r1 = rect_rows(rect, img.shape[0])
    band = img[r0:r1, x0 + round(9 * scale):x0 + round(14 * scale)].astype(int)
    inside = (np.abs(band - np.asarray(back, int)).max(axis=2) <= 1).all(axis=1)
    return [(r0 + a, r0 + b) for a, b in runs(inside, min_len=round(20 * scale))]


def has_text(img: np.ndarray, rows, cols, level: int = 170) -> bool:
    """Whether bright (text) pixels appear in img[rows, cols]."""
    return bool((img[rows[0]:rows[1], cols[0]:cols[1]].max(axis=2) > level).sum() >= 10)
