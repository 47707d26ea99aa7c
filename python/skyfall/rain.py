"""Precomputed rain-streak textures (Yoshida, Dobashi & Yamamoto, a fast method of drawing rain streaks for rainy scenery).

A rain texture F(R, D) shows a 1 m^3 cube of rain seen orthographically, perpendicular to
the fall direction, during one camera exposure: every drop of the diameter bin around D is
the streak it sweeps. Textures are stacked on billboards by the renderer so that the mix of
drop sizes follows Marshall-Palmer.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final, NamedTuple

import numpy as np
from numpy.typing import NDArray

from skyfall import _core
from skyfall._validate import float_array, integer, real
from skyfall.scenes import BoxScene, PhotoScene

if TYPE_CHECKING:
    from skyfall.weather import Weather

__all__ = [
    "Drops",
    "SEED_DIAMETERS_MM",
    "SEED_RAIN_RATES_MM_H",
    "TEXTURE_BUDGET_BYTES",
    "atlas",
    "diameter_bins",
    "drops",
    "read_atlas",
    "textures",
    "write_atlas",
]

SEED_RAIN_RATES_MM_H: Final = (1.0, 5.0, 10.0, 20.0)
"""The rain rates of Yoshida, Dobashi & Yamamoto's texture grid, mm/h."""
SEED_DIAMETERS_MM: Final = (1.0, 1.2, 1.4, 1.6, 1.8, 2.0)
"""The drop diameters of Yoshida, Dobashi & Yamamoto's texture grid, mm."""
TEXTURE_BUDGET_BYTES: Final[int] = _core.TEXTURE_BUDGET_BYTES
"""Largest result :func:`textures` allocates (2 GiB); larger requests raise ValueError first."""


def _vector(name: str, value: Any) -> NDArray[np.float64]:
    arr = float_array(name, value)
    if arr.ndim > 1:
        raise ValueError(f"{name} must be a scalar or 1-D sequence, got shape {arr.shape}")
    return np.ascontiguousarray(arr.reshape(-1))


def diameter_bins(diameters_mm: Sequence[float] | NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Diameter bins that texture diameters stand for.

    Parameters
    ----------
    diameters_mm : sequence of float
        Strictly increasing diameters, mm, each in (0, 8].

    Returns
    -------
    lower_mm, upper_mm : ndarray
        Bin edges, mm: midpoints between neighbouring diameters; the outer bins are
        symmetric about their diameter; a single diameter gets a 0.2 mm bin. Lower edges
        are clipped at 0.

    Examples
    --------
    >>> lower, upper = diameter_bins([1.0, 1.2, 1.4])
    >>> np.round(lower, 3), np.round(upper, 3)
    (array([0.9, 1.1, 1.3]), array([1.1, 1.3, 1.5]))
    """
    return _core.rain_diameter_bins(_vector("diameters_mm", diameters_mm))


def textures(
    rain_rates_mm_h: Sequence[float] | NDArray[np.float64] | float,
    diameters_mm: Sequence[float] | NDArray[np.float64] | float,
    *,
    size_px: int = 512,
    exposure_s: float = 1.0 / 30.0,
    seed: int = 0,
) -> NDArray[np.float32]:
    """Render rain textures for every (rain rate, diameter) pair.

    Parameters
    ----------
    rain_rates_mm_h : sequence of float
        Rain rates R, mm/h, each in [0, 500].
    diameters_mm : sequence of float
        Strictly increasing drop diameters D, mm, each in (0, 8]; each stands for the drops
        of its bin (see :func:`diameter_bins`).
    size_px : int
        Side of each square texture in pixels, [16, 16384]; the texture spans 1 m, so this
        is also pixels per metre.
    exposure_s : float
        Exposure time T, s, in [1e-6, 0.1] (a streak, v T, must fit in the 1 m texture).
    seed : int
        Seed in [0, 2^64); same inputs and seed give the same bits in any process.

    Returns
    -------
    ndarray of float32, shape (n_rates, n_diameters, size_px, size_px)
        Opacity in [0, 1]. Each drop of the bin in the 1 m^3 cube (count: the analytic
        Marshall-Palmer bin integral, fraction drawn at random; diameter: Marshall-Palmer
        within the bin; Beard 1976 fall speed at 20 degC, 1013.25 hPa) is a vertical streak
        of width D and length v T with opacity min(1, D / (v T)), box-filtered into pixels,
        combined as 1 - prod(1 - a). Rows grow downwards (drops fall to larger row
        indices); textures tile seamlessly in both directions.

    Raises
    ------
    ValueError
        For values out of range, or a result over :data:`TEXTURE_BUDGET_BYTES` (checked
        before anything is allocated).

    Notes
    -----
    Textures are rendered in parallel across (rate, diameter) pairs with the GIL released.
    The mean opacity's expectation over drop positions is exactly 1 - prod(1 - a_i D_i L_i)
    for the drawn drops (areas in m^2).

    Examples
    --------
    >>> tex = textures([10.0], [1.0, 2.0], size_px=64, seed=0)
    >>> tex.shape, tex.dtype
    ((1, 2, 64, 64), dtype('float32'))
    >>> bool(tex.min() >= 0.0 and tex.max() <= 1.0)
    True
    """
    rates = _vector("rain_rates_mm_h", rain_rates_mm_h)
    diams = _vector("diameters_mm", diameters_mm)
    size = integer("size_px", size_px, 16, 16384)
    exposure = real("exposure_s", exposure_s)
    s = integer("seed", seed, 0, 2**64 - 1)
    return _core.rain_textures(rates, diams, size, exposure, s)


def atlas(tex: NDArray[np.float32]) -> NDArray[np.float32]:
    """Lay textures out as one 2-D mosaic: rows are rain rates, columns diameters.

    Parameters
    ----------
    tex : ndarray, shape (n_rates, n_diameters, size, size)
        Output of :func:`textures`.

    Returns
    -------
    ndarray of float32, shape (n_rates * size, n_diameters * size)

    Examples
    --------
    >>> atlas(textures([1.0, 10.0], [1.0, 1.5, 2.0], size_px=32)).shape
    (64, 96)
    """
    arr = np.asarray(tex)
    if arr.ndim != 4 or arr.shape[2] != arr.shape[3]:
        raise ValueError(f"tex must have shape (n_rates, n_diameters, size, size), got {arr.shape}")
    nr, nd, s, _ = arr.shape
    return np.ascontiguousarray(arr.transpose(0, 2, 1, 3).reshape(nr * s, nd * s), dtype=np.float32)


def write_atlas(
    path: str | Path,
    tex: NDArray[np.float32],
    rain_rates_mm_h: Sequence[float],
    diameters_mm: Sequence[float],
) -> None:
    """Write textures as a one-channel float32 EXR mosaic through OpenImageIO.

    The rates and diameters are stored as metadata (``skyfall:rain_rates_mm_h``,
    ``skyfall:diameters_mm``) so :func:`read_atlas` restores everything bit-exactly.
    """
    from skyfall import io

    rates = _vector("rain_rates_mm_h", rain_rates_mm_h)
    diams = _vector("diameters_mm", diameters_mm)
    arr = np.asarray(tex)
    if arr.ndim != 4 or arr.shape[:2] != (rates.size, diams.size):
        raise ValueError(f"tex has shape {arr.shape}, expected ({rates.size}, {diams.size}, size, size)")
    meta = {
        "skyfall:rain_rates_mm_h": ",".join(repr(float(r)) for r in rates),
        "skyfall:diameters_mm": ",".join(repr(float(d)) for d in diams),
    }
    io.write_image(path, atlas(arr)[:, :, None], channel_names=["Y"], metadata=meta)


def read_atlas(path: str | Path) -> tuple[NDArray[np.float32], NDArray[np.float64], NDArray[np.float64]]:
    """Read an atlas written by :func:`write_atlas`.

    Returns
    -------
    tex : ndarray of float32, shape (n_rates, n_diameters, size, size)
    rain_rates_mm_h, diameters_mm : ndarray of float64
    """
    from skyfall import io

    image, meta = io.read_image_with_metadata(path)
    try:
        rates = np.array([float(v) for v in meta["skyfall:rain_rates_mm_h"].split(",")])
        diams = np.array([float(v) for v in meta["skyfall:diameters_mm"].split(",")])
    except KeyError as exc:
        raise ValueError(f"{path} is not a skyfall rain atlas (missing {exc.args[0]})") from None
    h, w = image.shape[:2]
    nr, nd = rates.size, diams.size
    s = h // nr
    if h != nr * s or w != nd * s:
        raise ValueError(f"{path}: image {w}x{h} does not fit {nr} x {nd} square textures")
    tex = image[:, :, 0].reshape(nr, s, nd, s).transpose(0, 2, 1, 3)
    return np.ascontiguousarray(tex, dtype=np.float32), rates, diams


class Drops(NamedTuple):
    """Drops of a rain region (see :func:`drops`)."""

    position_m: NDArray[np.float64]
    """(N, 3) world positions at the end of the exposure, m (float64: exact far from the
    origin too)."""
    velocity_m_s: NDArray[np.float32]
    """(N, 3) velocities, m/s."""
    diameter_m: NDArray[np.float32]
    """(N,) diameters, m."""
    id: NDArray[np.int64]
    """(N, 5) stable identities: voxel (ix, iy, iz), diameter bin, index."""


def drops(
    center_m: Sequence[float],
    weather: Weather,
    *,
    time_s: float = 0.0,
    seed: int = 0,
    ground: bool = True,
    scene: BoxScene | PhotoScene | None = None,
) -> Drops:
    """The raindrops a ``rain_method="drops"`` frame draws: every drop within
    ``weather.rain_near_m`` of ``center_m``.

    Drops live in 1 m world voxels at integer coordinates; each voxel's drops come from a
    generator seeded by (seed, voxel, diameter bin), with Marshall-Palmer counts and sizes and
    Beard fall speeds, and move with (wind_x, -v, wind_z), wrapping inside their voxel. So
    the same seed gives the same drops for any camera, frame or process: ground truth for
    stereo and video. With ``ground`` no drops lie below y = 0. These are always the
    individual drops: the default billboards draw each voxel's rain texture instead, facing the
    camera, with the same counts and sizes per voxel. With ``weather.rain_far_m`` a frame draws
    only the drops within it (horizontally) one by one and the rest as layers, whose streaks
    are other, random drops: these are still all of the region's drops.

    Parameters
    ----------
    center_m : sequence of 3 float
        Region centre (the camera position), m.
    weather : Weather
        Rain rate, diameters, wind and region radius.
    time_s : float
        Time, s.
    seed : int
        Seed in [0, 2^64).
    ground : bool
        Whether the ground plane y = 0 bounds the rain.
    scene : BoxScene or PhotoScene, optional
        With ``weather.rain_sheltered``, its boxes (or a photo's ``occluders``) keep the rain
        off what they cover, as in the frames.
    """
    c = float_array("center_m", center_m).reshape(-1)
    if c.size != 3 or not np.all(np.isfinite(c)):
        raise ValueError(f"center_m must be 3 finite numbers (m), got {center_m!r}")
    s = integer("seed", seed, 0, 2**64 - 1)
    from skyfall.weather import Weather  # (a module-level import would be circular)

    if not isinstance(weather, Weather):
        raise TypeError(f"weather must be a skyfall.Weather, got {type(weather).__name__}")
    t = real("time_s", time_s)
    shelter = None
    if scene is not None and weather.rain_sheltered:
        if isinstance(scene, BoxScene):
            shelter = np.ascontiguousarray(scene.boxes, dtype=np.float32)
        elif isinstance(scene, PhotoScene):
            shelter = scene.occluders
        else:
            raise TypeError(f"scene must be a BoxScene, a PhotoScene or None, got {type(scene).__name__}")
    # The core makes the drops from the weather itself, always drop by drop.
    pos, vel, diam, ids = _core.rain_drops([float(v) for v in c], weather, time_s=t, seed=s, ground=bool(ground), shelter=shelter)
    return Drops(pos, vel, diam, ids)
