"""The snow cover: where the snow lies after it has fallen with the wind.

After Koitabashi, Matsubara, Moriya & Takahashi, *Snowfall and snow-cover scenes with wind*
(Tokyo Denki University), made physical: the ground and the box tops (or a photo's surfaces,
from its depth map through its camera) are a height field of square cells; each step shadow
buffers rendered along a spread of fall paths (each flake size at its own fall speed, through
the wind's gusts, the wind slowed below the roofs by Macdonald's urban canopy profile) decide
how much of the snow reaches each cell, and those grow by the depth that
the rate, the step and the snow's density give, R * dt * rho_water / rho_snow, times the flux
through the cell's own surface (1 on level ground, more on faces turned to the wind, less on
faces turned from it); then the paper's random factor r (seeded, moving snow between cells
without making any) and its 4-neighbour smoothing (of the step's increment, on each surface).
The snow's own height enters the height field, so drifts build. Above fresh snow's threshold
(about 4.3 m/s at 10 m) the wind also moves the snow that lies (Pomeroy & Gray's saltation
flux, settling in Werner's 15-degree lee of every crest): roofs are scoured, drifts form in the
lee of walls and boxes. The method is described in full in
``rust/skyfall-core/src/snow/cover/mod.rs`` and its ``wind.rs`` and ``drift.rs``.

Mass is kept: the snow that fell on the catchment's lit cells (``fallen_kg``), plus what the
wind blew in across its edges less what it blew out, is the snow lying on it (``lying_kg``);
the open sky's share over the same area (``open_sky_kg``) differs from it
by the wind's shadows and what it carried across the catchment's sides.

Rendering: the cover is part of the weather, ``Weather(snow_cover=cover)`` (or
``dataclasses.replace(weather, snow_cover=cover)``), as every effect is: the surfaces
whiten (albedo 0.85, fresh snow) and lift by the depth lying on them, lit by the sky and the
lamps as the surfaces are, and the frame carries ``layers["snow_depth_m"]`` (the depth
between the cells' centres, interpolated over each surface, so a drift's shading and the
cover's edge vary smoothly). Thin snow lies in patches (:func:`coverage`, :data:`PATCH_M`):
white where they lie, the surface beneath between them; the layer is the patches' depth
d / c(d) where a pixel shows one and 0 between them (its mean over many patches is d). Under a sun the snow sparkles: single ice facets
mirror the sun's disc into the camera (``rust/skyfall-core/src/snow/cover/sparkle.rs``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skyfall import _core
from skyfall._validate import float_array, in_range, integer
from skyfall.scenes import BoxScene, PhotoScene
from skyfall.weather import Weather

__all__ = ["COVER_FULL_M", "PATCH_BLEND", "PATCH_M", "SNOW_ALBEDO", "SnowCover", "accumulate", "coverage", "open_depth_m"]

SNOW_ALBEDO: float = _core.SNOW_ALBEDO
"""Albedo of the drawn snow, the cover and the falling flakes alike (the core's one constant,
0.85 as float32: fresh dry snow reflects 0.80-0.90 of visible light: Cuffey & Paterson, *The
Physics of Glaciers*, 4th ed., 2010, Table 5.2)."""

COVER_FULL_M: float = _core.SNOW_COVER_FULL_M
"""The mean depth of lying snow from which it hides the surface beneath whole, m (2 cm). Thin
snow lies in patches that cover the share :func:`coverage` of a surface; frames draw them
white and the surface beneath between them."""

PATCH_M: float = _core.SNOW_PATCH_M
"""The size of thin snow's largest patches, m (10 cm; they come in three octaves, down to
2.5 cm): a smooth random field over the ground, the same in every frame and process."""

PATCH_BLEND: tuple[float, float] = _core.SNOW_PATCH_BLEND
"""A pixel whose footprint is at most ``PATCH_BLEND[0] * PATCH_M`` shows the patches sharp
(snow or ground); from ``PATCH_BLEND[1] * PATCH_M`` on it shows their mean share,
:func:`coverage`; linear between. The expected share is :func:`coverage` at every distance."""


def coverage(depth_m: ArrayLike) -> NDArray[np.float64]:
    """The share of a surface that a mean depth of lying snow covers:
    1 - (1 - d / :data:`COVER_FULL_M`)^2 below :data:`COVER_FULL_M`, 1 from there, 0 for no snow.

    Parameters
    ----------
    depth_m : array_like
        Mean depth of snow, m (a cover's ``depth_m`` or ``open_depth_m``).

    Returns
    -------
    numpy.ndarray
        The share in [0, 1], float64, of the input's shape.

    Examples
    --------
    >>> from skyfall import snow
    >>> snow.coverage([0.0, 0.005, 0.01, 0.05]).round(4).tolist()
    [0.0, 0.4375, 0.75, 1.0]
    """
    d = np.clip(np.asarray(depth_m, dtype=np.float64) / COVER_FULL_M, 0.0, 1.0)
    return 1.0 - (1.0 - d) ** 2


MARGIN_M = 10.0
"""How far a box scene's default grid reaches beyond its boxes and its camera, m."""


@dataclass(frozen=True, eq=False)
class SnowCover:
    """The snow lying on a scene after :func:`accumulate`; ``Weather(snow_cover=...)`` draws it.

    Two covers are equal when they are the same object (their arrays are not compared), so a
    :class:`~skyfall.Weather` holding one compares and hashes as its other fields do.

    Attributes
    ----------
    depth_m : ndarray of float64, shape (nz, nx)
        Depth of snow per cell, m (0 where none or no surface). Row k, column i is the cell
        whose centre is ``origin_m + ((i + 0.5) * spacing_m, (k + 0.5) * spacing_m)`` in
        world (x, z).
    base_m : ndarray of float64, shape (nz, nx)
        Height of the surface the snow lies on (ground, box top, a photo's highest point in
        the cell), m; NaN where there is none.
    origin_m : tuple of 2 float
        World (x, z) of the grid's corner, m.
    spacing_m : float
        Cell side, m.
    shape : tuple of 2 int
        (nz, nx).
    fallen_kg, lying_kg, open_sky_kg : float
        Snow that fell on the catchment's lit cells, snow lying on it at the end (equal to
        ``fallen_kg + blown_in_kg - blown_out_kg``: mass is kept), and snow that fell through
        the level plane over its surface cells (R * rho_water * area * duration), kg.
    blown_in_kg, blown_out_kg : float
        Snow the wind carried in across the grid's upwind edge and out across its downwind
        edge (0 below fresh snow's threshold of about 4.3 m/s at 10 m), kg.
    canopy : tuple of 3 float
        The canopy the wind blew through: its height above the lowest surface (m), Macdonald's
        attenuation a (the wind at the ground is exp(-a) of the wind above the roofs) and the
        frontal area index lambda_f; zeros in still air or without buildings.
    open_depth_m : float
        The depth the run lays on level open ground, R * duration * rho_water / rho_snow, m.
    steps : int
        Steps run (``ceil(duration_s / dt_s)``, each of ``dt_s`` = duration / steps).
    dt_s : float
        The step used, s.
    fall_velocity_m_s : tuple of 3 float
        The snow's mean fall velocity (wind plus the flakes' fall speed), m/s.
    """

    depth_m: NDArray[np.float64]
    base_m: NDArray[np.float64]
    origin_m: tuple[float, float]
    spacing_m: float
    shape: tuple[int, int]
    fallen_kg: float
    lying_kg: float
    open_sky_kg: float
    open_depth_m: float
    steps: int
    dt_s: float
    fall_velocity_m_s: tuple[float, float, float]
    blown_in_kg: float
    blown_out_kg: float
    canopy: tuple[float, float, float]
    core: _core.SnowCoverGrid = field(repr=False, compare=False)

    @property
    def x_m(self) -> NDArray[np.float64]:
        """World x of each column's cell centres, m, shape (nx,)."""
        return np.asarray(self.origin_m[0] + (np.arange(self.shape[1]) + 0.5) * self.spacing_m, dtype=np.float64)

    @property
    def z_m(self) -> NDArray[np.float64]:
        """World z of each row's cell centres, m, shape (nz,)."""
        return np.asarray(self.origin_m[1] + (np.arange(self.shape[0]) + 0.5) * self.spacing_m, dtype=np.float64)

    @property
    def fall_angle_deg(self) -> float:
        """Angle of the snow's mean fall from the vertical, degrees."""
        vx, vy, vz = self.fall_velocity_m_s
        return math.degrees(math.atan2(math.hypot(vx, vz), -vy)) if vy < 0 else 0.0


def open_depth_m(weather: Weather, duration_s: float) -> float:
    """The depth of snow ``weather`` lays on level open ground in ``duration_s``, m:
    R * duration * rho_water / rho_snow (1 mm/h of water at 100 kg/m^3 for one hour: 0.01 m).

    Parameters
    ----------
    weather : Weather
        Its ``snow_rate_mm_h`` and ``snow_density_kg_m3``.
    duration_s : float
        How long it snows, s, in [0, 1e7].

    Returns
    -------
    float
    """
    t = in_range("duration_s", duration_s)
    return weather.snow_rate_mm_h * 1e-3 / 3600.0 * t * 1000.0 / weather.snow_density_kg_m3


def _extent(scene: BoxScene, extent_m: Any) -> tuple[list[float], list[float]]:
    """The box scene's grid extent: ``extent_m`` (x0, z0, x1, z1), or its boxes and camera
    with :data:`MARGIN_M` around them."""
    if extent_m is not None:
        e = float_array("extent_m", extent_m).reshape(-1)
        if e.size != 4 or not np.all(np.isfinite(e)) or not (e[2] > e[0] and e[3] > e[1]):
            raise ValueError(f"extent_m must be (x0, z0, x1, z1) with x1 > x0 and z1 > z0, finite, m; got {extent_m!r}")
        return [float(e[0]), float(e[1])], [float(e[2]), float(e[3])]
    cam = np.asarray(scene.camera.position_m, dtype=np.float64)
    xs = [cam[0]]
    zs = [cam[2]]
    if len(scene.boxes):
        xs += [float(scene.boxes[:, 0].min()), float(scene.boxes[:, 3].max())]
        zs += [float(scene.boxes[:, 2].min()), float(scene.boxes[:, 5].max())]
    margin = MARGIN_M if len(scene.boxes) else 3 * MARGIN_M
    return [min(xs) - margin, min(zs) - margin], [max(xs) + margin, max(zs) + margin]


def accumulate(
    scene: BoxScene | PhotoScene,
    weather: Weather,
    *,
    duration_s: float,
    dt_s: float = 60.0,
    resolution_m: float = 0.5,
    seed: int = 0,
    roughness: float = 0.1,
    extent_m: Any = None,
    turbulence: float = 0.4,
    redistribute: bool = True,
) -> SnowCover:
    """Let ``weather``'s snow fall on ``scene`` for ``duration_s`` and return the cover.

    Parameters
    ----------
    scene : BoxScene or PhotoScene
        A box scene (its ground and box tops) or a photo (its surfaces from the depth map
        through its camera; points more than 200 m from the camera, horizontally, are left
        out and drawn as level open ground).
    weather : Weather
        ``snow_rate_mm_h`` (water equivalent), ``snow_density_kg_m3`` and ``wind_m_s``.
    duration_s : float
        How long it snows, s, in [0, 1e7].
    dt_s : float
        Time step, s, in (0, 1e7]; a run takes ``ceil(duration_s / dt_s)`` equal steps (a
        step longer than the run: one step), at most 100000.
    resolution_m : float
        Cell side of the height field, m, in [0.01, 100]; at most 4096^2 cells.
    seed : int
        Seeds the random factor, in [0, 2^64).
    roughness : float
        In [0, 1]: the amplitude of the paper's random factor r = 1 + roughness * u (u
        uniform between -1 and 1 per cell, fixed over the run); 0: a smooth cover.
    extent_m : array_like of 4 float, optional
        A box scene's grid, (x0, z0, x1, z1) in world metres; by default its boxes and its
        camera with 10 m around them (an empty scene: 30 m around the camera).
    turbulence : float
        In [0, 2]: the wind's gusts, the standard deviation of each horizontal component as a
        share of the mean wind (over cities 0.3-0.4, the default 0.4); with the flakes' spread
        of fall speeds they spread the fall directions, so shadows are soft. 0: no gusts.
    redistribute : bool
        Whether the wind moves snow that has landed (saltation into the lee of walls and
        boxes; only where the wind exceeds fresh snow's threshold, about 4.3 m/s at 10 m).

    Returns
    -------
    SnowCover

    Raises
    ------
    ValueError
        For values outside their ranges (named), too many cells or steps, or an updraft
        (``wind_m_s[1]``) that keeps the snow from falling.

    Examples
    --------
    >>> from skyfall import Weather, scenes, snow
    >>> cover = snow.accumulate(scenes.empty(), Weather(snow_rate_mm_h=1.0), duration_s=3600.0, resolution_m=2.0)
    >>> round(float(cover.depth_m.mean()), 6)
    0.01
    """
    if not isinstance(weather, Weather):
        raise TypeError(f"weather must be a skyfall.Weather, got {type(weather).__name__}")
    res = in_range("resolution_m", resolution_m)
    dur = in_range("duration_s", duration_s)
    dt = in_range("dt_s", dt_s)
    rough = in_range("roughness", roughness)
    turb = in_range("turbulence", turbulence)
    if not isinstance(redistribute, bool | np.bool_):
        raise TypeError(f"redistribute must be a bool, got {type(redistribute).__name__}")
    seed_ = integer("seed", seed, 0, 2**64 - 1)
    if isinstance(scene, BoxScene):
        lo, hi = _extent(scene, extent_m)
        boxes = np.ascontiguousarray(scene.boxes, dtype=np.float32).reshape(-1, 9)
        grid = _core.snow_cover_boxes(
            boxes, bool(scene.ground), weather, lo, hi, resolution_m=res, duration_s=dur, dt_s=dt, roughness=rough, seed=seed_,
            turbulence=turb, redistribute=bool(redistribute),
        )
    elif isinstance(scene, PhotoScene):
        if extent_m is not None:
            raise ValueError("extent_m sets a box scene's grid; a photo's follows its depth map")
        grid = _core.snow_cover_photo(
            scene.camera, scene.depth_m, weather, resolution_m=res, duration_s=dur, dt_s=dt, roughness=rough, seed=seed_,
            turbulence=turb, redistribute=bool(redistribute),
        )
    else:
        raise TypeError(f"scene must be a BoxScene or PhotoScene, got {type(scene).__name__}")
    fallen, lying, open_sky, open_depth = grid.budget
    steps, dt_used = grid.steps
    return SnowCover(
        depth_m=grid.depth_m,
        base_m=grid.base_m,
        origin_m=grid.origin_m,
        spacing_m=grid.spacing_m,
        shape=grid.shape,
        fallen_kg=fallen,
        lying_kg=lying,
        open_sky_kg=open_sky,
        open_depth_m=open_depth,
        steps=steps,
        dt_s=dt_used,
        fall_velocity_m_s=grid.fall_velocity_m_s,
        blown_in_kg=grid.blown_kg[0],
        blown_out_kg=grid.blown_kg[1],
        canopy=grid.canopy,
        core=grid,
    )
