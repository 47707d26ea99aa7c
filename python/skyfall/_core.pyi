"""Type stubs for the compiled ``skyfall._core`` module (checked by mypy.stubtest)."""

from typing import NotRequired, TypedDict, final

import numpy as np
from numpy.typing import NDArray

from skyfall.camera import Camera
from skyfall.scenes import BoxScene, PhotoScene
from skyfall.weather import Weather

__all__ = [
    "GlassClock",
    "Windshield",
    "furmidge_critical",
    "metaball_height_map",
    "metaball_normals",
    "refract_through_drops",
    "windshield_gpu",
    "apply_lut8",
    "encode_srgb8",
    "rain_drops",
    "snowflakes",
    "KOSCHMIEDER",
    "AIRLIGHT_PATCH_PX",
    "AIRLIGHT_TOP_FRACTION",
    "atmospheric_light_pixel",
    "dark_channel",
    "AMBIENT_EXTENT_M",
    "CLOUD_DOME_FACE_PX",
    "FRAME_BUDGET_BYTES",
    "AmbientHorizon",
    "AmbientLightMap",
    "ambient_horizon",
    "HORIZON_MAX_PAIRS",
    "GpuDevice",
    "SnowCoverGrid",
    "snow_cover_boxes",
    "snow_cover_photo",
    "GpuUnavailableError",
    "frame_plan",
    "render_frame",
    "render_frame8",
    "render_photo8",
    "weather_optics",
    "weather_sun",
    "CloudDome",
    "CloudField",
    "cloud_path_traced",
    "LAYERS",
    "LAYER_NEUTRAL",
    "SNOW_ALBEDO",
    "SNOW_COVER_FULL_M",
    "SNOW_PATCH_M",
    "SNOW_PATCH_BLEND",
    "MAX_DIAMETER_MM",
    "MAX_RAIN_RATE_MM_H",
    "RANGES",
    "RANGE_MEANINGS",
    "check_range",
    "SkyModel",
    "SkyfallError",
    "TEXTURE_BUDGET_BYTES",
    "__version__",
    "air_density_kg_m3",
    "air_viscosity",
    "cloud_base_m",
    "drops_per_m3",
    "marshall_palmer",
    "rain_diameter_bins",
    "rain_extinction_per_m",
    "rain_rate_from_dsd",
    "rain_textures",
    "terminal_velocity_m_s",
    "attenuation_volume",
    "check_sun_direction",
    "cloud_particles",
    "harris_illumination",
    "sample_attenuation",
]

__version__: str
TEXTURE_BUDGET_BYTES: int
MAX_DIAMETER_MM: float
MAX_RAIN_RATE_MM_H: float

RANGES: dict[str, tuple[float, float, bool, bool, str]]
"""Every user-facing parameter's valid range: name -> (lo, hi, lo_inclusive, hi_inclusive, unit)."""
RANGE_MEANINGS: dict[str, str]
"""Name -> what the parameter is, one line."""

def check_range(name: str, value: float, index: int | None = None) -> float: ...

KOSCHMIEDER: float
AIRLIGHT_PATCH_PX: int
AIRLIGHT_TOP_FRACTION: float

def dark_channel(image: NDArray[np.uint8] | NDArray[np.float32], patch_px: int) -> NDArray[np.float32]: ...
def atmospheric_light_pixel(image: NDArray[np.uint8] | NDArray[np.float32], patch_px: int, top_fraction: float) -> tuple[int, int]: ...
AMBIENT_EXTENT_M: float
CLOUD_DOME_FACE_PX: int
HORIZON_MAX_PAIRS: int
FRAME_BUDGET_BYTES: int

class SkyfallError(Exception): ...
class GpuUnavailableError(SkyfallError): ...

class _Request(TypedDict):
    """One frame's request: the frame's own objects, read by the core attribute by attribute."""

    camera: Camera
    weather: Weather
    scene: BoxScene | PhotoScene
    time_s: float
    seed: int
    cull_threshold: float | None
    ambient: AmbientLightMap
    snow_cover: NotRequired[SnowCoverGrid]
    clouds: NotRequired[CloudField]
    windshield: NotRequired[Windshield | GlassClock]

LAYERS: dict[str, str]
"""The layers a frame can carry, name -> meaning, in the order frames list them."""
LAYER_NEUTRAL: dict[str, float]
"""Each layer's value where its pass drew nothing, name -> value (rain_alpha 0, transmittance 1)."""
SNOW_ALBEDO: float
"""Albedo of fresh snow (flakes and cover), 0.85 as float32."""
SNOW_COVER_FULL_M: float
"""The mean depth of lying snow from which it hides the surface beneath whole, m (0.02)."""
SNOW_PATCH_M: float
"""The lattice of thin snow's patches' largest features, m (0.1)."""
SNOW_PATCH_BLEND: tuple[float, float]
"""Pixel footprints, as shares of SNOW_PATCH_M, up to which thin snow's patches are drawn sharp
and from which as their mean share (0.1, 0.5)."""

def render_frame(
    request: _Request,
    *,
    device: GpuDevice | None = None,
    cpu_fallback: bool = False,
    out: dict[str, NDArray[np.float32] | None] | None = None,
) -> tuple[NDArray[np.float32], NDArray[np.float32], dict[str, NDArray[np.float32]], dict[str, int]]: ...
def frame_plan(request: _Request) -> list[tuple[str, bool, bool, list[str]]]: ...
def render_frame8(
    request: _Request, out_srgb8: NDArray[np.uint8], *, layers: dict[str, NDArray[np.float32]] | None = None
) -> dict[str, int]: ...
def render_photo8(
    request: _Request,
    photo_srgb8: NDArray[np.uint8],
    decode_table: NDArray[np.float32],
    out_srgb8: NDArray[np.uint8],
    *,
    rain_alpha_out: NDArray[np.float32] | None = None,
    snow_alpha_out: NDArray[np.float32] | None = None,
) -> dict[str, int]: ...
def weather_optics(weather: Weather) -> tuple[float, float, float, float, float, float]: ...
def weather_sun(weather: Weather) -> tuple[list[float], float] | None: ...

def cloud_base_m(rain_rate_mm_h: float) -> float: ...
@final
class SkyModel:
    def __new__(
        cls,
        sky_type: int,
        sun_elevation_deg: float | None,
        sun_azimuth_deg: float | None,
        extinction_per_m: float,
        cloud_base_m: float,
    ) -> SkyModel: ...
    @property
    def scale(self) -> float: ...
    def luminance_relative(self, dirs: NDArray[np.float32], *, received: bool) -> NDArray[np.float64]: ...
    def rgb_relative(self, dirs: NDArray[np.float32], *, received: bool) -> NDArray[np.float64]: ...
    @property
    def colours(self) -> tuple[list[float], list[float], list[float]]: ...
    def illuminance(self, points_m: NDArray[np.float32], boxes: NDArray[np.float32], *, samples: int) -> NDArray[np.float32]: ...
    def ambient_map(
        self,
        boxes: NDArray[np.float32],
        *,
        bounds_min_m: list[float],
        bounds_max_m: list[float],
        spacing_m: float,
        samples: int,
        spacing_name: str | None = None,
        per_azimuth: bool = False,
        dome: CloudDome | None = None,
    ) -> AmbientLightMap: ...
    def light_map(self, horizon: AmbientHorizon, *, dome: CloudDome | None = None) -> AmbientLightMap: ...

@final
class AmbientHorizon:
    """What a scene fixes of its ambient-light map: each open node's visible sky per azimuth
    (and, after a sky the same at every azimuth, each open node's weights for such skies)."""

    @property
    def dims(self) -> list[int]: ...
    @property
    def samples(self) -> int: ...
    @property
    def nbytes(self) -> int: ...

def ambient_horizon(
    boxes: NDArray[np.float32],
    *,
    bounds_min_m: list[float],
    bounds_max_m: list[float],
    spacing_m: float,
    samples: int,
    spacing_name: str | None = None,
) -> AmbientHorizon: ...

@final
class AmbientLightMap:
    @property
    def origin_m(self) -> list[float]: ...
    @property
    def spacing_m(self) -> float: ...
    @property
    def dims(self) -> list[int]: ...
    @property
    def values(self) -> NDArray[np.float32]: ...
    @property
    def solid(self) -> NDArray[np.bool_]: ...
    @property
    def light_colour(self) -> list[float] | None: ...
    def sample(self, points_m: NDArray[np.float32]) -> NDArray[np.float32]: ...

@final
class SnowCoverGrid:
    """A snow cover (``skyfall.snow.SnowCover.core``): its height field and depth per cell."""

    @property
    def depth_m(self) -> NDArray[np.float64]: ...
    @property
    def base_m(self) -> NDArray[np.float64]: ...
    @property
    def origin_m(self) -> tuple[float, float]: ...
    @property
    def spacing_m(self) -> float: ...
    @property
    def shape(self) -> tuple[int, int]: ...
    @property
    def budget(self) -> tuple[float, float, float, float]: ...
    @property
    def steps(self) -> tuple[int, float]: ...
    @property
    def fall_velocity_m_s(self) -> tuple[float, float, float]: ...
    @property
    def blown_kg(self) -> tuple[float, float]: ...
    @property
    def canopy(self) -> tuple[float, float, float]: ...

def snow_cover_boxes(
    boxes: NDArray[np.float32],
    ground: bool,
    weather: Weather,
    lo_m: list[float],
    hi_m: list[float],
    *,
    resolution_m: float,
    duration_s: float,
    dt_s: float,
    roughness: float,
    seed: int,
    turbulence: float,
    redistribute: bool,
) -> SnowCoverGrid: ...
def snow_cover_photo(
    camera: Camera,
    depth_m: NDArray[np.float32],
    weather: Weather,
    *,
    resolution_m: float,
    duration_s: float,
    dt_s: float,
    roughness: float,
    seed: int,
    turbulence: float,
    redistribute: bool,
) -> SnowCoverGrid: ...

@final
class GpuDevice:
    def __new__(cls, *, require_hardware: bool) -> GpuDevice: ...
    @property
    def adapter_info(self) -> tuple[str, str, str, str]: ...


def air_density_kg_m3(
    temperature_c: NDArray[np.float64], pressure_hpa: NDArray[np.float64], relative_humidity: NDArray[np.float64]
) -> NDArray[np.float64]: ...
def air_viscosity(temperature_c: NDArray[np.float64]) -> NDArray[np.float64]: ...
def terminal_velocity_m_s(
    diameter_mm: NDArray[np.float64],
    model: str,
    temperature_c: NDArray[np.float64],
    pressure_hpa: NDArray[np.float64],
    relative_humidity: NDArray[np.float64],
) -> NDArray[np.float64]: ...
def marshall_palmer(diameter_mm: NDArray[np.float64], rain_rate_mm_h: NDArray[np.float64]) -> NDArray[np.float64]: ...
def drops_per_m3(
    rain_rate_mm_h: NDArray[np.float64], d_min_mm: NDArray[np.float64], d_max_mm: NDArray[np.float64]
) -> NDArray[np.float64]: ...
def rain_rate_from_dsd(
    rain_rate_mm_h: NDArray[np.float64],
    model: str,
    temperature_c: NDArray[np.float64],
    pressure_hpa: NDArray[np.float64],
    relative_humidity: NDArray[np.float64],
    d_min_mm: NDArray[np.float64],
    d_max_mm: NDArray[np.float64],
) -> NDArray[np.float64]: ...
def rain_extinction_per_m(rain_rate_mm_h: NDArray[np.float64]) -> NDArray[np.float64]: ...
def rain_textures(
    rain_rates_mm_h: NDArray[np.float64],
    diameters_mm: NDArray[np.float64],
    size_px: int,
    exposure_s: float,
    seed: int,
) -> NDArray[np.float32]: ...
def rain_diameter_bins(diameters_mm: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...


def rain_drops(
    center_m: list[float], weather: Weather, *, time_s: float, seed: int, ground: bool, shelter: NDArray[np.float32] | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float32], NDArray[np.float32], NDArray[np.int64]]: ...

def snowflakes(
    center_m: list[float], weather: Weather, *, time_s: float, seed: int, ground: bool
) -> tuple[NDArray[np.float64], NDArray[np.float32], NDArray[np.float32], NDArray[np.int64]]: ...

def encode_srgb8(linear: NDArray[np.float32]) -> NDArray[np.uint8]: ...
def apply_lut8(encoded: NDArray[np.uint8], table: NDArray[np.float32]) -> NDArray[np.float32]: ...

# Clouds (skyfall.clouds).
def cloud_particles(
    kind: str, n_particles: int, extent_m: float, altitude_m: float, seed: int
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], float]: ...
def harris_illumination(
    positions_m: NDArray[np.float64],
    radii_m: NDArray[np.float64],
    optical_depths: NDArray[np.float64],
    albedos: NDArray[np.float64],
    asymmetry_g: float,
    sun_direction: tuple[float, float, float],
    sun_radiance: float,
) -> NDArray[np.float64]: ...
def attenuation_volume(
    positions_m: NDArray[np.float64],
    radii_m: NDArray[np.float64],
    optical_depths: NDArray[np.float64],
    albedos: NDArray[np.float64],
    asymmetry_g: float,
    sun_direction: tuple[float, float, float],
    resolution: int,
) -> tuple[NDArray[np.float32], NDArray[np.float64]]: ...
def sample_attenuation(
    gamma: NDArray[np.float32], world_from_volume: NDArray[np.float64], points_m: NDArray[np.float64]
) -> NDArray[np.float32]: ...
def check_sun_direction(sun_direction: tuple[float, float, float]) -> list[float]: ...
@final
class CloudField:
    def __new__(
        cls,
        positions_m: NDArray[np.float64],
        radii_m: NDArray[np.float64],
        optical_depths: NDArray[np.float64],
        albedos: NDArray[np.float64],
        asymmetry_g: float,
        sun_direction: tuple[float, float, float] | None,
        resolution: int,
        *,
        diffuse: bool = True,
    ) -> CloudField: ...
    @property
    def n_particles(self) -> int: ...
    @property
    def has_sun(self) -> bool: ...
    def sun_share(self, points_m: NDArray[np.float64]) -> NDArray[np.float32]: ...

@final
class CloudDome:
    """A cloud field over a point, seen along every direction above its horizon: what it
    hides of the sky and the light it sends down."""
    def __new__(
        cls, field: CloudField, sky: SkyModel, eye_m: tuple[float, float, float], sun_relative: float, face_px: int = 32
    ) -> CloudDome: ...
    def sample(self, dirs: NDArray[np.float64]) -> tuple[NDArray[np.float32], NDArray[np.float32]]: ...
    def sky_rgb(self, dirs: NDArray[np.float64]) -> NDArray[np.float32]: ...

def cloud_path_traced(
    positions_m: NDArray[np.float64],
    radii_m: NDArray[np.float64],
    optical_depths: NDArray[np.float64],
    albedos: NDArray[np.float64],
    asymmetry_g: float,
    sun_direction: tuple[float, float, float],
    sun_relative: float,
    eye_m: tuple[float, float, float],
    directions: NDArray[np.float64],
    paths: int,
    max_orders: int,
    seed: int,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]: ...
@final
class Windshield:
    def __new__(
        cls,
        *,
        glass_width_mm: float,
        glass_height_mm: float,
        glass_tilt_deg: float,
        car_speed_m_s: float,
        rain_rate_mm_h: float,
        wipers: int,
        wiper_period_s: float,
        wiper_angles_deg: tuple[float, float],
        advancing_deg: float,
        receding_deg: float,
        cell_mm: float,
        particle_radius_mm: float,
        seed: int,
        state: dict[str, object] | None = None,
    ) -> Windshield: ...
    def step(self, dt_s: float) -> None: ...
    def drops(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.uint8]]: ...
    def metaballs(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...
    def blades(self) -> list[tuple[tuple[float, float], float, float, float]]: ...
    def water_kg(self) -> tuple[float, float, float, float]: ...
    @property
    def t_s(self) -> float: ...
    def arrival_kg_per_s(self) -> float: ...
    def state(self) -> dict[str, object]: ...
    def drawn_steady(
        self,
        *,
        cell_mm: float,
        block: int,
        mass_edges_kg: NDArray[np.float64],
        counts: NDArray[np.float64],
        mass_weights: NDArray[np.float64],
        t_s: float,
    ) -> tuple[Windshield, tuple[int, float, int]]: ...

@final
class GlassClock:
    def __new__(cls, warm: Windshield, period_s: float, epoch_periods: int) -> GlassClock: ...
    def at(self, t_s: float) -> Windshield: ...
    @property
    def epoch_s(self) -> float: ...

def furmidge_critical(advancing_deg: float, receding_deg: float, glass_tilt_deg: float) -> tuple[float, float]: ...
def metaball_height_map(
    centers_px: NDArray[np.float32], radii_px: NDArray[np.float32], width: int, height: int, compress: bool
) -> NDArray[np.float32]: ...
def metaball_normals(height_map: NDArray[np.float32], slope_px: float) -> NDArray[np.float32]: ...
def refract_through_drops(
    frame: NDArray[np.float32],
    height_map: NDArray[np.float32],
    *,
    refraction: str,
    focal_px: float,
    principal_px: tuple[float, float],
    index: float,
    slope_px: float,
    lookup_px: int,
    blur_px: float,
) -> tuple[NDArray[np.float32], NDArray[np.float32]]: ...
def windshield_gpu(
    device: GpuDevice,
    centers_px: NDArray[np.float32],
    radii_px: NDArray[np.float32],
    frame: NDArray[np.float32],
    *,
    compress: bool,
    refraction: str,
    focal_px: float,
    principal_px: tuple[float, float],
    index: float,
    slope_px: float,
    lookup_px: int,
) -> tuple[NDArray[np.float32], tuple[NDArray[np.float32], NDArray[np.float32]]]: ...
