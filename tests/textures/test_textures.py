"""Textures: every registry name painted, shapes/alpha semantics, tiling, mips, PNG."""
from __future__ import annotations

import zlib

import numpy as np

from voxel_addon import textures as T
from voxel_addon.core.blocks import REGISTRY
from voxel_addon.textures import paint


def test_every_name_has_its_own_painter():
    assert set(REGISTRY.texture_names) <= set(T.PAINTERS)
    arr = T.texture_array()
    assert arr.shape == (len(REGISTRY.texture_names), 16, 16, 4) and arr.dtype == np.uint8
    assert T.glow_array().shape == arr.shape[:3]
    # no two textures identical (a copy-paste painter would show up here)
    flat = {arr[i].tobytes() for i in range(len(arr))}
    assert len(flat) == len(arr)


def test_seeded_and_deterministic():
    assert np.array_equal(T.texture_array(seed=5), T.texture_array(seed=5))
    assert not np.array_equal(T.texture_array(seed=5), T.texture_array(seed=6))
    assert np.array_equal(T.texture_array(origin="bottom"), T.texture_array()[:, ::-1])


def _alpha(name):
    return T.image(name)[0][..., 3]


def test_alpha_follows_render_class():
    for b in REGISTRY.blocks:
        if b.shape == "none":
            continue
        for f in ("-x", "+z", "-z"):
            a = _alpha(b.texture(f))
            if b.render == "opaque":
                assert (a == 255).all(), (b.name, f)
            elif b.render == "alpha_test":  # coverage: only 0 or 255, and some holes
                assert set(np.unique(a)) <= {0, 255}, (b.name, f)
                assert (a == 0).any(), (b.name, f)
            elif b.render == "blend":
                assert (a < 255).any() and (a > 0).all(), (b.name, f)
    assert (_alpha("glass") < 64).mean() > 0.6  # mostly transparent, with a frame
    assert (_alpha("glass")[0] > 200).all()


def test_glow_masks_where_blocks_glow():
    for b in REGISTRY.blocks:
        if b.shape == "none":
            continue
        g = T.image(b.texture("-x"))[1]
        assert (g.any()) == (b.glow > 0), b.name
    g = T.image("ore")[1]
    assert 0 < (g > 0).mean() < 0.3  # specks, not the whole face
    rgb = T.image("lamp_white")[0][..., :3].astype(int)
    assert rgb[T.image("lamp_white")[1] > 0].mean() > 200  # lamps are bright


def test_opaque_ground_tiles_seamlessly():
    # wrap-around neighbours differ no more than interior neighbours do (no seam)
    for n in ("stone", "dirt", "grass_top", "sand", "snow", "water"):
        img = T.image(n)[0][..., :3].astype(int)
        inner = np.abs(np.diff(img, axis=1)).mean()
        seam = np.abs(img[:, 0] - img[:, -1]).mean()
        assert seam < 2.5 * inner + 8, n


def test_mipmaps_weight_colour_by_alpha():
    m = T.mipmaps(T.texture_array())
    assert [x.shape[1] for x in m] == [16, 8, 4, 2, 1]
    leaves = m[-1][T.layer("leaves"), 0, 0]
    a = T.image("leaves")[0].reshape(-1, 4).astype(float)
    want = (a[:, :3] * a[:, 3:]).sum(0) / a[:, 3].sum()
    assert np.abs(leaves[:3] - want).max() <= 1
    assert abs(leaves[3] - a[:, 3].mean()) <= 1
    g = T.mipmaps(T.glow_array())
    assert g[1].shape == (len(REGISTRY.texture_names), 8, 8)


def _decode_png(data: bytes) -> np.ndarray:
    """Independent reader for the 8-bit RGBA, filter-0 PNGs we write."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, w = 8, b"", None
    while pos < len(data):
        n = int.from_bytes(data[pos:pos + 4], "big")
        tag, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]
        assert zlib.crc32(tag + body) == int.from_bytes(data[pos + 8 + n:pos + 12 + n], "big")
        if tag == b"IHDR":
            w, h = int.from_bytes(body[:4], "big"), int.from_bytes(body[4:8], "big")
            assert body[8:10] == b"\x08\x06"
        elif tag == b"IDAT":
            idat += body
        pos += 12 + n
    raw = np.frombuffer(zlib.decompress(idat), np.uint8).reshape(h, 1 + 4 * w)
    assert (raw[:, 0] == 0).all()
    return raw[:, 1:].reshape(h, w, 4)


def test_save_png_roundtrip(tmp_path):
    p = T.save_png("flowers", tmp_path / "f.png", scale=3)
    img = _decode_png(p.read_bytes())
    assert img.shape == (48, 48, 4)
    assert np.array_equal(img[::3, ::3], T.image("flowers")[0])
    s = _decode_png(T.save_sheet(tmp_path / "sheet.png", scale=2).read_bytes())
    assert s.shape[2] == 4 and s.shape[0] > 32
