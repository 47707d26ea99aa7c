"""The windshield's golden image: the demo's in-car view (``skyfall._demo.windshield_still``:
the street in 10 mm/h rain through the "rain" preset's windshield a minute in, the wipers
mid-sweep), small, against a PNG made from the code on purpose, with the bounds of
``tests/test_golden.py`` (SSIM, mean |difference|, share of values more than one code off).

It lives in ``tests/data/golden/windshield/`` so that regenerating it rewrites no other golden:
``SKYFALL_UPDATE_GOLDEN=1 .venv/bin/python -m pytest tests/test_golden_windshield.py``. The GPU
backend renders the street and the whole windshield stage (the demo's f/8 lens defocuses the
drops: the GPU blurs them and draws the blades in the frame's own passes).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from numpy.typing import NDArray
from skimage.metrics import structural_similarity

from skyfall import Renderer, io
from skyfall._demo import windshield_still

GOLDEN = Path(__file__).parent / "data" / "golden" / "windshield"
UPDATE = os.environ.get("SKYFALL_UPDATE_GOLDEN") == "1"
W, H = 320, 180
NAME = f"windshield_{W}x{H}.png"
# (min SSIM, max mean |difference| in codes, max fraction of values > 1 code off), as test_golden.py
BOUNDS = {"cpu": (0.995, 0.25, 0.001), "gpu": (0.99, 0.25, 0.005)}


def render(backend: str) -> NDArray[np.uint8]:
    return io.to_srgb8(windshield_still(Renderer(W, H, backend=backend)).rgb)


@pytest.fixture(scope="module")
def golden() -> NDArray[np.uint8]:
    if UPDATE:
        GOLDEN.mkdir(parents=True, exist_ok=True)
        io.write_image(GOLDEN / NAME, render("cpu"))
    return io.to_srgb8(io.read_image(GOLDEN / NAME))


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_the_in_car_view_matches_its_golden(golden: NDArray[np.uint8], backend: str) -> None:
    got = render(backend)
    assert got.shape == golden.shape == (H, W, 3)
    ssim = float(structural_similarity(got, golden, data_range=255, channel_axis=-1))
    diff = np.abs(got.astype(np.int16) - golden)
    min_ssim, max_mean, max_off = BOUNDS[backend]
    assert ssim >= min_ssim and diff.mean() <= max_mean and np.mean(diff > 1) <= max_off, (ssim, diff.mean(), np.mean(diff > 1))


def test_the_golden_shows_drops_and_blades(golden: NDArray[np.uint8]) -> None:
    # against the same street and camera without the glass: the blades are where the golden is
    # much darker (a thin share of the frame), the drops change much of the rest a little
    from skyfall import Weather, scenes
    from skyfall._demo import WINDSHIELD_TIME_S, windshield_camera

    weather = Weather(rain_rate_mm_h=10.0, visibility_m=2000.0)
    plain = io.to_srgb8(Renderer(W, H, backend="cpu").render(scenes.street(), weather, camera=windshield_camera(), time_s=WINDSHIELD_TIME_S).rgb)
    diff = plain.astype(np.int16) - golden
    blades = (diff.min(axis=2) > 20).mean()
    assert 0.005 < blades < 0.1, blades
    assert (np.abs(diff).max(axis=2) > 2).mean() > 0.1
