"""Golden images: the demo's street frames, small, against PNGs made from the code on purpose.

The demo (``python -m skyfall._demo``) renders its three street frames at 1280 x 720; here the
same scenes, weathers and seeds (:data:`skyfall._demo.DEMO_FRAMES`) render at 320 x 180 on the
CPU backend, with the day rain's ``rain_alpha`` PNG and the 8-bit photo path (render_srgb8 of
the clear street as an 8-bit photo with its depth, in 10 mm/h rain: the augmentation path the
rain bench times at 1080p). Each is compared, as 8-bit sRGB, with its PNG in tests/data/golden/
(see the README there), and the GPU backend (lavapipe where there is no GPU) with the same PNGs.

Bounds. The CPU backend is deterministic, and today it gives the goldens bit for bit; the bounds
leave room for a change that rounds a pixel the other way (reassociated sums, another compiler)
and nothing more:

- SSIM >= 0.995 (scikit-image, 8-bit data range). The issue's 0.98 is too loose for rain at this
  size: streaks are a few pixels and faint, so the day-rain frame with another seed's rain scores
  0.988 and with no streaks at all 0.9925, while a frame without its awning scores 0.85.
- mean |difference| <= 0.25 codes: catches what SSIM barely sees, a uniform change of brightness
  (3 % brighter: SSIM 0.9976 but 1.13 codes) and the rain of another seed (0.5-1.4 codes).
- at most 0.1 % of the values more than one code off.

The GPU backend gets SSIM >= 0.99 and 0.5 % of values more than one code off, with the same
mean: f32 rounding (FMA) may move a silhouette by a pixel (tests/test_render.py allows 0.5 % of
pixels there). Measured on lavapipe: SSIM 0.9999995-1.0, mean 1.7e-5-5.2e-5 codes, 1 to 9 values
one code off (of 172,800 per RGB frame; the photo path has the 9), none more. The whole file
runs in about 2.5 s.

Regenerate the goldens only when a change of the pictures is intended, and say why in the
commit: ``SKYFALL_UPDATE_GOLDEN=1 .venv/bin/python -m pytest tests/test_golden.py`` rewrites
them from the CPU backend (then compares, so it passes), and update tests/data/golden/README.md.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from numpy.typing import NDArray
from skimage.metrics import structural_similarity

from skyfall import PhotoScene, Renderer, Weather, io, scenes
from skyfall._demo import DEMO_FRAMES, STREET_RAIN_DAY, rain_alpha_png
from skyfall._demo.photo import PHOTO_FRAMES
from skyfall._demo.snow import SNOW_DEMOS, png8

GOLDEN = Path(__file__).parent / "data" / "golden"
UPDATE = os.environ.get("SKYFALL_UPDATE_GOLDEN") == "1"
W, H = 320, 180
PHOTO_RAIN = Weather(rain_rate_mm_h=10.0)
NAMES = [*(d.name for d in DEMO_FRAMES), "street_rain_day_alpha", "street_photo8_rain"]
PHOTO_W = 160
"""The demo's photos (skyfall._demo.photo) are guarded at 160 px wide (their own aspect)."""
# (min SSIM, max mean |difference| in codes, max fraction of values > 1 code off)
BOUNDS = {"cpu": (0.995, 0.25, 0.001), "gpu": (0.99, 0.25, 0.005)}


def street_photo() -> PhotoScene:
    """The clear street as an 8-bit photo with its depth map (as benches/bench_rain.py makes it
    at 1080p); made on the CPU backend for both backends, so both get the same input."""
    street = scenes.street()
    clear = Renderer(W, H, backend="cpu").render(street)
    return PhotoScene(io.to_srgb8(clear.rgb), clear.depth_m, camera=street.camera)


def render_all(backend: str) -> dict[str, NDArray[np.uint8]]:
    """Every golden's picture, 8-bit sRGB, from ``backend``."""
    renderer = Renderer(W, H, backend=backend)
    images: dict[str, NDArray[np.uint8]] = {}
    for demo in DEMO_FRAMES:
        frame = demo.render(renderer)
        images[demo.name] = demo.png8(frame)
        if demo is STREET_RAIN_DAY:
            images["street_rain_day_alpha"] = io.to_srgb8(rain_alpha_png(frame))
    images["street_photo8_rain"] = renderer.render_srgb8(street_photo(), PHOTO_RAIN, seed=0)
    return images


def read_golden(name: str) -> NDArray[np.uint8]:
    """A golden PNG's codes (read through OpenImageIO, decoded, encoded back: exact)."""
    codes = io.to_srgb8(io.read_image(GOLDEN / f"{name}_{W}x{H}.png"))
    return codes[..., 0] if codes.shape[-1] == 1 else codes


def compare(got: NDArray[np.uint8], want: NDArray[np.uint8]) -> tuple[float, float, float]:
    """(SSIM, mean |difference| in codes, fraction of values more than one code off)."""
    assert got.shape == want.shape, (got.shape, want.shape)
    ssim = float(structural_similarity(got, want, data_range=255, channel_axis=-1 if got.ndim == 3 else None))
    diff = np.abs(got.astype(np.int16) - want)
    return ssim, float(diff.mean()), float(np.mean(diff > 1))


def within(stats: tuple[float, float, float], backend: str) -> bool:
    ssim, mean, off = stats
    min_ssim, max_mean, max_off = BOUNDS[backend]
    return ssim >= min_ssim and mean <= max_mean and off <= max_off


@pytest.fixture(scope="module")
def goldens() -> dict[str, NDArray[np.uint8]]:
    if UPDATE:
        GOLDEN.mkdir(parents=True, exist_ok=True)
        for name, image in render_all("cpu").items():
            io.write_image(GOLDEN / f"{name}_{W}x{H}.png", image)  # uint8: written as it is
    return {name: read_golden(name) for name in NAMES}


@pytest.fixture(scope="module", params=["cpu", "gpu"])
def rendered(request: pytest.FixtureRequest) -> tuple[str, dict[str, NDArray[np.uint8]]]:
    return request.param, render_all(request.param)


@pytest.mark.parametrize("name", NAMES)
def test_frames_match_their_goldens(rendered, goldens, name):
    backend, images = rendered
    image = images[name]
    stats = compare(image, goldens[name])
    assert within(stats, backend), f"{name} on {backend}: SSIM {stats[0]:.5f}, mean {stats[1]:.4f} codes, {stats[2]:.3%} > 1 code (bounds {BOUNDS[backend]})"


def test_the_goldens_are_the_demo_frames_and_show_rain(goldens):
    photos = [f"{f.name}_{PHOTO_W}w.png" for f in PHOTO_FRAMES] + [snow_golden(d).name for d in SNOW_DEMOS]
    assert sorted(p.name for p in GOLDEN.glob("*.png")) == sorted([f"{n}_{W}x{H}.png" for n in NAMES] + photos)
    for name in NAMES:
        assert goldens[name].shape == ((H, W) if name.endswith("alpha") else (H, W, 3)), name
    alpha = goldens["street_rain_day_alpha"]
    assert alpha.max() == 255 and np.mean(alpha > 0) > 0.9  # stretched to its maximum; at 50 mm/h streaks everywhere
    # the dusk frame is darker than the day's but for its lamps and headlights, which show as
    # near-white emitters; the day frame has none
    dusk, day = goldens["street_rain"], goldens["street_rain_day"]
    assert np.median(dusk) < np.median(day)
    assert np.mean(dusk.min(axis=2) >= 250) > 0.002 and not np.any(day.min(axis=2) >= 250)


@pytest.mark.parametrize("frame", PHOTO_FRAMES, ids=[f.name for f in PHOTO_FRAMES])
def test_the_demo_photos_match_their_goldens(frame):
    # The 8-bit path on the CPU (render_srgb8's fused path), as the demo writes it.
    path = GOLDEN / f"{frame.name}_{PHOTO_W}w.png"
    before, after = frame.render(PHOTO_W)
    if UPDATE:
        io.write_image(path, after)
    stats = compare(after, io.to_srgb8(io.read_image(path)))
    assert within(stats, "cpu"), f"{frame.name}: SSIM {stats[0]:.5f}, mean {stats[1]:.4f} codes, {stats[2]:.3%} > 1 code"
    assert np.abs(after.astype(int) - before).max() > 20  # the rain did something


def test_the_bounds_reject_other_rain():
    # what the bounds are for: the day rain with another seed, or without streaks, fails them
    renderer = Renderer(W, H, backend="cpu")
    want = read_golden(STREET_RAIN_DAY.name)
    other_seed = STREET_RAIN_DAY.png8(renderer.render(scenes.street(), STREET_RAIN_DAY.weather, seed=1))
    no_streaks = STREET_RAIN_DAY.png8(renderer.render(scenes.street(), Weather(rain_rate_mm_h=50.0, wind_m_s=(3.0, 0.0, 0.0), rain_streaks=False)))
    for image in (other_seed, no_streaks):
        for backend in BOUNDS:
            assert not within(compare(image, want), backend)


def snow_golden(demo) -> Path:
    """The golden of a snow demo: the street at 320 x 180, the photo at 160 px wide."""
    return GOLDEN / (f"{demo.name}_{PHOTO_W}w.png" if demo.name.startswith("photo") else f"{demo.name}_{W}x{H}.png")


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
@pytest.mark.parametrize("demo", SNOW_DEMOS, ids=[d.name for d in SNOW_DEMOS])
def test_the_snow_demos_match_their_goldens(demo, backend):
    # skyfall._demo.snow's frames under their covers, on both backends against the CPU's
    # goldens (SKYFALL_UPDATE_GOLDEN=1 with -k snow_demos writes these two alone, from the CPU).
    path = snow_golden(demo)
    bare, snowy = demo.render(PHOTO_W if demo.name.startswith("photo") else W, H, backend=backend)
    image = png8(snowy)
    if UPDATE and backend == "cpu":
        io.write_image(path, image)
    stats = compare(image, io.to_srgb8(io.read_image(path)))
    assert within(stats, backend), f"{demo.name} on {backend}: SSIM {stats[0]:.5f}, mean {stats[1]:.4f} codes, {stats[2]:.3%} > 1 code"
    # the snow whitened the picture where it lies
    assert png8(snowy).mean() > png8(bare).mean() + 5
