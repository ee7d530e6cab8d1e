"""Region culling: the fast plane test equals the thesis's brute-force 8-corner clip test."""
import numpy as np

from voxel_addon.render import camera as C

_CORNERS = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], float)


def brute(mvp, lo, hi):
    pts = lo[:, None, :] + (hi - lo)[:, None, :] * _CORNERS[None]
    clip = (np.c_[pts.reshape(-1, 3), np.ones(len(pts) * 8)] @ mvp.T).reshape(-1, 8, 4)
    x, y, z, w = np.moveaxis(clip, -1, 0)
    return ~((x < -w).all(1) | (x > w).all(1) | (y < -w).all(1) | (y > w).all(1)
             | (z < -w).all(1) | (z > w).all(1))


def test_culling_equals_brute_force():
    rng = np.random.default_rng(0)
    culled = 0
    for _ in range(40):
        cam = C.Camera(*rng.uniform(-50, 50, 2), rng.uniform(0, 200), rng.uniform(0, 360),
                       rng.uniform(-89, 89))
        lo = rng.uniform(-300, 300, (2000, 3))
        hi = lo + rng.uniform(0, 40, (2000, 3))
        got = C.visible(cam.view_proj(), lo, hi)
        assert (got == brute(cam.view_proj(), lo, hi)).all()
        culled += (~got).sum()
    assert culled > 10000  # the cameras do cull


def test_closed_form_matrices_match_numpy():
    rng = np.random.default_rng(1)
    for _ in range(50):
        cam = C.Camera(*rng.uniform(-1e4, 1e4, 2), rng.uniform(0, 256), rng.uniform(-720, 720),
                       rng.uniform(-90, 90), rng.uniform(20, 110), rng.uniform(0.5, 3),
                       rng.uniform(0.05, 1), rng.uniform(100, 2000))
        vp, inv = cam.matrices()
        assert np.allclose(vp, cam.proj() @ cam.view())
        assert np.allclose(inv, np.linalg.inv(vp), rtol=1e-6, atol=1e-9 * np.abs(inv).max())
        # what lies ahead of the camera lands in the middle of the screen
        p = vp @ np.r_[cam.pos + cam.forward * (cam.near + 5.0), 1.0]
        assert np.allclose(p[:2] / p[3], 0.0, atol=1e-6) and -1 < p[2] / p[3] < 1


def test_shadow_matrix_matches_numpy_reference(gl):
    """The light matrix in Python floats equals the NumPy formulation: ortho fitted to
    the frustum corners (from the inverse view-projection) in light space, the near
    plane reaching back to the top of the area."""
    from voxel_addon.render import Settings
    from voxel_addon.render.pipeline import Renderer
    r = Renderer(gl, Settings())
    r.area = (-3, -2, 4, 5)
    rng = np.random.default_rng(3)
    for _ in range(20):
        cam = C.Camera(*rng.uniform(-40, 40, 2), rng.uniform(60, 120), rng.uniform(0, 360),
                       rng.uniform(-80, 80), 70.0, rng.uniform(1, 2), 0.1, 600.0)
        d = rng.normal(size=3)
        d[2] = abs(d[2]) + 0.1
        d /= np.linalg.norm(d)
        got, texel, bias = r._shadow_matrix(cam, d)
        near_cam = C.Camera(cam.x, cam.y, cam.z, cam.yaw, cam.pitch, cam.fov, cam.aspect,
                            cam.near, r.s.shadow_fade + 2.0)
        corners = C.frustum_corners(np.linalg.inv(near_cam.view_proj()))
        assert np.allclose(sorted(near_cam.corners()), sorted(map(tuple, corners)), atol=1e-6)
        view = C.look_at(corners.mean(0), -d)
        lc = corners @ view[:3, :3].T + view[:3, 3]
        lo, hi = lc.min(0), lc.max(0)
        box = np.array([[x, y, z, 1.0] for x in (-48, 64) for y in (-32, 80) for z in (0, 256)])
        top = max(hi[2], (box @ view[2]).max())
        near, far = -top - 1.0, -lo[2] + 1.0
        want = C.ortho(lo[0], hi[0], lo[1], hi[1], near, far) @ view
        assert np.allclose(got, want, atol=1e-9)
        assert np.isclose(texel, max(hi[0] - lo[0], hi[1] - lo[1]) / r.s.shadow_size)
        assert np.isclose(bias, 0.05 / (far - near))
    r.release()
