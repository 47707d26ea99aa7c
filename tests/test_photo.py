"""Photos keep their own light (issue 14, item 1): the airlight estimated from the photo (He,
Sun & Tang's dark channel prior) against scipy and a synthetic hazy image whose airlight is
known; the ground-plane depth against the camera's own projection; a photo's frames scale
with its exposure, and its sky fades continuously with the rain."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage
from skimage import data, transform

from skyfall import Camera, PhotoScene, Renderer, Weather, io
from skyfall.photo import dark_channel, estimate_airlight, ground_plane_depth


def test_the_dark_channel_is_scipys_minimum_filter_of_the_channel_minimum():
    rng = np.random.default_rng(1)
    img = rng.uniform(0, 1, (41, 57, 3)).astype(np.float32)
    codes = rng.integers(0, 256, (23, 19, 3), dtype=np.uint8)
    for patch in (1, 3, 15, 31):
        want = ndimage.minimum_filter(img.min(axis=2), size=patch, mode="nearest")
        np.testing.assert_array_equal(dark_channel(img, patch_px=patch), want)
        want8 = ndimage.minimum_filter(codes.min(axis=2), size=patch, mode="nearest")
        np.testing.assert_array_equal(dark_channel(codes, patch_px=patch), want8.astype(np.float32))
    with pytest.raises(ValueError, match="patch_px"):
        dark_channel(img, patch_px=4)
    with pytest.raises(ValueError, match="image"):
        dark_channel(img[..., :2])


def hazy(airlight: np.ndarray, noise: float, seed: int = 0) -> np.ndarray:
    """I = J t + A (1 - t) (Koschmieder; He, Sun & Tang's model) over a colourful scene J whose
    every pixel has one channel near zero (the dark channel prior holds), depth from 5 m at
    the bottom to 3 km at the top, the top tenth sky (t = 0)."""
    rng = np.random.default_rng(seed)
    h, w = 120, 160
    j = rng.uniform(0.05, 0.9, (h, w, 3))
    j[np.arange(h)[:, None], np.arange(w)[None, :], rng.integers(0, 3, (h, w))] = 0.01
    depth = np.geomspace(3000.0, 5.0, h)[:, None] * np.ones((1, w))
    depth[: h // 10] = np.inf
    t = np.exp(-2e-3 * depth)[..., None]
    img = j * t + airlight * (1 - t) + rng.normal(0, noise, (h, w, 3))
    return np.clip(img, 0, None).astype(np.float32)


@pytest.mark.parametrize("airlight", [(0.62, 0.70, 0.81), (0.05, 0.04, 0.03), (2.0, 1.6, 1.2)])
def test_the_estimate_recovers_a_known_airlight(airlight):
    a = np.array(airlight)
    np.testing.assert_allclose(estimate_airlight(hazy(a, 0.0)), a, rtol=1e-6)
    # with sensor noise (1 % of the brightest airlight) the brightest of the top 0.1 % is a
    # noisy pixel: within 4 % of the level
    noisy = estimate_airlight(hazy(a, 0.01 * a.max(), seed=3))
    np.testing.assert_allclose(noisy, a, rtol=0.04)
    # and through 8 bits: the sRGB codes give the same pixel, decoded
    if a.max() <= 1:
        codes = io.to_srgb8(hazy(a, 0.0))
        np.testing.assert_allclose(estimate_airlight(codes), io.decode_srgb8(io.to_srgb8(a.astype(np.float32))), rtol=1e-6)


def test_with_sky_pixels_the_estimate_is_the_horizon_sky_whatever_stands_in_it():
    # A sky graded from A at the horizon to darker overhead, with a white tower and a lamp in
    # it (what He, Sun & Tang's estimator picks in scikit-image's rocket: its lit base).
    h, w = 90, 120
    cam = Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0, width=w, height=h)
    depth = ground_plane_depth(cam)
    sky = np.isinf(depth)
    a = np.array([0.30, 0.28, 0.35])
    rows = np.arange(h)[:, None, None]
    img = np.where(sky[..., None], a * (0.4 + 0.6 * rows / (h / 2)), 0.05).astype(np.float32)
    img[:, 50:70] = 0.95  # the tower, white from top to bottom
    img[40:45, 10:15] = 20.0  # a lamp
    got = estimate_airlight(img, depth_m=depth, camera=cam)
    # the lowest tenth of the sky is its bottom rows, 0.4 + 0.6 (rows / 45) of A there
    low = np.flatnonzero(sky[:, 0])[-1]
    lowest = int(np.ceil(0.1 * sky.sum() / w))
    want = a[None, :] * (0.4 + 0.6 * np.arange(low - lowest + 1, low + 1) / (h / 2))[:, None]
    assert np.all(got >= want.min(axis=0) - 1e-6) and np.all(got <= want.max(axis=0) + 1e-6)
    assert np.abs(estimate_airlight(img) - 0.95).max() < 1e-6  # without the depth map: the tower
    # an 8-bit photo gives the median code, decoded
    codes = io.to_srgb8(img)
    np.testing.assert_allclose(estimate_airlight(codes, depth_m=depth, camera=cam), got, rtol=0.02)
    with pytest.raises(ValueError, match="needs the camera"):
        estimate_airlight(img, depth_m=depth)


def test_the_ground_plane_is_where_the_camera_says():
    cam = Camera((2.0, 1.3, -4.0), yaw_deg=25.0, pitch_deg=-6.0, vertical_fov_deg=50.0, width=64, height=48)
    depth = ground_plane_depth(cam)
    fx, fy, cx, cy = cam.intrinsics()
    ys, xs = np.nonzero(np.isfinite(depth))
    d = depth[ys, xs].astype(np.float64)
    ray = np.stack([(xs + 0.5 - cx) / fx, -(ys + 0.5 - cy) / fy, -np.ones_like(d)], axis=1) @ cam.rotation.T
    points = cam.position_m + ray * d[:, None]
    np.testing.assert_allclose(points[:, 1], 0.0, atol=1e-5 * d.max())
    # the camera's own projection of those ground points gives the pixel centres and depths back
    px, back = cam.project(points)
    np.testing.assert_allclose(px, np.stack([xs + 0.5, ys + 0.5], axis=1), atol=1e-3)
    np.testing.assert_allclose(back, d, rtol=1e-5)
    # above the horizon: sky
    assert np.isinf(depth[0]).all() and np.isfinite(depth[-1]).all()


def test_a_photo_without_depth_gets_its_horizon_where_it_is_told():
    img = np.full((60, 80, 3), 100, np.uint8)  # no sky in it: a flat mid grey
    scene = PhotoScene(img, camera_height_m=2.0, horizon_row=21.0)
    assert scene.depth_source == "ground_plane" and not scene.sky_mask.any()
    ground = ground_plane_depth(scene.camera)
    below = np.isfinite(ground[:, 0])
    # rows whose centre (k + 0.5) lies below row 21 see the ground, up to distance_m (10 m);
    # the rows above it hold something upright at distance_m: no sky without a sky mask
    assert below.argmax() == 21 and not below[:21].any() and below[21:].all()
    np.testing.assert_array_equal(scene.depth_m, np.minimum(ground, np.float32(10.0)))
    assert (scene.depth_m[:21] == 10.0).all()
    assert scene.camera.position_m[1] == 2.0 and scene.camera.pitch_deg < 0  # a horizon above the middle: looking down
    far = PhotoScene(img, camera_height_m=2.0, horizon_row=21.0, distance_m=50.0)
    np.testing.assert_array_equal(far.depth_m, np.minimum(ground, np.float32(50.0)))
    with pytest.raises(ValueError, match="either a camera or camera_height_m"):
        PhotoScene(img, camera=Camera((0, 2, 0)), horizon_row=20.0)
    with pytest.raises(ValueError, match="this photo has one"):
        PhotoScene(img, np.ones((60, 80)), camera_height_m=2.0)
    with pytest.raises(ValueError, match="this photo has one"):
        PhotoScene(img, np.ones((60, 80)), distance_m=3.0)
    with pytest.raises(ValueError, match="pitch"):
        PhotoScene(img, horizon_row=1e6)
    with pytest.raises(ValueError, match="airlight"):
        PhotoScene(img, airlight="grey")
    with pytest.raises(ValueError, match=r"airlight\[1\] = -1.0 is outside"):
        PhotoScene(img, airlight=(0.1, -1.0, 0.1))


def small(image: np.ndarray, width: int = 128) -> np.ndarray:
    h = round(image.shape[0] * width / image.shape[1])
    return np.round(transform.resize(image, (h, width), anti_aliasing=True) * 255).astype(np.uint8)


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_a_photo_at_a_quarter_of_the_exposure_gets_a_quarter_of_the_weather(backend):
    # The issue: the same photo at a quarter of its brightness got the same grey sky (11 -> 175).
    img = io.decode_srgb8(small(data.astronaut()))
    h, w = img.shape[:2]
    r = Renderer(w, h, backend=backend)
    weather = Weather(rain_rate_mm_h=25.0, visibility_m=2000.0)
    full = r.render(PhotoScene(img, camera_height_m=1.6, horizon_row=0.6 * h, encoding="linear"), weather, seed=2)
    quarter = r.render(PhotoScene(img / 4, camera_height_m=1.6, horizon_row=0.6 * h, encoding="linear"), weather, seed=2)
    np.testing.assert_allclose(quarter.rgb * 4, full.rgb, rtol=1e-5, atol=1e-7)
    assert full.layers["rain_alpha"].max() > 0.005  # it did rain


def test_a_dusk_sky_fades_continuously_and_keeps_its_colour():
    # scikit-image's rocket: a dusk sky, mean sRGB (27, 41, 67) at full size. Before, any rain
    # (0.01 mm/h included) made every sky pixel one flat grey (175, 175, 175).
    photo = small(data.rocket(), 160)
    h, w = photo.shape[:2]
    scene = PhotoScene(photo, camera_height_m=1.6, horizon_row=0.65 * h)
    sky = np.isinf(scene.depth_m)
    r = Renderer(w, h, backend="cpu")
    clear = photo[sky].astype(float)
    tiny = r.render_srgb8(scene, Weather(rain_rate_mm_h=1e-7)).astype(float)
    assert np.abs(tiny[sky] - clear).max() <= 1  # sigma -> 0 gives the photo back
    means = [r.render_srgb8(scene, Weather(rain_rate_mm_h=rate))[sky].astype(float).mean(axis=0) for rate in (0.01, 1.0, 25.0)]
    # the sky moves towards the photo's own airlight as the rain thickens, staying blue
    air = io.to_srgb8(np.array(scene.airlight_linear, np.float32)).astype(float)
    dist = [np.abs(m - air).sum() for m in (clear.mean(axis=0), *means)]
    assert dist == sorted(dist, reverse=True), dist
    for m in means:
        assert m[2] > m[0] + 15  # blue over red, like the dusk it is
    heavy = r.render_srgb8(scene, Weather(rain_rate_mm_h=25.0))[sky].astype(float)
    assert np.abs(heavy.mean(axis=0) - air).max() < 10 and heavy.mean() < 140  # not the old grey 175
