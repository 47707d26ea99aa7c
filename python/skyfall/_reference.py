"""Published data and independent references bundled with skyfall, private: for the demo's plots,
the tests and the benches (tests keep their own copies of measured data)."""

from __future__ import annotations

from importlib import resources

import numpy as np
from numpy.typing import NDArray

__all__ = ["EARTH_RADIUS_M", "canyon_illuminance", "gunn_kinzer_1949", "path_to_cloud_base_m"]

EARTH_RADIUS_M = 6.371e6
"""The Earth's mean radius, m."""


def gunn_kinzer_1949() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Measured raindrop fall speeds in still air (Gunn & Kinzer 1949, J. Meteor. 6, Table 2).

    Returns
    -------
    diameter_mm, fall_speed_m_s : ndarray
        35 drops, 0.078-5.8 mm, at about 1013 hPa, 20 degC, 50 % RH.

    Examples
    --------
    >>> d, v = gunn_kinzer_1949()
    >>> len(d), float(d[0]), float(d[-1]), float(v[-1])  # mm, mm, m/s
    (35, 0.078, 5.8, 9.17)
    """
    text = resources.files("skyfall").joinpath("data/gunn_kinzer_1949.csv").read_text()
    rows = [line.split(",") for line in text.splitlines() if line and not line.startswith("#")][1:]
    return np.array([float(r[0]) for r in rows]), np.array([float(r[1]) for r in rows])


def path_to_cloud_base_m(sin_elevation: NDArray[np.float64] | float, ceiling_m: float) -> NDArray[np.float64]:
    """The path from an eye to a cloud base ``ceiling_m`` above it along a ray of elevation
    sin ``sin_elevation``, the base a shell over the Earth's sphere:
    sqrt((R + h)^2 - R^2 cos^2 g) - R sin g, in float64, written directly (an independent
    reference for the core's ``haze::path_to_ceiling_m``, which is f32 and rearranged).

    Examples
    --------
    >>> round(float(path_to_cloud_base_m(1.0, 800.0)), 6), round(float(path_to_cloud_base_m(0.0, 800.0)))
    (800.0, 100967)
    """
    s = np.asarray(sin_elevation, dtype=np.float64)
    r = EARTH_RADIUS_M
    path: NDArray[np.float64] = np.sqrt((r + ceiling_m) ** 2 - r**2 * (1.0 - s**2)) - r * s
    return path


def canyon_illuminance(
    x_m: float, height_m: float, width_m: float, *, extinction_per_m: float = 0.0, cloud_base_m: float = 1000.0
) -> float:
    """Horizontal illuminance on the floor of an infinitely long street canyon, over E.

    An independent reference for :func:`skyfall.sky.horizontal_illuminance` (adaptive scipy
    quadrature, not skyfall's sampler): the CIE standard overcast sky,
    L = Lz (1 + 2 sin g) / 3, seen through the rain as L tau + Lz / 3 (1 - tau) (attenuated
    by tau = exp(-sigma d(g)) along the path d to a cloud base H up on the Earth's sphere,
    sqrt((R + H)^2 - (R cos g)^2) - R sin g, plus the light scattered into the path, which saturates at
    the cloud base's horizon luminance Lz / 3: :mod:`skyfall.sky`), over the directions
    that clear walls of height ``height_m`` at x = +-width_m / 2 (the canyon runs along Z),
    seen from the point (``x_m``, 0, z); divided by the same integral over the open sky.
    Needs scipy.
    """
    try:
        from scipy import integrate  # type: ignore[import-untyped]
    except ImportError as exc:  # pragma: no cover - scipy is a test and bench dependency
        raise ImportError("skyfall._reference.canyon_illuminance needs scipy: pip install scipy") from exc

    def radiance(g: float) -> float:
        tau = float(np.exp(-extinction_per_m * path_to_cloud_base_m(np.sin(g), cloud_base_m))) if extinction_per_m > 0 else 1.0
        return float(((1 + 2 * np.sin(g)) / 3 * tau + (1 - tau) / 3) * np.sin(g) * np.cos(g))

    def over_elevation(phi: float, h: float) -> float:
        sx = np.sin(phi)  # horizontal direction (sin phi, 0, -cos phi)
        if abs(sx) < 1e-12 or h <= 0:
            g0 = 0.0
        else:
            dist = (width_m / 2 - x_m) / sx if sx > 0 else (-width_m / 2 - x_m) / sx
            g0 = float(np.arctan2(h, dist))
        return float(integrate.quad(radiance, g0, np.pi / 2, epsabs=1e-12, epsrel=1e-10)[0])

    def total(h: float) -> float:
        pts = [np.pi / 2, np.pi, 3 * np.pi / 2]
        return float(integrate.quad(over_elevation, 0, 2 * np.pi, args=(h,), points=pts, limit=400, epsrel=1e-9)[0])

    return total(height_m) / total(0.0)
