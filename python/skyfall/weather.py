"""The weather a frame is rendered in: one object that later effects extend."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property, lru_cache

import numpy as np
from numpy.typing import NDArray
from typing import TYPE_CHECKING, Any

from skyfall import _core
from skyfall._validate import all_in_range, choice, flag, float_array, in_range, inside

if TYPE_CHECKING:
    from skyfall.snow import SnowCover

__all__ = ["Weather"]

KOSCHMIEDER: float = _core.KOSCHMIEDER
"""-ln(0.02): visibility is where contrast falls to 2 % (the core's constant)."""


@dataclass(frozen=True)
class Weather:
    """Weather parameters, validated on construction.

    Parameters
    ----------
    rain_rate_mm_h : float
        Rain rate, mm/h, in [0, 500].
    snow_rate_mm_h : float
        Snowfall rate as liquid-water equivalent (what gauges and forecasts give), mm/h, in
        [0, 100]; 1 mm/h of water lays 1 cm/h of snow at 100 kg/m^3. Flakes: Gunn & Marshall's
        sizes, Locatelli & Hobbs' masses and fall speeds (:mod:`skyfall.physics`).
    snow_density_kg_m3 : float
        Bulk density of the snow cover, kg/m^3, in [20, 917] (fresh snow 70-150; default 100).
    visibility_m : float
        Meteorological visibility of the air without rain, m, in [0.01, inf] (``inf``: perfectly clear).
        Enters as Koschmieder extinction 3.912 / visibility_m.
    sky_illuminance_lux : float
        Horizontal illuminance E of the open sky at the ground, lux, in [1e-4, 150000] (what a
        lux meter reads, rain included). Frames are in units of E/pi (a white surface under
        the open sky is 1.0); ``Frame.luminance_scale_cd_m2`` converts to cd/m^2.
    rain_sheltered : bool
        Boxes (a box scene's, a photo's ``occluders``) keep the rain off what they cover: a
        drop whose path back up along its velocity meets a box is not drawn (default True).
        Under an awning only what the wind blows in remains. The same test keeps the water
        film off sheltered surfaces (``rain_duration_s``).
    rain_duration_s : float or None
        How long the rain has fallen at ``rain_rate_mm_h`` on the surfaces, s, in [0, 1e7]:
        it leaves a water film (README, "Wet surfaces") that darkens rough surfaces (Lekner &
        Dorf) and mirrors the sky, the buildings, the lamps and the sun (Fresnel's
        reflectance, 0.02 looking straight down, 1 at grazing), and the frame carries
        ``layers["wetness"]`` (0-1). ``None``: long enough to fill every exposed surface
        (1 mm). ``0`` (default): dry surfaces, the frame's bits unchanged. Both backends draw
        it (box scenes and photos); ``render_srgb8`` then takes its banded path.
    dry_s : float
        How long ago that rain stopped, s, in [0, 1e7] (default 0: it is raining). The film
        dries at 0.25 mm/h, and the frame draws no falling rain (no streaks, no rain in the
        haze): the street after the rain.
    sky : "overcast" or int
        The sky's luminance distribution: ``"overcast"`` (default) is Yamamoto & Tadamura's CIE standard
        overcast sky, (1 + 2 sin(elevation)) / 3 of the zenith; 1-15 the CIE S 011 general
        sky types (:data:`skyfall.sky.SKY_TYPES`).
    sun_elevation_deg, sun_azimuth_deg : float, optional
        The sun, for the CIE types that depend on it (2, 4, 6-15): elevation in [0, 90] deg,
        azimuth from -Z (north, where a default camera looks) towards +X (east), deg.
    cloud_base_m : float, optional
        Cloud base height, m, in [1, 20000]; sky light crosses H / sin(elevation) of the
        hazy air below it. Default: :func:`skyfall.sky.cloud_base_m` of the rain rate.
    snow_near_m : float
        Radius of the snow region around the camera in which flakes are drawn, m, in (0, 50]
        (default 8: flakes fall about 1 m/s, so their streaks are short, and the largest, 10 mm,
        is still about a pixel wide at 8 m in a 1080p frame with a 60 deg field of view);
        beyond it, and for flakes under 1 mm, snow shows only as haze
        (``snow_extinction_per_m``; within it the haze carries only the flakes under 1 mm, so
        the drawn flakes are not counted twice). The flakes in view go as snow_near_m^3.
    snow_opacity : {"extinction", "levels"}
        How a flake's opacity falls with its distance d: ``"extinction"`` (default)
        continuously, e^(-tau) with tau the haze's optical depth to the flake (this weather's
        ``extinction_per_m``, the snow's own included, less the drawn particles' share within
        their regions), as the haze dims a surface at d; ``"levels"``: Koitabashi et al.'s three
        levels, 0.75 / 0.5 / 0.25 in the near, middle and far thirds of ``snow_near_m``.
    wind_m_s : sequence of 3 float
        Wind velocity (x, y, z), m/s, each in [-60, 60]; drops move with it horizontally
        (the vertical component is ignored: drops fall at their terminal speed), so streaks
        slant along the drop's velocity.
    rain_near_m : float
        Radius of the rain region around the camera in which drops are drawn as streaks, m,
        in (0, 50] (5 m as in Yoshida, Dobashi & Yamamoto); beyond it rain shows only as haze,
        and within it the haze carries only the drops outside the drawn bins.
    rain_far_m : float, optional
        The rain's far level of detail: drops farther than this horizontally, m, in
        (0, 50] and below ``rain_near_m``, are drawn as one pre-rasterised, world-anchored
        cylindrical layer per 1.5 m of the rest of the region (in the spirit of Yoshida,
        Dobashi & Yamamoto's rain textures) instead of one streak each; the nearer drops stay
        streaks, drawn one by one whatever ``rain_method`` (billboards balance whole voxels'
        opacity, which a cut there breaks). Its cost is per pixel and layer: faster than drop
        by drop in heavy rain and deep regions, no faster in light rain in a 5 m region; the
        frame's mean opacity is the per-drop reference's (``benches/results/rain.md`` measures
        both). The layers' textures
        are cached per rain rate, diameters, exposure and focal length. Both backends (the GPU's
        SSIM against the CPU's frame 0.9995 or more); pinhole cameras only (a camera with
        ``f_number`` refuses it). None (default): every drop one by one, the frame's bits
        unchanged.
    rain_diameters_mm : sequence of float
        Strictly increasing drop diameters, mm, each in (0, 8], whose bins are drawn (see
        :func:`skyfall.rain.diameter_bins`); Yoshida, Dobashi & Yamamoto's 1.0-2.0 mm by default.
    rain_streaks : bool
        Draw the drops near the camera as streaks (default). False leaves rain as haze only.
    rain_method : {"billboards", "drops"}
        ``"billboards"`` (default): Yoshida, Dobashi & Yamamoto's method, the bin's rain texture on a billboard
        through each voxel's centre facing the camera (every streak of a voxel at one depth),
        its streaks widened so that they carry, in expectation, the opacity of the voxel's drops.
        ``"drops"``: every drop drawn at its own place, the reference the billboards are measured
        against (and the drops :func:`skyfall.rain.drops` lists). Billboards turn to face each
        camera, so two views of one seed share the voxels' streaks only approximately; stereo
        ground truth that must match drop for drop wants ``"drops"``.
    sun_illuminance_lux : float, optional
        The sun's direct illuminance on a surface facing it, at the ground, lux, in
        [0, 150000]. None (default): a clear sky's (Navvab et al.'s turbidity model, about
        87 klx for a sun 45 deg up) for the CIE types 7-15, whose skies show the sun, and no
        direct sun for the others and the overcast sky. With a sun, E (``sky_illuminance_lux``)
        is the sky's diffuse light alone: box scenes' surfaces facing the sun receive
        ``sun_illuminance_lux / E * cos(incidence)`` more, shadowed by the boxes and by
        ``clouds`` (``frame.layers["sun_transmittance"]``); the beam crosses the haze below the
        cloud base. A photo is not relit: its clouds are lit by the sun, its surfaces keep
        their own light.
    clouds : skyfall.clouds.Cloud or str, optional
        Clouds in the sky (:mod:`skyfall.clouds`, Shimada, Shinya, Shiraishi & Harada): a
        ``Cloud`` in world metres, or a preset's name (:data:`skyfall.clouds.PRESETS`). They are
        composited over the sky (and whatever lies behind them) before the haze, lit by the
        sun through their attenuation volume and by the sky's light from above, and draw
        ``layers["cloud_alpha"]``; under a sky with a sun they shade the ground. They drift
        with ``wind_m_s`` (a frame at ``time_s`` draws them moved by its horizontal components
        times ``time_s``, :func:`skyfall.clouds.drifted`). None (default): no clouds, the
        frame's bits unchanged.
    windshield : skyfall.windshield.Windshield or str, optional
        Look through a windshield in the rain (:mod:`skyfall.windshield`): a ``Windshield``
        as it stands (the caller steps it), or a preset's name (:data:`skyfall.windshield.PRESETS`,
        drawn by :func:`skyfall.windshield.warm` at the frame's time and seed). Its drops
        refract the frame as the last stage and draw the layers ``drop_mask`` and
        ``drop_height``. None (default): no glass, the frame's bits unchanged.
    snow_cover : skyfall.snow.SnowCover, optional
        Snow lying on the scene (:func:`skyfall.snow.accumulate` of the scene rendered): its
        surfaces whiten and lift by the depth on them, and the frame carries
        ``layers["snow_depth_m"]`` (the depth on each pixel's surface, m, 0 where none). A
        weather that made the cover and the weather that shows it may differ
        (``dataclasses.replace(weather, snow_cover=cover)``). The fused 8-bit path does not
        draw a cover: :meth:`skyfall.Renderer.render_srgb8` renders the float frame and
        encodes it. None (default): no cover, the frame's bits unchanged.
    """

    rain_rate_mm_h: float = 0.0
    snow_rate_mm_h: float = 0.0
    snow_density_kg_m3: float = 100.0
    visibility_m: float = math.inf
    sky_illuminance_lux: float = 10000.0
    wind_m_s: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rain_near_m: float = 5.0
    rain_far_m: float | None = None
    rain_diameters_mm: tuple[float, ...] = field(default=(1.0, 1.2, 1.4, 1.6, 1.8, 2.0))
    rain_streaks: bool = True
    rain_method: str = "billboards"
    rain_sheltered: bool = True
    rain_duration_s: float | None = 0.0
    dry_s: float = 0.0
    sky: str | int = "overcast"
    sun_elevation_deg: float | None = None
    sun_azimuth_deg: float | None = None
    cloud_base_m: float | None = None
    snow_near_m: float = 8.0
    snow_opacity: str = "extinction"
    windshield: Any = None
    sun_illuminance_lux: float | None = None
    clouds: Any = None
    snow_cover: SnowCover | None = None

    def __post_init__(self) -> None:
        r = in_range("rain_rate_mm_h", self.rain_rate_mm_h)
        object.__setattr__(self, "snow_rate_mm_h", in_range("snow_rate_mm_h", self.snow_rate_mm_h))
        object.__setattr__(self, "snow_density_kg_m3", in_range("snow_density_kg_m3", self.snow_density_kg_m3))
        v = in_range("visibility_m", self.visibility_m)
        e = in_range("sky_illuminance_lux", self.sky_illuminance_lux)
        wind = float_array("wind_m_s", self.wind_m_s).reshape(-1)
        if wind.size != 3:
            raise ValueError(f"wind_m_s = {self.wind_m_s!r} must have 3 components (x, y, z)")
        all_in_range("wind_m_s", wind)
        near = in_range("rain_near_m", self.rain_near_m)
        diams = tuple(float(d) for d in all_in_range("rain_diameters_mm", self.rain_diameters_mm).reshape(-1))
        if not diams or any(b <= a for a, b in zip(diams, diams[1:])):
            raise ValueError(f"rain_diameters_mm = {self.rain_diameters_mm!r} must be strictly increasing (and not empty)")
        object.__setattr__(self, "wind_m_s", (float(wind[0]), float(wind[1]), float(wind[2])))
        object.__setattr__(self, "rain_near_m", near)
        if self.rain_far_m is not None:
            object.__setattr__(self, "rain_far_m", in_range("rain_far_m", self.rain_far_m))
        object.__setattr__(self, "rain_diameters_mm", diams)
        choice("rain_method", self.rain_method, ("drops", "billboards"))
        object.__setattr__(self, "snow_near_m", in_range("snow_near_m", self.snow_near_m))
        if self.rain_duration_s is not None:
            object.__setattr__(self, "rain_duration_s", in_range("rain_duration_s", self.rain_duration_s))
        object.__setattr__(self, "dry_s", in_range("dry_s", self.dry_s))
        choice("snow_opacity", self.snow_opacity, ("extinction", "levels"))
        for name in ("rain_streaks", "rain_sheltered"):
            object.__setattr__(self, name, flag(name, getattr(self, name)))
        object.__setattr__(self, "rain_rate_mm_h", r)
        object.__setattr__(self, "visibility_m", v)
        object.__setattr__(self, "sky_illuminance_lux", e)
        if isinstance(self.sky, str):
            if self.sky != "overcast":
                raise ValueError(f"sky = {self.sky!r} must be \"overcast\" or a CIE general sky type 1-15")
        elif isinstance(self.sky, (int, np.integer)) and not isinstance(self.sky, bool):
            if not inside("sky", int(self.sky)):
                raise ValueError(f"sky = {self.sky} is outside the valid range 1-15 (CIE general sky types) or \"overcast\"")
            object.__setattr__(self, "sky", int(self.sky))
        else:
            raise TypeError(f"sky must be \"overcast\" or an int 1-15, got {type(self.sky).__name__}")
        for name in ("sun_elevation_deg", "sun_azimuth_deg", "cloud_base_m", "sun_illuminance_lux"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, in_range(name, getattr(self, name)))
        # The checks across fields (rain_far_m below rain_near_m, the sun's elevation and
        # azimuth given together, a sun's illuminance with its position) are the core's alone
        # (`weather::Weather::validate`): reading the weather's optics runs them, naming the
        # parameter. Then the sky's own (a sun for the types that need one).
        _ = self._optics
        self.sky_model()
        if self.clouds is not None:
            from skyfall import clouds as _clouds

            if isinstance(self.clouds, str):
                if self.clouds not in _clouds.PRESETS:
                    raise ValueError(f"clouds = {self.clouds!r} is not a preset: use one of {', '.join(map(repr, _clouds.PRESETS))}")
            elif not isinstance(self.clouds, _clouds.Cloud):
                raise TypeError(f"clouds must be a skyfall.clouds.Cloud or a preset's name, got {type(self.clouds).__name__}")
        if self.windshield is not None:
            from skyfall import windshield as _ws

            if isinstance(self.windshield, str):
                if self.windshield not in _ws.PRESETS:
                    raise ValueError(f"windshield = {self.windshield!r} is not a preset: use one of {', '.join(map(repr, _ws.PRESETS))}")
            elif not isinstance(self.windshield, _ws.Windshield):
                raise TypeError(f"windshield must be a skyfall.windshield.Windshield or a preset's name, got {type(self.windshield).__name__}")
        if self.snow_cover is not None:
            from skyfall import snow as _snow

            if not isinstance(self.snow_cover, _snow.SnowCover):
                raise TypeError(f"snow_cover must be a skyfall.snow.SnowCover (skyfall.snow.accumulate's), got {type(self.snow_cover).__name__}")

    @cached_property
    def _optics(self) -> tuple[float, float, float, float, float, float]:
        """(sigma_air, sigma_rain, sigma, cloud base, airlight, sigma_snow) from the core, which the frames use."""
        return _core.weather_optics(self)

    @property
    def air_extinction_per_m(self) -> float:
        """Koschmieder extinction of the air, 3.912 / visibility_m, 1/m."""
        return self._optics[0]

    @property
    def rain_extinction_per_m(self) -> float:
        """Extinction by rain, 1/m (:func:`skyfall.physics.rain_extinction_per_m`)."""
        return self._optics[1]

    @property
    def snow_extinction_per_m(self) -> float:
        """Extinction by falling snow, 1/m: sum of N(D) 2 A(D) over the flakes of the rate (Gunn &
        Marshall's sizes, Mitchell's projected areas; 0 without snow)."""
        return self._optics[5]

    @property
    def extinction_per_m(self) -> float:
        """Total extinction sigma = sigma_air + sigma_rain + sigma_snow, 1/m."""
        return self._optics[2]

    @property
    def cloud_base_height_m(self) -> float:
        """The cloud base H in use, m: ``cloud_base_m`` or :func:`skyfall.sky.cloud_base_m` of the rain rate."""
        return self._optics[3]

    @property
    def airlight_relative(self) -> float:
        """The airlight, relative to E/pi: the luminance the haze tends to with distance and
        the sky at the horizon, the cloud base's horizon luminance under this sky (3/7 for the
        clear overcast sky, 1 for the uniform sky, tending to 1 as the rain thickens: see
        :mod:`skyfall.sky`). A photo's frames scale it to the photo's own airlight."""
        return self._optics[4]

    @cached_property
    def _sun(self) -> tuple[tuple[float, float, float], float] | None:
        r = _core.weather_sun(self)
        return None if r is None else ((float(r[0][0]), float(r[0][1]), float(r[0][2])), float(r[1]))

    @property
    def sun_direction(self) -> tuple[float, float, float] | None:
        """Unit vector towards the sun when the weather has direct sunlight (see
        ``sun_illuminance_lux``), else None."""
        return None if self._sun is None else self._sun[0]

    @property
    def sun_relative(self) -> float:
        """The sun's normal illuminance at the ground over E, through the haze below the cloud
        base (0 without a sun): a white surface facing the sun receives this much more light
        than the open sky gives it."""
        return 0.0 if self._sun is None else self._sun[1]

    def sky_model(self) -> _core.SkyModel:
        """The normalised sky with the rain's attenuation, as ``_core`` uses it (cached)."""
        sky_type = 0 if self.sky == "overcast" else int(self.sky)
        return _sky_model(sky_type, self.sun_elevation_deg, self.sun_azimuth_deg, self.extinction_per_m, self.cloud_base_height_m)

    @property
    def luminance_scale_cd_m2(self) -> float:
        """E/pi, cd/m^2: multiply a frame's relative values by this to get luminance."""
        return self.sky_illuminance_lux / math.pi


@lru_cache(maxsize=64)
def _sky_model(sky_type: int, sun_el: float | None, sun_az: float | None, sigma: float, cloud_base: float) -> _core.SkyModel:
    return _core.SkyModel(sky_type, sun_el, sun_az, sigma, cloud_base)
