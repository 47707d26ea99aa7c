"""A property-based harness over the public functions and the command line's options (issue
28): hostile values (NaN, infinities, negatives, huge and tiny numbers, huge integers, empty
and 1x1 arrays, wrong dtypes, shapes and memory orders, wrong types) for one parameter at a
time, the others valid. Each call returns a documented result (no NaN; finite where the
function is finite) or raises ValueError, TypeError or MemoryError whose message names the
parameter; anything else (another exception, a crash, a silent NaN) fails.

``make test`` runs a bounded number of cases per target (``SKYFALL_FUZZ_EXAMPLES``, default
12); ``make fuzz`` runs many more and prints the count of cases.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import skyfall
import skyfall.depth
import skyfall.photo
from skyfall import Camera, PhotoScene, Renderer, Weather, cli, clouds, io, physics, rain, sky, windshield
from skyfall.dataset.sample import DatasetConfig, parse_range

EXAMPLES = int(os.environ.get("SKYFALL_FUZZ_EXAMPLES", "12"))
CASES: dict[str, int] = {}

# ---------------------------------------------------------------------------------------------
# Hostile values


def _arrays() -> st.SearchStrategy[Any]:
    shapes = st.sampled_from([(0,), (1,), (1, 1), (3,), (2, 3), (3, 2, 2), (0, 3)])
    dtypes = st.sampled_from([np.float64, np.float32, np.float16, np.int8, np.int64, np.uint16, np.bool_, np.complex64])
    fills = st.sampled_from([0.0, 1.0, -1.0, math.nan, math.inf, -math.inf, 1e30, 3.5])

    def build(shape: tuple[int, ...], dtype: Any, fill: float, order: str, strided: bool) -> Any:
        with np.errstate(invalid="ignore", over="ignore"):
            base = np.full(shape if not strided else (*shape[:-1], 2 * shape[-1]) if shape else shape, fill).astype(dtype)
        a = np.asarray(base, order="F" if order == "F" else "C")
        if strided and a.ndim:
            a = a[..., ::2]
        return a

    return st.builds(build, shapes, dtypes, fills, st.sampled_from(["C", "F"]), st.booleans())


HOSTILE: st.SearchStrategy[Any] = st.one_of(
    st.sampled_from([math.nan, math.inf, -math.inf, -1.0, -1e-300, 0.0, 1e-300, 1e300, -1e300, 1e30, 2.5e9, 0.5]),
    st.sampled_from([0, -1, 1, 2**63, 2**64, -(2**63), 10**30, 16385, 100000]),
    st.sampled_from([True, False, None, "", "abc", "nan", b"1", [], (), {}, [1.0], [math.nan, 1.0], [[1.0, 2.0]], object()]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(2**70), max_value=2**70),
    _arrays(),
)

# ---------------------------------------------------------------------------------------------
# Targets


@dataclass
class Target:
    """A public call: ``call(**{param: value})`` with one parameter hostile."""

    name: str
    call: Callable[..., Any]
    params: tuple[str, ...]
    names: tuple[str, ...] = ()  # more names a message may use (fields, aliases)
    finite: bool = True  # the result is finite wherever it is defined
    skip_values: Callable[[str, Any], bool] = field(default=lambda p, v: False)


_W, _H = 16, 12
_R = Renderer(_W, _H, backend="cpu")
_PIXELS = np.random.default_rng(0).integers(0, 255, (_H, _W, 3), dtype=np.uint8)
_DEPTH = np.full((_H, _W), 4.0, np.float32)
_PHOTO = PhotoScene(np.full((_H, _W, 3), 0.2, np.float32), np.full((_H, _W), 8.0, np.float32),
                    camera=Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0), encoding="linear", airlight="sky")

_WEATHER_FIELDS = ("rain_rate_mm_h", "snow_rate_mm_h", "visibility_m", "sky_illuminance_lux", "wind_m_s", "rain_near_m",
                   "rain_far_m", "rain_diameters_mm", "rain_streaks", "rain_method", "rain_sheltered", "sky",
                   "sun_elevation_deg", "sun_azimuth_deg", "cloud_base_m", "snow_near_m", "snow_opacity",
                   "sun_illuminance_lux", "windshield", "clouds")
_CAMERA_ARGS = ("position_m", "yaw_deg", "pitch_deg", "look_at_m", "vertical_fov_deg", "width", "height", "fx", "fy", "cx",
                "cy", "exposure_s", "velocity_m_s", "focal_length_mm", "sensor_width_mm", "f_number", "focus_distance_m")
_CONFIG_FIELDS = ("variants", "seed", "width", "height", "rain_rate_mm_h", "visibility_m", "exposure_s", "f_number",
                  "focus_distance_m", "wind_m_s", "snow_rate_mm_h", "snow_hours", "snow_resolution_m", "windshield",
                  "clouds", "rain_near_m", "rain_far_m", "camera_height_m", "horizon_row", "vertical_fov_deg",
                  "camera_jitter_m", "camera_jitter_deg", "layers", "exr", "exr_compression", "png_compression",
                  "png_strategy", "ambient_spacing_m", "backend", "parquet", "sequence", "fps", "video_lossless")


def _render(**kw: Any) -> Any:
    weather_kw = {k: kw.pop(k) for k in list(kw) if k in _WEATHER_FIELDS}
    weather = Weather(**weather_kw) if weather_kw else Weather(rain_rate_mm_h=5.0)
    return _R.render(_PHOTO, weather, **kw).rgb


def _render_camera(**kw: Any) -> Any:
    cam = Camera(**{"vertical_fov_deg": 60.0, **kw}) if "fx" not in kw and "focal_length_mm" not in kw else Camera(**kw)
    return _R.render(_PHOTO, Weather(rain_rate_mm_h=5.0), camera=cam).rgb


def _heavy_weather(p: str, v: Any) -> bool:
    # Valid but slow weather (a region's worth of drops at 16 px is still seconds of work).
    return p in ("rain_near_m", "snow_near_m") and isinstance(v, (int, float)) and not isinstance(v, bool) and v > 20


def _config(**kw: Any) -> Any:
    return DatasetConfig(out=Path("unused"), scene="street", **kw)


_OUT = Path(__import__("tempfile").mkdtemp(prefix="skyfall-fuzz-"))


def _cli_render(**kw: Any) -> Any:
    (flag, value), = kw.items()
    code = cli.main(["render", "--width", "8", "--height", "6", "--out", str(_OUT / "fuzz.png"), f"--{flag}", str(value)])
    if code == cli.EXIT_USAGE:
        raise ValueError(f"{flag}: usage error")
    return code


TARGETS = [
    Target("physics.air_density_kg_m3", physics.air_density_kg_m3, ("temperature_c", "pressure_hpa", "relative_humidity")),
    Target("physics.air_viscosity_pa_s", physics.air_viscosity_pa_s, ("temperature_c",)),
    Target("physics.terminal_velocity", lambda **kw: physics.terminal_velocity(kw.pop("diameter_mm", 1.0), **kw),
           ("diameter_mm", "model", "temperature_c", "pressure_hpa", "relative_humidity")),
    Target("physics.marshall_palmer", lambda **kw: physics.marshall_palmer(kw.get("diameter_mm", 1.0), kw.get("rain_rate_mm_h", 5.0)),
           ("diameter_mm", "rain_rate_mm_h")),
    Target("physics.drops_per_m3", lambda **kw: physics.drops_per_m3(**{"rain_rate_mm_h": 5.0, **kw}), ("rain_rate_mm_h", "d_min_mm", "d_max_mm")),
    Target("physics.rain_rate_from_dsd", lambda **kw: physics.rain_rate_from_dsd(kw.pop("rain_rate_mm_h", 5.0), **kw),
           ("rain_rate_mm_h", "model", "d_min_mm", "d_max_mm", "temperature_c")),
    Target("physics.rain_extinction_per_m", lambda **kw: physics.rain_extinction_per_m(kw.get("rain_rate_mm_h", 5.0)), ("rain_rate_mm_h",)),
    Target("sky.cloud_base_m", lambda **kw: sky.cloud_base_m(kw.get("rain_rate_mm_h", 5.0)), ("rain_rate_mm_h",)),
    Target("sky.luminance", lambda **kw: sky.luminance(kw.pop("elevation_deg", 30.0), kw.pop("azimuth_deg", 0.0), **kw),
           ("elevation_deg", "azimuth_deg", "sky", "horizontal_illuminance_lux", "sun_elevation_deg")),
    Target("io.encode_srgb", lambda **kw: io.encode_srgb(kw.get("linear", 0.5)), ("linear",)),
    Target("io.decode_srgb", lambda **kw: io.decode_srgb(kw.get("encoded", 0.5)), ("encoded",)),
    Target("io.decode_srgb8", lambda **kw: io.decode_srgb8(kw.get("encoded", np.zeros(3, np.uint8))), ("encoded",)),
    Target("io.to_srgb8", lambda **kw: io.to_srgb8(kw.get("linear", 0.5)), ("linear",)),
    Target("Weather", lambda **kw: Weather(**kw).extinction_per_m, _WEATHER_FIELDS),
    Target("Camera", lambda **kw: Camera(**{"vertical_fov_deg": 60.0, **kw}).exposure_s if "fx" not in kw else Camera(**kw).exposure_s,
           _CAMERA_ARGS, names=("position_m", "look_at_m", "fov", "focal", "sensor")),
    Target("Renderer", lambda **kw: Renderer(**{"width": 8, "height": 6, "backend": "cpu", **kw}).width, ("width", "height", "backend")),
    Target("Renderer.render(weather)", _render, _WEATHER_FIELDS, skip_values=_heavy_weather),
    Target("Renderer.render(call)", _render, ("time_s", "seed", "cull_threshold", "ambient_spacing_m", "ambient_samples")),
    Target("Renderer.render(camera)", _render_camera, ("yaw_deg", "pitch_deg", "exposure_s", "velocity_m_s", "f_number",
                                                       "focus_distance_m", "vertical_fov_deg"), names=("fov",)),
    Target("clouds.particles", lambda **kw: clouds.particles(kw.pop("kind", "cumulus"), **{"n_particles": 200, **kw}).positions_m,
           ("kind", "n_particles", "extent_m", "altitude_m", "seed"),
           skip_values=lambda p, v: p == "n_particles" and isinstance(v, int) and 2000 < v <= 1_000_000),
    Target("rain.diameter_bins", lambda **kw: rain.diameter_bins(kw.get("diameters_mm", [1.0, 2.0]))[0], ("diameters_mm",)),
    Target("windshield.metaball_height_map",
           lambda **kw: windshield.metaball_height_map(kw.get("centers_px", [[1.0, 1.0]]), kw.get("radii_px", [2.0]), kw.get("shape", (6, 8))),
           ("centers_px", "radii_px", "shape"), names=("width", "height")),
    Target("windshield.normals", lambda **kw: windshield.normals(kw.get("height_map", np.zeros((4, 4), np.float32)), kw.get("slope_px", 1.0)),
           ("height_map", "slope_px")),
    Target("windshield.Windshield", lambda **kw: windshield.Windshield(**{"glass_width_mm": 100.0, "glass_height_mm": 80.0, **kw}).water_kg(),
           ("rain_rate_mm_h", "glass_width_mm", "glass_height_mm", "glass_tilt_deg", "car_speed_m_s", "wipers", "wiper_period_s",
            "wiper_angles_deg", "advancing_deg", "receding_deg", "cell_mm", "particle_radius_mm", "seed")),
    Target("parse_range", lambda **kw: parse_range("wind_m_s", kw.get("value", "0:1")), ("value",), names=("wind_m_s",)),
    Target("DatasetConfig", _config, _CONFIG_FIELDS, finite=False),
    Target("skyfall render", _cli_render, ("rain-rate", "wind-m-s", "exposure-s", "visibility-m", "seed", "f-number", "rain-near-m"),
           names=("rain_rate_mm_h", "wind_m_s", "exposure_s", "visibility_m", "seed", "f_number", "rain_near_m")),
    Target("PhotoScene (no depth)", lambda **kw: PhotoScene(kw.pop("image", _PIXELS), **kw).depth_m,
           ("image", "distance_m", "sky_mask", "camera_height_m", "horizon_row", "vertical_fov_deg", "airlight", "encoding"),
           names=("RGBA", "depth_m"), finite=False),
    Target("PhotoScene (depth)", lambda **kw: PhotoScene(_PIXELS, kw.pop("depth_m", _DEPTH), **kw).depth_m,
           ("depth_m", "depth_scale_m", "sky_mask"), finite=False),
    Target("photo.estimate_sky_mask", lambda **kw: skyfall.photo.estimate_sky_mask(kw.pop("image", _PIXELS), **kw),
           ("image", "encoding", "max_gradient", "min_share", "work_px")),
    Target("skyfall.augment", lambda **kw: skyfall.augment(kw.pop("image", _PIXELS), **kw),
           ("image", "seed", "rain_rate_mm_h", "visibility_m", "exposure_s", "encoding", "wind_m_s", "snow_rate_mm_h"),
           names=("shape", "RGBA", "range", "fields", "linear"), skip_values=_heavy_weather),
    Target("depth.to_metres", lambda **kw: skyfall.depth.to_metres(kw.pop("relative", np.linspace(0.1, 1.0, 12)[:, None] * np.ones((1, 16))), **{"distance_m": 5.0, **kw})[0],
           ("relative", "distance_m", "sky_mask"), finite=False),
]


def _bad_result(value: Any, finite: bool) -> str | None:
    """Why a returned value is not a documented result (None: it is)."""
    if isinstance(value, dict):
        for v in value.values():
            why = _bad_result(v, finite)
            if why:
                return why
        return None
    try:
        a = np.asarray(value)
    except Exception:  # noqa: BLE001 - an object that is not numeric: not ours to judge
        return None
    if a.dtype.kind not in "fc":
        return None
    if np.isnan(a).any():
        return "NaN in the result"
    if finite and not np.isfinite(a).all():
        return "an infinity in the result"
    return None


def _check(target: Target, param: str, value: Any) -> None:
    CASES[target.name] = CASES.get(target.name, 0) + 1
    try:
        with np.errstate(all="ignore"):
            result = target.call(**{param: value})
    except (ValueError, TypeError, MemoryError) as e:
        message = str(e)
        names = {param, param.replace("-", "_"), *target.names}
        assert any(n in message for n in names), f"{target.name}({param}={value!r}): {type(e).__name__} without the name: {message!r}"
        return
    except SystemExit as e:  # argparse's own refusal of a value's type: a usage error
        assert target.name.startswith("skyfall ") and e.code == 2, f"{target.name}({param}={value!r}): exit {e.code}"
        return
    why = _bad_result(result, target.finite)
    assert why is None, f"{target.name}({param}={value!r}) returned {why}"


@pytest.mark.parametrize("target", TARGETS, ids=[t.name for t in TARGETS])
def test_hostile_values_give_a_result_or_a_named_error(target: Target, capsys: pytest.CaptureFixture[str]) -> None:
    @settings(max_examples=EXAMPLES, deadline=None, derandomize=EXAMPLES <= 50,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much, HealthCheck.data_too_large])
    @given(st.sampled_from(target.params), HOSTILE)
    def run(param: str, value: Any) -> None:
        if target.skip_values(param, value):
            return
        _check(target, param, value)
        capsys.readouterr()  # the CLI's own output

    run()


def test_report_the_number_of_cases() -> None:
    # Last in this module: what the harness ran (make fuzz prints it).
    total = sum(CASES.values())
    print(f"\nfuzz: {total} cases over {len(CASES)} targets ({EXAMPLES} examples per target)", file=sys.__stdout__)
    if len(CASES) == len(TARGETS):  # the whole module ran
        assert total >= len(TARGETS)
