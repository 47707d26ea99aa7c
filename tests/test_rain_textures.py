"""skyfall.rain.textures against analytic expectations, and its contract."""

from __future__ import annotations

import hashlib
import subprocess
import sys

import numpy as np
import pytest
from scipy import integrate

from skyfall import physics, rain

SEED_R = rain.SEED_RAIN_RATES_MM_H
SEED_D = rain.SEED_DIAMETERS_MM


def mp(d_mm: float, r: float) -> float:
    return 8000.0 * np.exp(-4.1 * r**-0.21 * d_mm)


def bin_moments(r: float, lo: float, hi: float) -> tuple[float, float, float]:
    """Expected drop count, E[D^2] and Var[D^2] (D in m) of a Marshall-Palmer bin, by quadrature."""
    n, _ = integrate.quad(mp, lo, hi, args=(r,), epsrel=1e-12)
    m2, _ = integrate.quad(lambda d: mp(d, r) * (d * 1e-3) ** 2, lo, hi, epsrel=1e-12)
    m4, _ = integrate.quad(lambda d: mp(d, r) * (d * 1e-3) ** 4, lo, hi, epsrel=1e-12)
    return n, m2 / n, m4 / n - (m2 / n) ** 2


def test_mean_opacity_matches_analytic_expectation():
    # Every streak adds alpha * D * L = (pi/4) (D / (v T)) * D * (v T) = pi D^2 / 4 of
    # opacity-area (m^2), the drop's cross-section, to the 1 m^2 texture (box filtering and
    # wrapping conserve it), so the expected mean opacity of a texture is
    # lambda * E[pi D^2 / 4] = integral of N(D) pi D^2 / 4 over the bin: independent of fall speed.
    # Tolerance: 4 standard deviations of the mean over seeds, from the drop-count rounding and
    # the spread of D^2 within the bin, plus 0.5 % for overlaps (1 - prod vs sum) and float32.
    seeds = 12
    tex = np.stack([rain.textures(SEED_R, SEED_D, size_px=64, seed=s) for s in range(seeds)])
    lo, hi = rain.diameter_bins(SEED_D)
    for i, r in enumerate(SEED_R):
        for j in range(len(SEED_D)):
            n, e_d2, var_d2 = bin_moments(r, lo[j], hi[j])
            expected = n * e_d2 * np.pi / 4
            frac = n - np.floor(n)
            sd_one = np.pi / 4 * np.sqrt(n * var_d2 + frac * (1 - frac) * e_d2**2)
            tol = 4 * sd_one / np.sqrt(seeds) + 0.005 * expected
            got = tex[:, i, j].mean(dtype=np.float64)
            assert abs(got - expected) <= tol, (r, SEED_D[j], got, expected, tol)


def test_long_exposures_wrap_and_conserve_opacity():
    # At T = 0.1 s streaks are 0.4-0.9 m long: most cross the bottom edge. Only wrapping to the
    # top keeps every streak's full area in the texture, and keeps rows statistically alike.
    r, d = 50.0, (0.5, 1.0, 1.5)
    seeds = 8
    tex = np.stack([rain.textures([r], d, size_px=128, exposure_s=0.1, seed=s)[0] for s in range(seeds)])
    lo, hi = rain.diameter_bins(d)
    for j in range(len(d)):
        n, e_d2, var_d2 = bin_moments(r, lo[j], hi[j])
        # (each streak carries the drop's cross-section pi D^2 / 4)
        area = np.pi / 4
        tol = area * (4 * np.sqrt(n * var_d2 + 0.25 * e_d2**2) / np.sqrt(seeds) + 0.01 * n * e_d2)
        assert abs(tex[:, j].mean(dtype=np.float64) - area * n * e_d2) <= tol
    rows = tex.mean(axis=(0, 1, 3), dtype=np.float64)
    top, bottom = rows[:16].mean(), rows[-16:].mean()
    assert abs(top - bottom) < 0.15 * rows.mean()


def test_streak_length_is_fall_speed_times_exposure():
    # One narrow bin of 2 mm drops at light rain: isolated streaks. The longest vertical run of
    # lit pixels (cyclic, a streak may wrap) is v(D) T in pixels, +/- the bin's spread and a pixel.
    size, t = 512, 1 / 30
    tex = rain.textures([2.0], [2.0], size_px=size, exposure_s=t, seed=3)[0, 0]
    lo, hi = rain.diameter_bins([2.0])
    shortest = physics.terminal_velocity(lo[0]) * t * size
    longest = physics.terminal_velocity(hi[0]) * t * size
    runs = []
    for col in (tex > 0).T:
        if col.any() and not col.all():
            c = np.roll(col, -int(np.argmin(col)))  # start at an empty pixel
            edges = np.flatnonzero(np.diff(np.concatenate([[0], c.astype(int), [0]])))
            runs.extend(edges[1::2] - edges[::2])
    assert runs, "no streaks drawn"
    assert shortest - 1 <= max(runs) <= longest + 2


def test_zero_rain_gives_exact_zeros():
    tex = rain.textures([0.0, 5.0], SEED_D, size_px=32)
    assert not tex[0].any()
    assert tex[1].any()


def test_output_contract():
    tex = rain.textures([1.0, 10.0], [1.0, 2.0, 3.0], size_px=48, seed=1)
    assert tex.shape == (2, 3, 48, 48) and tex.dtype == np.float32 and tex.flags.c_contiguous
    assert tex.min() >= 0.0 and tex.max() <= 1.0


def test_heavier_rain_is_more_opaque():
    tex = rain.textures([1.0, 5.0, 20.0, 100.0, 500.0], [1.0], size_px=64, seed=2)
    means = tex.mean(axis=(1, 2, 3))
    assert np.all(np.diff(means) > 0)


def _digest(tex: np.ndarray) -> str:
    return hashlib.sha256(tex.tobytes()).hexdigest()


def test_same_seed_same_bits_in_another_process():
    here = _digest(rain.textures(SEED_R, SEED_D, size_px=64, seed=42))
    code = (
        "import hashlib; from skyfall import rain; "
        "t = rain.textures(rain.SEED_RAIN_RATES_MM_H, rain.SEED_DIAMETERS_MM, size_px=64, seed=42); "
        "print(hashlib.sha256(t.tobytes()).hexdigest())"
    )
    there = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert here == there


def test_different_seeds_differ_and_a_texture_does_not_depend_on_its_neighbours():
    a = rain.textures([10.0], SEED_D, size_px=64, seed=0)
    b = rain.textures([10.0], SEED_D, size_px=64, seed=1)
    assert not np.array_equal(a, b)
    both = rain.textures([1.0, 10.0], SEED_D, size_px=64, seed=0)
    np.testing.assert_array_equal(both[1], a[0])


def test_bins_follow_the_documented_rule():
    lo, hi = rain.diameter_bins(SEED_D)
    np.testing.assert_allclose(lo, [0.9, 1.1, 1.3, 1.5, 1.7, 1.9])
    np.testing.assert_allclose(hi, [1.1, 1.3, 1.5, 1.7, 1.9, 2.1])
    np.testing.assert_allclose(rain.diameter_bins([3.0]), [[2.9], [3.1]])


@pytest.mark.parametrize(
    "kwargs,exc,match",
    [
        ({"diameters_mm": [1.2, 1.0]}, ValueError, "strictly increasing"),
        ({"diameters_mm": []}, ValueError, "at least one"),
        ({"diameters_mm": [0.0]}, ValueError, "diameters_mm"),
        ({"diameters_mm": [9.0]}, ValueError, "diameters_mm"),
        ({"rain_rates_mm_h": [float("nan")]}, ValueError, "rain_rates_mm_h"),
        ({"rain_rates_mm_h": [-1.0]}, ValueError, "rain_rates_mm_h"),
        ({"size_px": 8}, ValueError, "size_px"),
        ({"size_px": 64.0}, TypeError, "size_px"),
        ({"exposure_s": 0.0}, ValueError, "exposure_s"),
        ({"exposure_s": 0.5}, ValueError, "exposure_s"),
        ({"exposure_s": "fast"}, TypeError, "exposure_s"),
        ({"seed": -1}, ValueError, "seed"),
        ({"seed": 1.5}, TypeError, "seed"),
        ({"rain_rates_mm_h": [[1.0]]}, ValueError, "1-D"),
    ],
)
def test_bad_arguments(kwargs, exc, match):
    args = {"rain_rates_mm_h": [5.0], "diameters_mm": [1.0], "size_px": 32}
    args.update(kwargs)
    with pytest.raises(exc, match=match):
        rain.textures(args.pop("rain_rates_mm_h"), args.pop("diameters_mm"), **args)


def test_memory_budget_refused_before_allocating():
    # 64 x 64 textures of 16384^2 float32 would be 4 TiB: refused at once with the size.
    nbytes = 64 * 64 * 16384**2 * 4
    with pytest.raises(ValueError, match=rf"{nbytes} bytes \(4096\.00 GiB\).*budget"):
        rain.textures(np.ones(64), np.linspace(0.5, 7.0, 64), size_px=16384)
    assert rain.TEXTURE_BUDGET_BYTES == 2 * 1024**3
