"""Sky light (Yamamoto & Tadamura): CIE skies, sky illuminance with occlusion, the ambient-light map.

Coordinates: world metres, +Y up; azimuth is measured from -Z (north, where a default camera
looks) towards +X (east). Every sky is normalised so that the open, unobstructed ground
receives ``horizontal_illuminance_lux`` (what a lux meter reads, rain included). Seen through
the rain the sky is the cloud base attenuated plus the light the drops scatter into the path,
L = L_c tau + A (1 - tau), tau = exp(-sigma d), d the path down from the cloud base H (H /
sin(elevation) overhead, sqrt(2 R H) along the horizon over the Earth's curve); the
in-scattered light saturates at the airlight A, the cloud base's horizon luminance
(``Weather.airlight_relative``). Rain so flattens the sky towards the uniform A = E/pi: the
low sky brightens, the high sky dims, and a street canyon's floor, which sees mostly the high
sky, gets a smaller share of E (under an awning, which hides the high sky, a larger one).

Illuminance is the integral of L tau H cos(theta) over the hemisphere, H = 1 where the sky is
visible. ``samples`` azimuths are sampled (midpoint rule); along each, the boxes' hidden
elevations are found exactly and the sky is integrated over the visible ones from tables
precomputed per sky (512 elevation steps, 4-point Gauss-Legendre each). The error so falls
as 1/samples^2 even where occluders cut the sky (``benches/results/sky.md`` tabulates it).

Colour: a sky with a sun (CIE types 6-15) has the colour of Hosek & Wilkie's clear-sky model
(*An Analytic Model for Full Spectral Sky-Dome Radiance*, 2012, RGB form) at a turbidity per
type, with the CIE luminance kept (:func:`luminance_rgb`); its sun has the colour of a 5778 K
black body through Rayleigh and aerosol extinction (:func:`colours`). The overcast skies
(``"overcast"``, 1-5) stay neutral. Colours are linear Rec. 709 (sRGB primaries, D65 white).

Occluders: the boxes of a :class:`~skyfall.scenes.BoxScene`, or the ``occluders`` a
:class:`~skyfall.PhotoScene` was given (a photo's depth map is not turned into geometry:
a depth map seen from one viewpoint says nothing of what hangs above a drop behind it).
"""

from __future__ import annotations

import math
import threading
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from skyfall import _core
from skyfall._validate import all_in_range, float_array, in_range, integer_in_range, real
from skyfall.scenes import BoxScene, PhotoScene
from skyfall.weather import Weather

__all__ = [
    "CHANNELS",
    "SKY_TYPES",
    "AmbientLightMap",
    "ambient_light_map",
    "SkyColours",
    "cloud_base_m",
    "colours",
    "expect_sweeps",
    "horizontal_illuminance",
    "luminance",
    "luminance_rgb",
]

CHANNELS = ("up", "+x", "-x", "+z", "-z")
"""The normals an ambient map holds illuminance for: a horizontal surface facing up, and
vertical surfaces facing +X, -X, +Z, -Z (every face of a box scene is one of them)."""

SKY_TYPES: dict[int | str, str] = {
    "overcast": "CIE standard overcast sky (Moon & Spencer), as Yamamoto & Tadamura use it",
    1: "Overcast, steep gradation, azimuthal uniformity",
    2: "Overcast, steep gradation, slight brightening towards sun",
    3: "Overcast, gentle gradation, azimuthal uniformity",
    4: "Overcast, gentle gradation, slight brightening towards sun",
    5: "Uniform luminance",
    6: "Partly cloudy, no gradation, slight brightening towards sun",
    7: "Partly cloudy, no gradation, brighter circumsolar region",
    8: "Partly cloudy, no gradation, distinct solar corona",
    9: "Partly cloudy, obscured sun",
    10: "Partly cloudy, brighter circumsolar region",
    11: "White-blue sky, distinct solar corona",
    12: "CIE standard clear sky, low turbidity",
    13: "CIE standard clear sky, polluted atmosphere",
    14: "Cloudless turbid sky, broad solar corona",
    15: "White-blue turbid sky, broad solar corona",
}
"""The skies ``sky=`` accepts (CIE S 011/E:2003 general skies 1-15)."""

DEFAULT_SAMPLES = 256
"""Azimuths for :func:`horizontal_illuminance`."""
MAP_SAMPLES = 64
"""Azimuths per node for :func:`ambient_light_map` and the renderer's map."""


def cloud_base_m(rain_rate_mm_h: float) -> float:
    """Cloud base height for a rain rate R in [0, 500] mm/h, m: 1500 - 250 ln(1 + R / (1 mm/h)),
    clamped to [300, 1500] m.

    Yamamoto & Tadamura make the cloud height a function of the rain rate (after Shibata 1999) without
    printing the relation; this is skyfall's own smooth stand-in: 1500 m dry, 900 m at
    10 mm/h, 520 m at 50 mm/h, 350 m at 100 mm/h. Override it with ``Weather.cloud_base_m``.
    """
    return float(_core.cloud_base_m(in_range("rain_rate_mm_h", rain_rate_mm_h)))


def _weather(
    weather: Weather | None,
    sky: str | int | None,
    horizontal_illuminance_lux: float | None,
    sun_elevation_deg: float | None,
    sun_azimuth_deg: float | None,
) -> Weather:
    """The sky settings as a Weather: the given one, or one built from the keywords."""
    given = {
        "sky": sky,
        "horizontal_illuminance_lux": horizontal_illuminance_lux,
        "sun_elevation_deg": sun_elevation_deg,
        "sun_azimuth_deg": sun_azimuth_deg,
    }
    if weather is not None:
        if not isinstance(weather, Weather):
            raise TypeError(f"weather must be a skyfall.Weather, got {type(weather).__name__}")
        clash = [k for k, v in given.items() if v is not None]
        if clash:
            raise ValueError(f"give the sky either through weather or through keywords, not both ({', '.join(clash)})")
        return weather
    e = 10000.0
    if horizontal_illuminance_lux is not None:  # checked under its own name (Weather's is sky_illuminance_lux)
        e = real("horizontal_illuminance_lux", horizontal_illuminance_lux)
        try:
            _core.check_range("sky_illuminance_lux", e, None)
        except ValueError as err:
            raise ValueError("horizontal_illuminance_lux" + str(err).removeprefix("sky_illuminance_lux")) from None
    return Weather(
        sky=sky if sky is not None else "overcast",
        sky_illuminance_lux=e,
        sun_elevation_deg=sun_elevation_deg,
        sun_azimuth_deg=sun_azimuth_deg,
    )


def _directions(elevation_deg: Any, azimuth_deg: Any) -> tuple[NDArray[np.float32], tuple[int, ...]]:
    el = float_array("elevation_deg", elevation_deg)
    az = float_array("azimuth_deg", azimuth_deg)
    try:
        el, az = np.broadcast_arrays(el, az)
    except ValueError:
        raise ValueError(f"shapes do not broadcast: elevation_deg{el.shape}, azimuth_deg{az.shape}") from None
    all_in_range("elevation_deg", el)
    all_in_range("azimuth_deg", az)
    e, a = np.radians(el), np.radians(az)
    dirs = np.stack([np.sin(a) * np.cos(e), np.sin(e), -np.cos(a) * np.cos(e)], axis=-1)
    return np.ascontiguousarray(dirs.reshape(-1, 3), dtype=np.float32), el.shape


def luminance(
    elevation_deg: Any,
    azimuth_deg: Any,
    *,
    sky: str | int | None = None,
    horizontal_illuminance_lux: float | None = None,
    sun_elevation_deg: float | None = None,
    sun_azimuth_deg: float | None = None,
    weather: Weather | None = None,
) -> Any:
    """Sky luminance seen from the ground, cd/m^2.

    Parameters
    ----------
    elevation_deg, azimuth_deg : float or array_like
        Direction: elevation above the horizon in [-90, 90] deg (0 below the horizon) and
        azimuth from -Z towards +X, deg. Broadcast together.
    sky : "overcast" or int, optional
        ``"overcast"`` (default): L/Lz = (1 + 2 sin(elevation)) / 3 with Lz = 9E / (7 pi);
        1-15: the CIE general skies (:data:`SKY_TYPES`).
    horizontal_illuminance_lux : float, optional
        E, lux (default 10000): the sky is scaled so the open ground receives it.
    sun_elevation_deg, sun_azimuth_deg : float, optional
        The sun, required by the CIE types that depend on it (2, 4, 6-15).
    weather : Weather, optional
        Take the sky, E, sun and the rain (the sky seen through it, see the module docstring)
        from a weather instead of the keywords. Without it there is no rain: tau = 1.

    Returns
    -------
    float or ndarray
        Luminance, cd/m^2, with the broadcast shape of the directions.
    """
    w = _weather(weather, sky, horizontal_illuminance_lux, sun_elevation_deg, sun_azimuth_deg)
    dirs, shape = _directions(elevation_deg, azimuth_deg)
    rel = w.sky_model().luminance_relative(dirs, received=True) * w.luminance_scale_cd_m2
    return float(rel[0]) if shape == () else rel.reshape(shape)


def luminance_rgb(
    elevation_deg: Any,
    azimuth_deg: Any,
    *,
    sky: str | int | None = None,
    horizontal_illuminance_lux: float | None = None,
    sun_elevation_deg: float | None = None,
    sun_azimuth_deg: float | None = None,
    weather: Weather | None = None,
) -> NDArray[np.float64]:
    """The sky seen from the ground in colour: linear Rec. 709 RGB, cd/m^2 per channel.

    The CIE luminance of :func:`luminance` times the sky's chroma there (Hosek & Wilkie's RGB
    model divided by its own luminance), so ``0.2126 R + 0.7152 G + 0.0722 B`` is
    :func:`luminance`. Through rain the cloud base's colour is mixed with the airlight's (the
    horizon's colour). Overcast skies give R = G = B.

    Parameters
    ----------
    elevation_deg, azimuth_deg, sky, horizontal_illuminance_lux, sun_elevation_deg, sun_azimuth_deg, weather
        As for :func:`luminance`.

    Returns
    -------
    ndarray
        float64, the broadcast shape of the directions plus a last axis of 3 (R, G, B).

    Examples
    --------
    >>> from skyfall import sky
    >>> r, g, b = sky.luminance_rgb(90.0, 0.0, sky=12, sun_elevation_deg=60.0, sun_azimuth_deg=180.0)
    >>> bool(b > g > r)
    True
    """
    w = _weather(weather, sky, horizontal_illuminance_lux, sun_elevation_deg, sun_azimuth_deg)
    dirs, shape = _directions(elevation_deg, azimuth_deg)
    rel = w.sky_model().rgb_relative(dirs, received=True) * w.luminance_scale_cd_m2
    return rel.reshape((*shape, 3))


@dataclass(frozen=True)
class SkyColours:
    """The colours of a sky's light: linear Rec. 709 RGB of luminance 1 each, (1, 1, 1) under
    an overcast sky.

    Attributes
    ----------
    horizon : tuple of float
        The horizon's colour (its luminance-weighted mean over the azimuths): the colour the
        haze's airlight takes, so distance fades to it.
    sky_light : tuple of float
        The colour of the light the open sky gives a horizontal surface, through the rain: the
        renderer tints the ambient-light map with it (shadows under a clear sky are blue).
    sun : tuple of float
        The colour of the sun's direct light (white-yellow high, orange near the horizon).
    """

    horizon: tuple[float, float, float]
    sky_light: tuple[float, float, float]
    sun: tuple[float, float, float]


def colours(
    *,
    sky: str | int | None = None,
    sun_elevation_deg: float | None = None,
    sun_azimuth_deg: float | None = None,
    weather: Weather | None = None,
) -> SkyColours:
    """The colours of a sky's horizon, of its light on the ground and of its sun.

    Parameters
    ----------
    sky, sun_elevation_deg, sun_azimuth_deg, weather
        As for :func:`luminance`.

    Returns
    -------
    SkyColours

    Examples
    --------
    >>> from skyfall import sky
    >>> c = sky.colours(sky=12, sun_elevation_deg=5.0, sun_azimuth_deg=180.0)
    >>> r, g, b = c.sun
    >>> bool(r > g > b)
    True
    """
    w = _weather(weather, sky, None, sun_elevation_deg, sun_azimuth_deg)
    horizon, light, sun = w.sky_model().colours

    def rgb(c: list[float]) -> tuple[float, float, float]:
        return (float(c[0]), float(c[1]), float(c[2]))

    return SkyColours(horizon=rgb(horizon), sky_light=rgb(light), sun=rgb(sun))


def _occluders(scene: BoxScene | PhotoScene | None) -> NDArray[np.float32]:
    if scene is None:
        return np.zeros((0, 9), dtype=np.float32)
    if isinstance(scene, BoxScene):
        return np.ascontiguousarray(scene.boxes, dtype=np.float32)
    if isinstance(scene, PhotoScene):
        return np.ascontiguousarray(scene.occluders, dtype=np.float32)
    raise TypeError(f"scene must be a BoxScene, a PhotoScene or None, got {type(scene).__name__}")


def _points(points_m: Any) -> NDArray[np.float32]:
    p = float_array("points_m", points_m)
    if p.ndim == 1 and p.size == 3:
        p = p.reshape(1, 3)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"points_m must have shape (N, 3), got {p.shape}")
    if not np.all(np.isfinite(p)) or np.any(np.abs(p) > np.finfo(np.float32).max):
        raise ValueError("points_m must be finite (and within float32 range)")
    return np.ascontiguousarray(p, dtype=np.float32)


def horizontal_illuminance(
    points_m: Any,
    scene: BoxScene | PhotoScene | None = None,
    *,
    sky: str | int | None = None,
    horizontal_illuminance_lux: float | None = None,
    sun_elevation_deg: float | None = None,
    sun_azimuth_deg: float | None = None,
    weather: Weather | None = None,
    samples: int = DEFAULT_SAMPLES,
    normal: str = "up",
) -> NDArray[np.float64]:
    """Sky illuminance at points, with the scene's occluders, lux.

    E(P) = integral over the hemisphere of L(w) tau(w) H(P, w) max(0, n.w) dw, H = 0 where a
    box hides the sky. The ground never hides the upper hemisphere.

    Parameters
    ----------
    points_m : array_like, shape (N, 3) or (3,)
        Points, m.
    scene : BoxScene or PhotoScene, optional
        Occluders: a box scene's boxes, a photo scene's ``occluders``; None: the open sky.
    sky, horizontal_illuminance_lux, sun_elevation_deg, sun_azimuth_deg, weather
        As for :func:`luminance`.
    samples : int
        Azimuths sampled, in [4, 65536] (default 256); the elevation integral along each is
        exact for the boxes.
    normal : {"up", "+x", "-x", "+z", "-z"}
        The surface's normal: "up" (default) is the horizontal illuminance of Yamamoto & Tadamura.

    Returns
    -------
    ndarray of float64, shape (N,)
        Illuminance, lux.
    """
    w = _weather(weather, sky, horizontal_illuminance_lux, sun_elevation_deg, sun_azimuth_deg)
    if normal not in CHANNELS:
        raise ValueError(f"normal = {normal!r} must be one of {CHANNELS}")
    n = integer_in_range("samples", samples)
    rel = w.sky_model().illuminance(_points(points_m), _occluders(scene), samples=n)
    return rel[:, CHANNELS.index(normal)].astype(np.float64) * w.sky_illuminance_lux


@dataclass(frozen=True)
class AmbientLightMap:
    """Sky illuminance on a uniform grid, interpolated trilinearly (Yamamoto & Tadamura section 4.3).

    Nodes inside boxes (``solid``) are left out of the interpolation: a point reads the open
    corners of its cell (weights renormalised), so beneath a thin awning it reads the nodes
    below it, on a wall those in front of it. (Solid nodes are filled from their open
    neighbours for the rare cell whose corners are all solid.) Points outside the grid take
    the nearest boundary value.

    Attributes
    ----------
    grid : ndarray of float32, shape (nx, ny, nz, 5)
        Illuminance at the nodes, lux, on the :data:`CHANNELS` normals; node (i, j, k) sits at
        ``origin_m + spacing_m * (i, j, k)``.
    origin_m : ndarray of float64, shape (3,)
        Position of node (0, 0, 0), m.
    spacing_m : float
        Node spacing, m.
    solid : ndarray of bool, shape (nx, ny, nz)
        Nodes inside a box.
    illuminance_lux : float
        E, the open ground's illuminance the values are scaled by.
    """

    grid: NDArray[np.float32]
    origin_m: NDArray[np.float64]
    spacing_m: float
    solid: NDArray[np.bool_]
    illuminance_lux: float
    core: _core.AmbientLightMap

    def sample(self, points_m: Any, normal: str = "up") -> NDArray[np.float64]:
        """Trilinear illuminance at points (N, 3), lux, on ``normal`` (one of :data:`CHANNELS`)."""
        if normal not in CHANNELS:
            raise ValueError(f"normal = {normal!r} must be one of {CHANNELS}")
        rel = self.core.sample(_points(points_m))
        return rel[:, CHANNELS.index(normal)].astype(np.float64) * self.illuminance_lux


_cache: OrderedDict[tuple[Any, ...], _core.AmbientLightMap] = OrderedDict()
_cache_lock = threading.Lock()
_CACHE_SIZE = 8
# What the boxes fix of a map (_core.AmbientHorizon: each node's visible sky per azimuth, and
# after the first overcast sky each node's weights for such skies), per (geometry, bounds,
# spacing, samples): a map under a new sky (another rain rate, visibility, sky type or sun) is
# then lit from it, bit for bit the map built from scratch, at a fraction of the cost (an
# overcast sky 4 ms on the bundled street, a sky with a sun 14 ms). Two kept (the bundled
# street's is 32 MB at 1 m and 64 azimuths, 88 MB with its weights).
_horizons: OrderedDict[tuple[Any, ...], _core.AmbientHorizon | None] = OrderedDict()
_geometries: OrderedDict[tuple[Any, ...], None] = OrderedDict()  # geometries with a map built
_HORIZONS = 2


_sweeping = False  # expect_sweeps(): every geometry's first sky lit from its horizon


def expect_sweeps(on: bool = True) -> None:
    """Light the first sky over each scene from the scene's horizon, in this process.

    A box scene's ambient map under its first sky is built directly (324 ms on the bundled
    street); a second sky over the same scene finds the scene's horizon (what its boxes hide,
    about 260 ms) and lights every later sky from it (about 5 ms overcast, 14 ms with a sun). A
    process that will render many weathers over a scene (a parameter sweep, a dataset worker:
    ``skyfall dataset --scene`` turns this on in each worker) saves the first direct build by
    finding the horizon at once. The maps are the same bits either way; the horizon costs memory
    (88 MB for the street with its overcast weights).

    Parameters
    ----------
    on : bool
        True (default) from now on; False restores the default (the first sky built directly).
    """
    global _sweeping
    _sweeping = bool(on)


def _horizon(
    boxes: NDArray[np.float32], lo: NDArray[np.float64], hi: NDArray[np.float64], spacing: float, samples: int, spacing_name: str
) -> _core.AmbientHorizon | None:
    """The geometry's horizon, found once per (geometry, bounds, spacing, samples); None for a
    grid too large to keep one (its maps are built directly)."""
    key = (boxes.tobytes(), boxes.shape, tuple(lo), tuple(hi), spacing, samples)
    with _cache_lock:
        if key in _horizons:
            _horizons.move_to_end(key)
            return _horizons[key]
    try:
        found: _core.AmbientHorizon | None = _core.ambient_horizon(
            boxes, bounds_min_m=list(lo), bounds_max_m=list(hi), spacing_m=spacing, samples=samples, spacing_name=spacing_name
        )
    except MemoryError:
        found = None  # past HORIZON_MAX_PAIRS, or no memory for it: the map is built directly
    with _cache_lock:
        _horizons[key] = found
        while len(_horizons) > _HORIZONS:
            _horizons.popitem(last=False)
    return found


def cached_core_map(
    boxes: NDArray[np.float32],
    w: Weather,
    lo: NDArray[np.float64],
    hi: NDArray[np.float64],
    spacing: float,
    samples: int,
    spacing_name: str = "spacing_m",
    clouds: _core.CloudField | None = None,
    eye_m: Any = None,
) -> _core.AmbientLightMap:
    """The core map, built once per (geometry, sky, bounds, spacing, samples, clouds) in a
    process; errors name the spacing ``spacing_name`` (the caller's own parameter). A map under
    a new sky over a geometry seen before is lit from the geometry's horizon, found at the
    second sky (the same bits as a direct build). ``clouds`` (a frame's cloud field) put their
    dome, seen from ``eye_m``, in the sky: what they hide of it and the light they send down
    (``_core.CloudDome``)."""
    model = w.sky_model()
    sky_key = (w.sky, w.sun_elevation_deg, w.sun_azimuth_deg, w.extinction_per_m, w.cloud_base_height_m)
    eye = None if clouds is None else tuple(float(v) for v in np.asarray(eye_m, dtype=np.float64).reshape(3))
    key = (boxes.tobytes(), boxes.shape, sky_key, tuple(lo), tuple(hi), spacing, samples, clouds, eye)
    with _cache_lock:
        if key in _cache:
            _cache.move_to_end(key)
            return _cache[key]
    # The first sky over a geometry builds its map directly; a second one (a sweep) finds the
    # geometry's horizon and lights every later sky from it; after expect_sweeps() the first
    # does.
    geometry = (boxes.tobytes(), boxes.shape, tuple(lo), tuple(hi), spacing, samples)
    with _cache_lock:
        swept = _sweeping or geometry in _geometries
        _geometries[geometry] = None
        while len(_geometries) > _CACHE_SIZE:
            _geometries.popitem(last=False)
    horizon = _horizon(boxes, lo, hi, spacing, samples, spacing_name) if swept and len(boxes) else None
    if eye is None:
        dome = None
    else:
        from skyfall.clouds import _dome_of

        dome = _dome_of(clouds, w, eye)
    if horizon is not None:
        built = model.light_map(horizon, dome=dome)
    else:
        built = model.ambient_map(
            boxes,
            bounds_min_m=list(lo),
            bounds_max_m=list(hi),
            spacing_m=spacing,
            samples=samples,
            spacing_name=spacing_name,
            dome=dome,
        )
    with _cache_lock:
        _cache[key] = built
        while len(_cache) > _CACHE_SIZE:
            _cache.popitem(last=False)
    return built


CAMERA_BOUNDS_STEP_M: Final = 8.0
"""In a box scene, the cube around the camera that a frame's map must cover is widened outwards
to multiples of this (a whole number of spacings, at least one), so cameras a few metres apart
(a dataset's jittered street, a clip's moving camera) share one map extent, and with it the
scene's cached horizon and maps: before, each jittered camera made a new map extent and its map
from scratch (``benches/results/sweeps.md``). The nodes stay on the scene's lattice, so frames
keep their bits."""


def default_bounds(
    scene: BoxScene | PhotoScene | None, spacing_m: float, around_m: Any = None, radius_m: float = 0.0
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The map's default extent: a box scene's boxes, from the ground (y = 0) to a spacing above
    the tallest roof, plus a ``radius_m`` cube around ``around_m`` (a camera's rain region;
    for a box scene widened outwards to multiples of :data:`CAMERA_BOUNDS_STEP_M`). A photo
    scene's occluders only count within that cube: its map serves the drops (and stays as small
    as they need: a photo's camera does not move)."""
    boxes = _occluders(scene).astype(np.float64)
    corners = [boxes[:, 0:3], boxes[:, 3:6]] if not isinstance(scene, PhotoScene) or around_m is None else []
    if around_m is not None:
        c = np.asarray(around_m, dtype=np.float64).reshape(1, 3)
        lo_c, hi_c = c - radius_m, c + radius_m
        if isinstance(scene, BoxScene):
            step = spacing_m * math.ceil(CAMERA_BOUNDS_STEP_M / spacing_m) if spacing_m > 0 else CAMERA_BOUNDS_STEP_M
            lo_c, hi_c = np.floor(lo_c / step) * step, np.ceil(hi_c / step) * step
        corners += [lo_c, hi_c]
    pts = np.concatenate(corners, axis=0) if corners else np.zeros((0, 3))
    if pts.size == 0:
        return np.zeros(3), np.zeros(3)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    if isinstance(scene, BoxScene) and scene.ground:
        lo[1] = max(lo[1], 0.0)
        hi[1] = max(hi[1], lo[1])
    if boxes.size and not isinstance(scene, PhotoScene):
        hi[1] += spacing_m
    return lo, hi


def ambient_light_map(
    scene: BoxScene | PhotoScene | None = None,
    *,
    spacing_m: float = 1.0,
    bounds: Any = None,
    sky: str | int | None = None,
    horizontal_illuminance_lux: float | None = None,
    sun_elevation_deg: float | None = None,
    sun_azimuth_deg: float | None = None,
    weather: Weather | None = None,
    samples: int = MAP_SAMPLES,
) -> AmbientLightMap:
    """Build (or fetch from the per-process cache) the ambient-light map of a scene.

    Parameters
    ----------
    scene : BoxScene or PhotoScene, optional
        The occluders (see :func:`horizontal_illuminance`). A scene without occluders gets a
        single-node map: the open sky everywhere.
    spacing_m : float
        Node spacing, m, in [0.05, 100].
    bounds : array_like, shape (2, 3), optional
        Min and max corners, m. Default: the boxes' extent from the ground to a spacing above
        the tallest roof.
    sky, horizontal_illuminance_lux, sun_elevation_deg, sun_azimuth_deg, weather
        As for :func:`luminance`.
    samples : int
        Azimuths per node, in [4, 65536] (default 64).

    Returns
    -------
    AmbientLightMap
    """
    w = _weather(weather, sky, horizontal_illuminance_lux, sun_elevation_deg, sun_azimuth_deg)
    s = in_range("spacing_m", spacing_m)
    n = integer_in_range("samples", samples)
    if bounds is None:
        lo, hi = default_bounds(scene, s)
    else:
        b = float_array("bounds", bounds)
        if b.shape != (2, 3) or not np.all(np.isfinite(b)) or np.any(b[1] < b[0]):
            raise ValueError(f"bounds must be [[xmin, ymin, zmin], [xmax, ymax, zmax]] with max >= min, got {np.asarray(bounds).tolist()}")
        lo, hi = b[0], b[1]
    return wrap(cached_core_map(_occluders(scene), w, lo, hi, s, n), w.sky_illuminance_lux)


def wrap(core: _core.AmbientLightMap, illuminance_lux: float) -> AmbientLightMap:
    """The public map around a core one."""
    return AmbientLightMap(
        grid=core.values * np.float32(illuminance_lux),
        origin_m=np.asarray(core.origin_m, dtype=np.float64),
        spacing_m=float(core.spacing_m),
        solid=core.solid,
        illuminance_lux=float(illuminance_lux),
        core=core,
    )
