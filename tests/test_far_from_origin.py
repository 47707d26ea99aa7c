"""Rain far from the world's origin (UTM-sized scenes) is the rain at the origin.

Drops are made in f64 world coordinates and kept relative to the camera, so a camera at
x = 5e6 m sees rain with the same statistics as one at the origin. With f32 world positions
(before) drops there snapped to a 0.5 m grid: 19 distinct x among 180k drops, and rain on
44 % of the pixels instead of all of them.
"""

from __future__ import annotations

import numpy as np
import pytest

import skyfall
from skyfall import Camera, PhotoScene, Renderer, Weather

W, H = 240, 135
SEEDS = range(8)
FAR = [(5e6, 1.6, 5e6), (-3e6, 101.6, 4e6)]


def _stats(position_m: tuple[float, float, float], seed: int, method: str) -> tuple[float, float, int]:
    cam = Camera(position_m, yaw_deg=20.0, pitch_deg=3.0, vertical_fov_deg=60.0, width=W, height=H)
    photo = PhotoScene(np.full((H, W, 3), 0.2, np.float32), np.full((H, W), 30.0, np.float32), camera=cam, encoding="linear")
    frame = Renderer(W, H, backend="cpu").render(photo, Weather(rain_rate_mm_h=40.0, rain_method=method), seed=seed, time_s=0.37)
    alpha = frame.layers["rain_alpha"]
    return float(alpha.mean()), float((alpha > 1e-3).mean()), frame.stats["rain_streaks"]


@pytest.mark.parametrize("method", ["drops", "billboards"])
@pytest.mark.parametrize("far", FAR)
def test_rain_far_from_the_origin_has_the_statistics_of_the_origin(method: str, far: tuple[float, float, float]) -> None:
    near = np.array([_stats((0.0, far[1], 0.0), s, method) for s in SEEDS])
    away = np.array([_stats(far, s, method) for s in SEEDS])
    for k, name in enumerate(["mean rain_alpha", "covered fraction", "streaks"]):
        a, b = near[:, k], away[:, k]
        se = np.sqrt(a.var(ddof=1) / len(a) + b.var(ddof=1) / len(b))
        # Two independent samples of the same rain: their means within 4 standard errors
        # (and 3 % of the mean, for the case of nearly no spread).
        assert abs(a.mean() - b.mean()) <= 4 * se + 0.03 * a.mean(), f"{name}: {a.mean()} at the origin, {b.mean()} at {far}"
    # Heavy rain covers nearly every pixel wherever the camera is (44 % at 5e6 m with f32 drops).
    assert away[:, 1].min() > 0.9 * near[:, 1].mean()


def test_drops_far_from_the_origin_are_not_on_a_grid() -> None:
    weather = Weather(rain_rate_mm_h=20.0, rain_near_m=3.0)
    here = skyfall.rain.drops((0.0, 1.6, 0.0), weather, seed=3)
    there = skyfall.rain.drops((5e6, 1.6, 5e6), weather, seed=3)
    assert there.position_m.dtype == np.float64
    # as many drops, as many distinct positions, and all within the region of the far centre
    assert abs(len(there.position_m) - len(here.position_m)) < 5 * np.sqrt(len(here.position_m))
    assert len(np.unique(there.position_m[:, 0])) > 0.99 * len(there.position_m)
    r = np.linalg.norm(there.position_m - np.array([5e6, 1.6, 5e6]), axis=1)
    assert r.max() <= 3.0 + 1e-6
