"""Camera geometry: known points on known pixels, depth along the optical axis."""

from __future__ import annotations

import math

import numpy as np
import pytest

import skyfall
from skyfall import Camera, scenes


def test_known_points_land_on_expected_pixels():
    cam = Camera((0.0, 1.6, 0.0), vertical_fov_deg=90.0, width=101, height=101)
    fx, fy, cx, cy = cam.intrinsics()
    assert fy == pytest.approx(50.5) and fx == fy and (cx, cy) == (50.5, 50.5)
    px, depth = cam.project([[0.0, 1.6, -10.0], [10.0, 1.6, -10.0], [0.0, 11.6, -10.0], [0.0, 1.6, 5.0]])
    np.testing.assert_allclose(px[0], [50.5, 50.5], atol=1e-9)
    np.testing.assert_allclose(px[1], [101.0, 50.5], atol=1e-9)  # 45 degrees right: the right edge
    np.testing.assert_allclose(px[2], [50.5, 0.0], atol=1e-9)  # 45 degrees up: the top edge
    np.testing.assert_allclose(depth, [10.0, 10.0, 10.0, -5.0])


def test_yaw_pitch_and_look_at_agree():
    a = Camera((1.0, 2.0, 3.0), yaw_deg=30.0, pitch_deg=-10.0)
    fwd = -a.rotation[:, 2]
    b = Camera((1.0, 2.0, 3.0), look_at_m=np.array([1.0, 2.0, 3.0]) + 7.0 * fwd)
    np.testing.assert_allclose(b.rotation, a.rotation, atol=1e-12)
    m = a.world_from_camera
    np.testing.assert_allclose(m[:3, :3].T @ m[:3, :3], np.eye(3), atol=1e-12)
    assert np.linalg.det(m[:3, :3]) == pytest.approx(1.0)
    # positive yaw turns left (towards -X), positive pitch looks up
    assert fwd[0] < 0 and fwd[1] < 0
    np.testing.assert_allclose(m[:3, 3], [1.0, 2.0, 3.0])


def test_rendered_box_covers_its_projection_and_depth_is_along_the_axis():
    cam = Camera((0.0, 1.6, 0.0), yaw_deg=20.0, pitch_deg=5.0, vertical_fov_deg=50.0, width=120, height=80)
    lo, hi = np.array([-6.0, 1.0, -14.0]), np.array([-3.0, 3.0, -12.0])
    scene = scenes.boxes([{"min": lo, "max": hi, "albedo": 0.8}], ground=False, camera=cam)
    frame = skyfall.Renderer(120, 80, backend="cpu").render(scene)
    hit = np.isfinite(frame.depth_m)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    px, depth = cam.project(corners)
    ys, xs = np.nonzero(hit)
    # every lit pixel centre lies inside the projected corners' bounding box
    assert xs.min() + 0.5 >= px[:, 0].min() and xs.max() + 0.5 <= px[:, 0].max()
    assert ys.min() + 0.5 >= px[:, 1].min() and ys.max() + 0.5 <= px[:, 1].max()
    assert depth.min() - 1e-4 <= frame.depth_m[hit].min() and frame.depth_m[hit].max() <= depth.max() + 1e-4
    # and the projection of the front face's centre is a hit pixel
    pts, centre_depth = cam.project([[(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, hi[2]]])
    cx, cy = pts[0]
    assert hit[int(cy), int(cx)]
    assert abs(frame.depth_m[int(cy), int(cx)] - centre_depth[0]) < 0.3  # face is tilted 20 degrees


def test_ground_depth_is_constant_along_rows():
    # Looking level over the ground, a row of pixels sees the ground at one depth along the
    # axis (their distances differ): depth = h * fy / (y + 0.5 - cy).
    cam = Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0)
    frame = skyfall.Renderer(64, 48, backend="cpu").render(scenes.empty(camera=cam))
    _, fy, _, cy = cam.with_resolution(64, 48).intrinsics()
    for y in (30, 40, 47):
        np.testing.assert_allclose(frame.depth_m[y], 1.6 * fy / (y + 0.5 - cy), rtol=1e-5)
    assert np.isinf(frame.depth_m[:24]).all()


@pytest.mark.parametrize(
    "kwargs,match",
    [
        ({"pitch_deg": 90.0}, "pitch_deg"),
        ({"vertical_fov_deg": 0.0}, "vertical_fov_deg"),
        ({"fx": 100.0}, "need width and height"),
        ({"position_m": (0, float("nan"), 0)}, "position_m"),
        ({"width": 0}, "width"),
        ({"exposure_s": 1.0}, "exposure_s"),
        ({"look_at_m": (0.0, 1.6, 0.0)}, "look_at_m"),
    ],
)
def test_bad_cameras(kwargs, match):
    args = {"position_m": (0.0, 1.6, 0.0)}
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        Camera(args.pop("position_m"), **args)


def test_explicit_intrinsics_must_match_the_frame():
    cam = Camera(width=64, height=48, fx=50.0, fy=50.0, cx=30.0, cy=20.0)
    assert cam.intrinsics() == (50.0, 50.0, 30.0, 20.0)
    with pytest.raises(ValueError, match="64x48"):
        skyfall.Renderer(32, 24, backend="cpu").render(scenes.empty(), camera=cam)
    assert math.isclose(Camera(vertical_fov_deg=90, width=10, height=10).intrinsics()[1], 5.0)


def test_ray_directions_meet_the_ground_where_the_frame_says() -> None:
    # A frame of open ground: each ground pixel's ray, scaled by its depth, ends on y = 0 (the
    # renderer's own ray cast), and an unscaled ray has camera-space z = -1.
    import numpy as np

    from skyfall import Camera, Renderer, scenes

    cam = Camera((0.3, 1.7, 0.0), pitch_deg=-25.0, yaw_deg=20.0, width=40, height=30)
    frame = Renderer(40, 30, backend="cpu").render(scenes.empty(camera=cam))
    ground = np.isfinite(frame.depth_m)
    assert ground.mean() > 0.3
    d = cam.ray_directions()
    pts = cam.position_m + d * frame.depth_m[..., None]
    np.testing.assert_allclose(pts[ground][:, 1], 0.0, atol=1e-4)
    back = np.asarray(cam.rotation)[:, 2]
    np.testing.assert_allclose(d @ back, -1.0, atol=1e-12)  # camera-space z = -1
