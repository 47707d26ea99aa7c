"""Type stubs for the compiled ``skyfall._core`` module (checked by mypy.stubtest)."""

from typing import TypedDict, final

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "apply_lut8",
    "encode_srgb8",
    "rain_drops",
    "AIRLIGHT_RELATIVE",
    "FRAME_BUDGET_BYTES",
    "AmbientLightMap",
    "GpuDevice",
    "GpuUnavailableError",
    "render_frame",
    "render_photo8",
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

AIRLIGHT_RELATIVE: float
FRAME_BUDGET_BYTES: int

class SkyfallError(Exception): ...
class GpuUnavailableError(SkyfallError): ...

_RegionArgs = tuple[float, NDArray[np.float64], float, list[float], float, int, str]
class _RainArgs(TypedDict):
    region: _RegionArgs
    exposure_s: float
    camera_velocity_m_s: list[float]
    ground: bool
    lights: NDArray[np.float32] | None
    sky_illuminance_lux: float
    cull_threshold: float | None
    occluders: NDArray[np.float32] | None
    shelter: bool

_RainTuple = tuple[NDArray[np.float32], NDArray[np.float32], int, int, int]
class _OutArrays(TypedDict):
    rgb: NDArray[np.float32] | None
    depth_m: NDArray[np.float32] | None
    transmittance: NDArray[np.float32] | None
    rain_alpha: NDArray[np.float32] | None
    rain_depth_m: NDArray[np.float32] | None

_FrameTuple = tuple[NDArray[np.float32], NDArray[np.float32], NDArray[np.float32] | None, _RainTuple | None]

def render_frame(
    width: int,
    height: int,
    camera_params: list[float],
    *,
    device: GpuDevice | None = None,
    boxes: NDArray[np.float32] | None = None,
    ground: bool = True,
    ground_albedo: list[float] = ...,
    photo_rgb: NDArray[np.float32] | None = None,
    photo_depth_m: NDArray[np.float32] | None = None,
    haze_params: tuple[float, list[float]] | None = None,
    rain: _RainArgs | None = None,
    sky: SkyModel | None = None,
    ambient: AmbientLightMap | None = None,
    out: _OutArrays | None = None,
) -> _FrameTuple: ...
def render_photo8(
    width: int,
    height: int,
    camera_params: list[float],
    photo_srgb8: NDArray[np.uint8],
    photo_depth_m: NDArray[np.float32],
    decode_table: NDArray[np.float32],
    out_srgb8: NDArray[np.uint8],
    *,
    rain_alpha_out: NDArray[np.float32] | None = None,
    haze_params: tuple[float, list[float]] | None = None,
    rain: _RainArgs | None = None,
    sky: SkyModel | None = None,
    ambient: AmbientLightMap | None = None,
) -> tuple[int, int, int] | None: ...

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
    def illuminance(self, points_m: NDArray[np.float32], boxes: NDArray[np.float32], *, samples: int) -> NDArray[np.float32]: ...
    def ambient_map(
        self,
        boxes: NDArray[np.float32],
        *,
        bounds_min_m: list[float],
        bounds_max_m: list[float],
        spacing_m: float,
        samples: int,
    ) -> AmbientLightMap: ...

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
    def sample(self, points_m: NDArray[np.float32]) -> NDArray[np.float32]: ...

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
    center_m: list[float], region_args: _RegionArgs, *, ground: bool, shelter: NDArray[np.float32] | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float32], NDArray[np.float32], NDArray[np.int64]]: ...

def encode_srgb8(linear: NDArray[np.float32]) -> NDArray[np.uint8]: ...
def apply_lut8(encoded: NDArray[np.uint8], table: NDArray[np.float32]) -> NDArray[np.float32]: ...
