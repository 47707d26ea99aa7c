"""The camera's thin lens: focal length in mm, f-number and focus distance; streaks defocused by
their circle of confusion on both backends and in the 8-bit path, their opacity kept, and a
pinhole (no f-number) the frames of before, bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skyfall import Camera, PhotoScene, Renderer, Weather, io

W, H = 128, 96


@pytest.fixture(scope="module")
def cpu() -> Renderer:
    return Renderer(W, H, backend="cpu")


@pytest.fixture(scope="module")
def gpu() -> Renderer:
    return Renderer(W, H, backend="gpu")


def photo8(cam: Camera) -> PhotoScene:
    rng = np.random.default_rng(4)
    img = rng.integers(40, 200, (H, W, 3), dtype=np.uint8)
    y, x = np.mgrid[0:H, 0:W]
    depth = (3.0 + 0.05 * x + 0.1 * y).astype(np.float32)
    depth[:15] = np.inf
    return PhotoScene(img, depth, camera=cam, airlight="sky")  # lit as a rendered frame: the drops show


# A wide aperture on a large sensor, so that at this small frame the near drops' blur circles
# reach the cap (f = 166 px · 200 mm / 128 px ≈ 260 mm at f/1: 8 px for a drop at 1 m).
# A short exposure, so the drops are opaque enough to show in 8 bits.
PIN = {"sensor_width_mm": 200.0, "exposure_s": 1.0 / 250.0}
LENS = {**PIN, "f_number": 1.0, "focus_distance_m": 8.0}
RAIN = Weather(rain_rate_mm_h=15.0, wind_m_s=(1.0, 0.0, 0.0), rain_near_m=4.0)


def test_focal_length_sets_the_view_and_the_lens_survives_with_resolution():
    cam = Camera(focal_length_mm=50.0, width=720, height=480)
    fx, fy, cx, cy = cam.intrinsics()
    assert fx == fy == pytest.approx(50.0 / 36.0 * 720) and (cx, cy) == (360.0, 240.0)
    # a full-frame 50 mm lens: 39.6 degrees across the frame's width
    assert math.degrees(2 * math.atan(360.0 / fx)) == pytest.approx(39.598, abs=1e-3)
    lens = Camera(focal_length_mm=85.0, sensor_width_mm=23.5, f_number=1.8, focus_distance_m=3.0)
    at = lens.with_resolution(400, 300)
    assert (at.focal_length_mm, at.sensor_width_mm, at.f_number, at.focus_distance_m) == (85.0, 23.5, 1.8, 3.0)
    assert at.intrinsics()[0] == pytest.approx(85.0 / 23.5 * 400)
    # a pinhole by default; an f-number alone focuses at infinity
    assert Camera().f_number is None and Camera().focus_distance_m is None
    assert Camera(f_number=2.0).focus_distance_m == math.inf


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"focal_length_mm": 50.0, "vertical_fov_deg": 40.0}, "focal_length_mm"),
        ({"focal_length_mm": 50.0, "width": 10, "height": 10, "fx": 9.0}, "focal_length_mm"),
        ({"focus_distance_m": 3.0}, "focus_distance_m needs f_number"),
        ({"focal_length_mm": 50.0, "f_number": 2.0, "focus_distance_m": 0.04}, "focus_distance_m"),
        ({"f_number": 0.3}, "f_number"),
        ({"f_number": 2.0, "focus_distance_m": -1.0}, "focus_distance_m"),
    ],
)
def test_contradicting_or_bad_lens_values_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Camera(**kwargs)


def test_focus_within_the_derived_focal_length_is_refused_by_the_core(cpu):
    # The focal length in mm follows from the field of view (f = fy · sensor / width): with a
    # 500 mm sensor 128 px wide it is 83 px · 500 mm / 128 px ≈ 325 mm, beyond a 0.3 m focus.
    cam = Camera(sensor_width_mm=500.0, f_number=2.0, focus_distance_m=0.3)
    with pytest.raises(ValueError, match=r"^focus_distance_m = 0.3 is not beyond the lens's focal length"):
        cpu.render(photo8(cam), RAIN)


def test_a_camera_without_f_number_renders_the_pinhole_bits(cpu):
    # focal_length_mm alone is a pinhole with that field of view: the same bits as the fx it sets.
    a = Camera(focal_length_mm=30.0)
    fx = 30.0 / 36.0 * W
    b = Camera(width=W, height=H, fx=fx, fy=fx)
    fa, fb = cpu.render(photo8(a), RAIN, seed=2), cpu.render(photo8(b), RAIN, seed=2)
    assert fa.rgb.tobytes() == fb.rgb.tobytes()
    assert fa.layers["rain_alpha"].tobytes() == fb.layers["rain_alpha"].tobytes()


def test_defocus_spreads_the_rain_and_keeps_its_opacity(cpu):
    pin = cpu.render(photo8(Camera(**PIN)), RAIN, seed=5).layers["rain_alpha"]
    soft = cpu.render(photo8(Camera(**LENS)), RAIN, seed=5).layers["rain_alpha"]
    # the same drops (the lens changes no fields of view: sensor_width_mm alone is a pinhole)
    assert (np.abs(soft - pin) > 1e-3).mean() > 0.1
    # spread: more pixels touched, the densest streaks thinned
    assert (soft > 1e-3).mean() > 1.1 * (pin > 1e-3).mean()
    assert soft.max() < 0.8 * pin.max()
    # Each drop keeps its opacity-area (∫α dA, tested per drop in the core); over the frame
    # the coverage 1 − ∏(1 − a) sums to nearly the same, off by the streaks' overlaps (which a
    # blur changes) and the frame's edges (which a blur crosses): measured within 0.8 % over
    # three seeds.
    assert soft.sum() == pytest.approx(pin.sum(), rel=0.03)


def test_the_8_bit_path_through_a_lens_is_the_float_frame_encoded(cpu):
    scene = photo8(Camera(**LENS))
    frame = cpu.render(scene, RAIN, seed=3)
    alpha = np.zeros((H, W), np.float32)
    got = cpu.render_srgb8(scene, RAIN, seed=3, layers={"rain_alpha": alpha}).image
    diff = np.abs(got.astype(int) - io.to_srgb8(frame.rgb))
    assert diff.max() <= 1 and np.mean(diff > 0) < 1e-3
    np.testing.assert_allclose(alpha, frame.layers["rain_alpha"], atol=1e-6)
    # and the lens did something there too: more than 1 code of change from the pinhole's in
    # 1.8 to 2.9 % of the pixels over three seeds
    pin = cpu.render_srgb8(photo8(Camera(**PIN)), RAIN, seed=3)
    assert np.mean(np.abs(pin.astype(int) - got).max(axis=2) > 1) > 0.01


def test_gpu_matches_cpu_through_a_lens(gpu, cpu):
    scene = photo8(Camera(**LENS))
    c, g = cpu.render(scene, RAIN, seed=7), gpu.render(scene, RAIN, seed=7)
    assert c.stats == g.stats
    assert np.abs(c.rgb - g.rgb).max() <= 1e-4
    assert np.abs(c.layers["rain_alpha"] - g.layers["rain_alpha"]).max() <= 1e-4
    assert c.layers["rain_alpha"].max() > 2e-3  # (rain there, blurred thin)
