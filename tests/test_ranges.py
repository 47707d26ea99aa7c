"""The valid ranges are declared once, in the core (``_core.RANGES``): the docs agree with
the table, and a value just outside each end is refused naming the parameter, through the
public API (Python's checks) and through ``_core`` (the core's)."""

from __future__ import annotations

import dataclasses
import inspect
import math
import re
from types import SimpleNamespace
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from skyfall import Camera, PhotoScene, PointLight, Renderer, SpotLight, Weather, _core, clouds, physics, rain, scenes, sky, snow
from skyfall import weather as weather_module
from skyfall import windshield as ws
from skyfall.dataset import DatasetConfig

RANGES = _core.RANGES
README = Path(__file__).resolve().parents[1] / "README.md"

_NUM = r"[-−]?(?:\d[\d.]*(?:e[-+]?\d+)?|inf|2\^64)"
INTERVAL = re.compile(rf"([\[(])\s*({_NUM})\s*,\s*({_NUM})\s*([\])])")


def _num(s: str) -> float:
    s = s.replace("−", "-")
    return float(2**64) if s == "2^64" else float(s)


def _interval(m: re.Match[str]) -> tuple[float, float, bool, bool]:
    return _num(m.group(2)), _num(m.group(3)), m.group(1) == "[", m.group(4) == "]"


def _table(name: str) -> tuple[float, float, bool, bool]:
    lo, hi, lo_inc, hi_inc, _unit = RANGES[name]
    return lo, hi, lo_inc, hi_inc


def documented(obj: Any) -> dict[str, tuple[float, float, bool, bool]]:
    """Each parameter of a numpydoc Parameters section with the first interval of its
    description (or the first after ``name`` where the description names several)."""
    doc = inspect.getdoc(obj) or ""
    m = re.search(r"^Parameters\n-+\n(.*?)(?:^\w[\w ]*\n-+\n|\Z)", doc, re.S | re.M)
    if m is None:
        return {}
    out: dict[str, tuple[float, float, bool, bool]] = {}
    entries = re.split(r"^(?=\S)", m.group(1), flags=re.M)
    for entry in entries:
        if not entry.strip():
            continue
        head, _, desc = entry.partition("\n")
        names = [n.strip() for n in head.split(" : ")[0].split(",")]
        for name in names:
            at = desc.find(f"``{name}``")
            found = INTERVAL.search(desc, at if at >= 0 else 0)
            if found is not None:
                out[name] = _interval(found)
    return out


# (public object, parameter) pairs whose docstrings state a range: every one must be found
# and must equal the table's.
DOCUMENTED: list[tuple[Any, str]] = [
    (Weather, "rain_rate_mm_h"),
    (Weather, "snow_rate_mm_h"),
    (Weather, "snow_density_kg_m3"),
    (snow.accumulate, "duration_s"),
    (snow.accumulate, "dt_s"),
    (snow.accumulate, "resolution_m"),
    (snow.accumulate, "roughness"),
    (snow.accumulate, "turbulence"),
    (snow.accumulate, "seed"),
    (Weather, "visibility_m"),
    (Weather, "sky_illuminance_lux"),
    (Weather, "sun_elevation_deg"),
    (Weather, "cloud_base_m"),
    (Weather, "sun_illuminance_lux"),
    (Weather, "wind_m_s"),
    (Weather, "rain_near_m"),
    (Weather, "rain_far_m"),
    (Weather, "snow_near_m"),
    (Weather, "rain_duration_s"),
    (Weather, "dry_s"),
    (Weather, "rain_diameters_mm"),
    (Camera, "position_m"),
    (Camera, "pitch_deg"),
    (Camera, "vertical_fov_deg"),
    (Camera, "width"),
    (Camera, "height"),
    (Camera, "fx"),
    (Camera, "fy"),
    (Camera, "cx"),
    (Camera, "cy"),
    (Camera, "exposure_s"),
    (Camera, "velocity_m_s"),
    (Camera, "focal_length_mm"),
    (Camera, "sensor_width_mm"),
    (Camera, "f_number"),
    (Camera, "focus_distance_m"),
    (PointLight, "position_m"),
    (PointLight, "intensity_cd"),
    (PointLight, "color"),
    (SpotLight, "position_m"),
    (SpotLight, "intensity_cd"),
    (SpotLight, "cone_deg"),
    (SpotLight, "color"),
    (PhotoScene, "vertical_fov_deg"),
    (PhotoScene, "airlight"),
    (PhotoScene, "camera_height_m"),
    (PhotoScene, "horizon_row"),
    (PhotoScene, "distance_m"),
    (Renderer, "width"),
    (Renderer, "height"),
    (Renderer.render, "time_s"),
    (Renderer.render, "seed"),
    (Renderer.render, "ambient_spacing_m"),
    (Renderer.render, "ambient_samples"),
    (sky.luminance, "elevation_deg"),
    (sky.horizontal_illuminance, "samples"),
    (sky.ambient_light_map, "spacing_m"),
    (sky.ambient_light_map, "samples"),
    (rain.diameter_bins, "diameters_mm"),
    (rain.textures, "rain_rates_mm_h"),
    (rain.textures, "diameters_mm"),
    (rain.textures, "size_px"),
    (rain.textures, "exposure_s"),
    (rain.textures, "seed"),
    (rain.drops, "seed"),
    (physics.air_density_kg_m3, "temperature_c"),
    (physics.air_density_kg_m3, "pressure_hpa"),
    (physics.air_density_kg_m3, "relative_humidity"),
    (physics.air_viscosity_pa_s, "temperature_c"),
    (physics.terminal_velocity, "diameter_mm"),
    (physics.marshall_palmer, "diameter_mm"),
    (physics.marshall_palmer, "rain_rate_mm_h"),
    (physics.drops_per_m3, "rain_rate_mm_h"),
    (physics.rain_rate_from_dsd, "rain_rate_mm_h"),
    (physics.rain_extinction_per_m, "rain_rate_mm_h"),
    (clouds.particles, "n_particles"),
    (clouds.particles, "extent_m"),
    (clouds.particles, "altitude_m"),
    (clouds.particles, "seed"),
    (clouds.Cloud, "positions_m"),
    (clouds.Cloud, "radii_m"),
    (clouds.Cloud, "optical_depths"),
    (clouds.Cloud, "albedos"),
    (clouds.Cloud, "asymmetry_g"),
    (clouds.harris_illumination, "sun_radiance"),
    (clouds.attenuation_volume, "resolution"),
    (ws.Windshield, "rain_rate_mm_h"),
    (ws.Windshield, "glass_width_mm"),
    (ws.Windshield, "glass_height_mm"),
    (ws.Windshield, "glass_tilt_deg"),
    (ws.Windshield, "car_speed_m_s"),
    (ws.Windshield, "wipers"),
    (ws.Windshield, "wiper_period_s"),
    (ws.Windshield, "wiper_angles_deg"),
    (ws.Windshield, "advancing_deg"),
    (ws.Windshield, "receding_deg"),
    (ws.Windshield, "cell_mm"),
    (ws.Windshield, "particle_radius_mm"),
    (ws.Windshield, "seed"),
    (ws.Windshield.step, "dt_s"),
]


@pytest.mark.parametrize(("obj", "name"), DOCUMENTED, ids=[f"{o.__qualname__}.{n}" for o, n in DOCUMENTED])
def test_docstrings_agree_with_the_table(obj: Any, name: str) -> None:
    docs = documented(obj)
    assert name in docs, f"{obj.__qualname__} documents no range for {name} ({sorted(docs)})"
    assert docs[name] == _table(name), f"{obj.__qualname__}: {name} documented {docs[name]}, table {RANGES[name]}"


def test_every_documented_range_of_the_public_api_is_in_the_list() -> None:
    """Parameters with a documented interval that the list above does not hold would go
    unchecked: they must be in it (or be known not to be a parameter's range)."""
    listed = {(o, n) for o, n in DOCUMENTED}
    not_ranges = {"sun_azimuth_deg", "azimuth_deg"}  # share an entry with an elevation range
    objects = {o for o, _ in DOCUMENTED}
    missing = [
        f"{o.__qualname__}.{n}"
        for o in objects
        for n in documented(o)
        if (o, n) not in listed and n not in not_ranges and n in RANGES
    ]
    assert not missing, missing


def test_sky_cloud_base_documents_the_rain_rate_range() -> None:
    doc = inspect.getdoc(sky.cloud_base_m) or ""
    m = INTERVAL.search(doc)
    assert m is not None and _interval(m) == _table("rain_rate_mm_h")


def test_readme_table_agrees_with_the_table() -> None:
    rows = 0
    for line in README.read_text().splitlines():
        m = re.match(r"^\|\s*((?:`\w+`,?\s*)+)\|(.*)\|\s*$", line)
        if m is None:
            continue
        names = re.findall(r"`(\w+)`", m.group(1))
        intervals = [_interval(i) for i in INTERVAL.finditer(m.group(2))]
        if not intervals:
            continue
        assert len(intervals) >= len(names), line
        for name, iv in zip(names, intervals):
            assert iv == _table(name), f"README: {name} {iv}, table {RANGES[name]}"
            rows += 1
    assert rows >= 6


def test_table_shape() -> None:
    assert len(RANGES) >= 40
    for name, (lo, hi, lo_inc, hi_inc, unit) in RANGES.items():
        assert isinstance(lo, float) and isinstance(hi, float) and lo < hi, name
        assert isinstance(lo_inc, bool) and isinstance(hi_inc, bool) and isinstance(unit, str), name
        assert _core.RANGE_MEANINGS[name], name


# --- refusals --------------------------------------------------------------------------

_tiny = Renderer(8, 6, backend="cpu")
_street = scenes.street()
_photo = np.full((6, 8, 3), 128, np.uint8)
_one_cloud = clouds.Cloud([[0.0, 0.0, 0.0]], [1.0], [1.0], [1.0])

INTEGERS = {"width", "height", "seed", "samples", "ambient_samples", "sky", "size_px", "n_particles", "resolution", "wipers"}

PUBLIC: dict[str, Callable[[Any], object]] = {
    "rain_rate_mm_h": lambda v: Weather(rain_rate_mm_h=v),
    "snow_rate_mm_h": lambda v: Weather(snow_rate_mm_h=v),
    "snow_density_kg_m3": lambda v: Weather(snow_density_kg_m3=v),
    "rain_rates_mm_h": lambda v: rain.textures([v], [1.0], size_px=16),
    "duration_s": lambda v: snow.accumulate(scenes.empty(), Weather(), duration_s=v, resolution_m=10.0),
    "dt_s": lambda v: snow.accumulate(scenes.empty(), Weather(), duration_s=60.0, dt_s=v, resolution_m=10.0),
    "resolution_m": lambda v: snow.accumulate(scenes.empty(), Weather(), duration_s=60.0, resolution_m=v),
    "roughness": lambda v: snow.accumulate(scenes.empty(), Weather(), duration_s=60.0, resolution_m=10.0, roughness=v),
    "turbulence": lambda v: snow.accumulate(scenes.empty(), Weather(), duration_s=60.0, resolution_m=10.0, turbulence=v),
    "visibility_m": lambda v: Weather(visibility_m=v),
    "sky_illuminance_lux": lambda v: Weather(sky_illuminance_lux=v),
    "wind_m_s": lambda v: Weather(wind_m_s=(0.0, 0.0, v)),
    "rain_near_m": lambda v: Weather(rain_near_m=v),
    "rain_far_m": lambda v: Weather(rain_far_m=v, rain_near_m=50.0),
    "snow_near_m": lambda v: Weather(snow_near_m=v),
    "rain_duration_s": lambda v: Weather(rain_rate_mm_h=1.0, rain_duration_s=v),
    "dry_s": lambda v: Weather(dry_s=v),
    "rain_diameters_mm": lambda v: Weather(rain_diameters_mm=(v,)),
    "diameters_mm": lambda v: rain.diameter_bins([v]),
    "sky": lambda v: Weather(sky=v),
    "sun_elevation_deg": lambda v: Weather(sky=12, sun_elevation_deg=v, sun_azimuth_deg=0.0),
    "sun_azimuth_deg": lambda v: Weather(sky=12, sun_elevation_deg=30.0, sun_azimuth_deg=v),
    "elevation_deg": lambda v: sky.luminance(v, 0.0),
    "azimuth_deg": lambda v: sky.luminance(10.0, v),
    "cloud_base_m": lambda v: Weather(cloud_base_m=v),
    "sun_illuminance_lux": lambda v: Weather(sky=12, sun_elevation_deg=30.0, sun_azimuth_deg=0.0, sun_illuminance_lux=v),
    "width": lambda v: Camera(width=v, height=10),
    "height": lambda v: Renderer(10, v),
    "position_m": lambda v: Camera((v, 0.0, 0.0)),
    "yaw_deg": lambda v: Camera(yaw_deg=v),
    "pitch_deg": lambda v: Camera(pitch_deg=v),
    "vertical_fov_deg": lambda v: Camera(vertical_fov_deg=v),
    "fx": lambda v: Camera(width=10, height=10, fx=v),
    "fy": lambda v: Camera(width=10, height=10, fy=v),
    "cx": lambda v: Camera(width=10, height=10, cx=v),
    "cy": lambda v: Camera(width=10, height=10, cy=v),
    "exposure_s": lambda v: Camera(exposure_s=v),
    "velocity_m_s": lambda v: Camera(velocity_m_s=(v, 0.0, 0.0)),
    "focal_length_mm": lambda v: Camera(focal_length_mm=v),
    "sensor_width_mm": lambda v: Camera(sensor_width_mm=v),
    "f_number": lambda v: Camera(f_number=v),
    "focus_distance_m": lambda v: Camera(f_number=2.0, focus_distance_m=v),
    "intensity_cd": lambda v: PointLight((0.0, 0.0, 0.0), v),
    "color": lambda v: SpotLight((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 1.0, color=(1.0, v, 1.0)),
    "cone_deg": lambda v: SpotLight((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 1.0, cone_deg=v),
    "time_s": lambda v: _tiny.render(_street, time_s=v),
    "seed": lambda v: _tiny.render(_street, seed=v),
    "cull_threshold": lambda v: _tiny.render(_street, cull_threshold=v),
    "spacing_m": lambda v: sky.ambient_light_map(_street, spacing_m=v),
    "ambient_spacing_m": lambda v: _tiny.render(_street, ambient_spacing_m=v),
    "samples": lambda v: sky.horizontal_illuminance([[0.0, 1.0, 0.0]], samples=v),
    "ambient_samples": lambda v: _tiny.render(_street, ambient_samples=v),
    "diameter_mm": lambda v: physics.terminal_velocity(v),
    "temperature_c": lambda v: physics.air_viscosity_pa_s(v),
    "pressure_hpa": lambda v: physics.air_density_kg_m3(20.0, v, 0.5),
    "relative_humidity": lambda v: physics.air_density_kg_m3(20.0, 1000.0, v),
    "d_min_mm": lambda v: physics.drops_per_m3(10.0, v, 9.0),
    "size_px": lambda v: rain.textures([10.0], [1.0], size_px=v),
    "airlight": lambda v: PhotoScene(_photo, airlight=(0.5, v, 0.5)),
    "camera_height_m": lambda v: PhotoScene(_photo, camera_height_m=v),
    "horizon_row": lambda v: PhotoScene(_photo, horizon_row=v),
    "distance_m": lambda v: PhotoScene(_photo, distance_m=v),
    "n_particles": lambda v: clouds.particles(n_particles=v),
    "extent_m": lambda v: clouds.particles(n_particles=10, extent_m=v),
    "altitude_m": lambda v: clouds.particles(n_particles=10, altitude_m=v),
    "positions_m": lambda v: clouds.Cloud([[0.0, v, 0.0]], [1.0], [1.0], [1.0]),
    "radii_m": lambda v: clouds.Cloud([[0.0, 0.0, 0.0]], [v], [1.0], [1.0]),
    "optical_depths": lambda v: clouds.Cloud([[0.0, 0.0, 0.0]], [1.0], [v], [1.0]),
    "albedos": lambda v: clouds.Cloud([[0.0, 0.0, 0.0]], [1.0], [1.0], [v]),
    "asymmetry_g": lambda v: clouds.Cloud([[0.0, 0.0, 0.0]], [1.0], [1.0], [1.0], v),
    "sun_radiance": lambda v: clouds.harris_illumination(_one_cloud, [0.0, 1.0, 0.0], sun_radiance=v),
    "resolution": lambda v: clouds.attenuation_volume(_one_cloud, [0.0, 1.0, 0.0], resolution=v),
    "glass_width_mm": lambda v: ws.Windshield(glass_width_mm=v),
    "glass_height_mm": lambda v: ws.Windshield(glass_height_mm=v),
    "glass_tilt_deg": lambda v: ws.Windshield(glass_tilt_deg=v),
    "car_speed_m_s": lambda v: ws.Windshield(car_speed_m_s=v),
    "cell_mm": lambda v: ws.Windshield(cell_mm=v),
    "advancing_deg": lambda v: ws.Windshield(advancing_deg=v),
    "receding_deg": lambda v: ws.Windshield(receding_deg=v),
    "wipers": lambda v: ws.Windshield(wipers=v),
    "wiper_period_s": lambda v: ws.Windshield(wiper_period_s=v),
    "wiper_angles_deg": lambda v: ws.Windshield(wiper_angles_deg=(v, v)),
    "particle_radius_mm": lambda v: ws.Windshield(particle_radius_mm=v),
    "dt_s": lambda v: ws.Windshield(glass_width_mm=20.0, glass_height_mm=20.0).step(v),
}


def just_outside(name: str) -> list[Any]:
    """Values just outside each end of a range (the end itself where it is open; NaN)."""
    lo, hi, lo_inc, hi_inc, _unit = RANGES[name]
    integer = name in INTEGERS
    out: list[Any] = []
    for end, inclusive, sign in ((lo, lo_inc, -1), (hi, hi_inc, 1)):
        if integer:
            out.append(int(end) + sign if inclusive else int(end))
        elif math.isinf(end):
            if not inclusive:
                out.append(end)
        else:
            out.append(end + sign * max(abs(end), 1.0) * 1e-9 if inclusive else end)
    if not integer:
        out.append(math.nan)
    return out


CASES = [(name, v) for name in RANGES for v in just_outside(name)]


def test_every_range_has_a_public_path() -> None:
    assert set(PUBLIC) == set(RANGES)


@pytest.mark.parametrize(("name", "value"), CASES, ids=[f"{n}={v}" for n, v in CASES])
def test_just_outside_is_refused_naming_the_parameter(name: str, value: Any) -> None:
    # velocity_m_s's range is the speed |v|: no public value is below 0, so that end is the
    # core's alone.
    if not (name == "velocity_m_s" and value < 0):
        with pytest.raises(ValueError, match=re.escape(name)):
            PUBLIC[name](value)
    with pytest.raises(ValueError, match=rf"^{re.escape(name)}(\[\d+\])? = .* is outside the valid range"):
        _core.check_range(name, float(value))


@pytest.mark.parametrize("name", sorted(RANGES))
def test_inside_is_accepted(name: str) -> None:
    lo, hi, lo_inc, hi_inc, _unit = RANGES[name]
    for v in (lo, hi):
        if math.isfinite(v) and (lo_inc if v == lo else hi_inc) and v < 1e18:
            assert _core.check_range(name, v) == v


def test_python_messages_are_the_cores() -> None:
    cases: list[tuple[Callable[[], object], str, float]] = [
        (lambda: Camera(exposure_s=0.2), "exposure_s", 0.2),
        (lambda: Weather(sky_illuminance_lux=2e5), "sky_illuminance_lux", 2e5),
        (lambda: Weather(wind_m_s=(0.0, 0.0, 61.0)), "wind_m_s", 61.0),
        (lambda: Camera(vertical_fov_deg=179.0), "vertical_fov_deg", 179.0),
    ]
    for call, name, v in cases:
        with pytest.raises(ValueError) as py_err:
            call()
        index = 2 if name == "wind_m_s" else None
        with pytest.raises(ValueError) as core_err:
            _core.check_range(name, v, index)
        assert str(py_err.value) == str(core_err.value)
    assert str(core_err.value) == "vertical_fov_deg = 179.0 is outside the valid range [0.001, 179) deg"


def test_the_checks_across_weather_fields_are_the_cores_alone() -> None:
    # rain_far_m below rain_near_m, the sun's position whole, a sun's illuminance with a
    # position: checked once, in the core (weather::Weather::validate and the binding's read of
    # the sun), whose messages name the parameter; weather.py holds no copy of them.
    cases: list[tuple[Callable[[], object], str]] = [
        (lambda: Weather(rain_near_m=5.0, rain_far_m=5.0), "rain_far_m: rain_far_m = 5 m must be less than rain_near_m = 5 m"),
        (lambda: Weather(sun_elevation_deg=30.0), "sun_elevation_deg: give both sun_elevation_deg and sun_azimuth_deg, or neither"),
        (lambda: Weather(sun_azimuth_deg=30.0), "sun_elevation_deg: give both sun_elevation_deg and sun_azimuth_deg, or neither"),
        (lambda: Weather(sun_illuminance_lux=1000.0), "sun_illuminance_lux: a sun needs a position: give sun_elevation_deg and sun_azimuth_deg"),
    ]
    for call, message in cases:
        with pytest.raises(ValueError) as e:
            call()
        assert str(e.value).startswith(message)
    # the same through the core's own read of a weather-like object, past every Python check
    w = Weather(rain_near_m=5.0, rain_far_m=4.0)
    fields = {f.name: getattr(w, f.name) for f in dataclasses.fields(w)}
    with pytest.raises(ValueError, match=r"^rain_far_m: rain_far_m = 6 m must be less than rain_near_m = 5 m"):
        _core.weather_optics(SimpleNamespace(**{**fields, "rain_far_m": 6.0}))  # type: ignore[arg-type]
    assert Weather(sun_illuminance_lux=0.0).sun_direction is None  # no sun: no position needed
    source = inspect.getsource(weather_module)
    for text in ("must be less than rain_near_m", "or neither", "needs a sun position", "needs a position"):
        assert text not in source
    with pytest.raises(ValueError, match="rain_far_m: rain_far_m = 6 m must be less than rain_near_m = 5 m"):
        DatasetConfig(out=Path("unused"), scene="street", rain_near_m=5.0, rain_far_m=6.0)


def _render_core(**changes: Any) -> object:
    """A rainy street frame through ``_core.render_frame`` with one value changed past the
    Python checks: the request's camera and weather are stand-ins with the same attributes
    (the core reads them attribute by attribute), so only the core's own checks run."""
    req = _tiny._request(_street, Weather(rain_rate_mm_h=5.0))
    cam, w = req["camera"], req["weather"]
    camera = SimpleNamespace(
        width=cam.width,
        height=cam.height,
        position_m=cam.position_m,
        rotation=cam.rotation,
        exposure_s=changes.get("exposure_s", cam.exposure_s),
        velocity_m_s=changes.get("camera_velocity_m_s", cam.velocity_m_s),
        intrinsics=cam.intrinsics,
        f_number=cam.f_number,
        focus_distance_m=cam.focus_distance_m,
        sensor_width_mm=cam.sensor_width_mm,
    )
    weather = SimpleNamespace(**{f.name: getattr(w, f.name) for f in dataclasses.fields(w)})
    if "sky_illuminance_lux" in changes:
        weather.sky_illuminance_lux = changes["sky_illuminance_lux"]
    req.update(camera=camera, weather=weather, cull_threshold=changes.get("cull_threshold"))
    return _core.render_frame(req)  # type: ignore[arg-type]


# The ranges that had drifted, through _core's own entry points (no Python check on the way).
CORE_PATHS: list[tuple[str, Callable[[float], object]]] = [
    ("exposure_s", lambda v: _render_core(exposure_s=v)),
    ("exposure_s", lambda v: _core.rain_textures(np.array([10.0]), np.array([1.0]), 16, v, 0)),
    ("sky_illuminance_lux", lambda v: _render_core(sky_illuminance_lux=v)),
    ("cull_threshold", lambda v: _render_core(cull_threshold=v)),
    ("sun_elevation_deg", lambda v: _core.SkyModel(12, v, 0.0, 0.0, 1000.0)),
    ("sun_azimuth_deg", lambda v: _core.SkyModel(12, 30.0, v, 0.0, 1000.0)),
    ("cloud_base_m", lambda v: _core.SkyModel(0, None, None, 0.0, v)),
    ("rain_rate_mm_h", lambda v: _core.cloud_base_m(v)),
    ("samples", lambda v: _core.SkyModel(0, None, None, 0.0, 1000.0).illuminance(np.zeros((1, 3), np.float32), np.zeros((0, 9), np.float32), samples=int(v))),
    ("spacing_m", lambda v: _core.SkyModel(0, None, None, 0.0, 1000.0).ambient_map(np.zeros((0, 9), np.float32), bounds_min_m=[0.0] * 3, bounds_max_m=[0.0] * 3, spacing_m=v, samples=64)),
]


@pytest.mark.parametrize(("name", "call"), CORE_PATHS, ids=[n for n, _ in CORE_PATHS])
def test_core_entry_points_refuse_just_outside(name: str, call: Callable[[float], object]) -> None:
    for v in just_outside(name):
        with pytest.raises(ValueError, match=rf"^{re.escape(name)} = .* is outside the valid range"):
            call(v)
    lo, hi, *_ = RANGES[name]
    call(lo if math.isfinite(lo) and RANGES[name][2] else (hi if math.isfinite(hi) else 0.0))


def test_camera_speed_is_checked_in_the_core() -> None:
    with pytest.raises(ValueError, match=r"^velocity_m_s = 1001.0 is outside the valid range \[0, 1000\] m/s"):
        _render_core(camera_velocity_m_s=[1001.0, 0.0, 0.0])
