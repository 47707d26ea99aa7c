"""One typed request per frame: ``Renderer.render`` and ``render_srgb8`` make one ``_core`` call
per frame, carrying the frame's own objects; the core derives the haze, the sky and the rain
from them (the same frames as the physics computed in Python before: independent numpy haze in
test_render.py, and the frame hashes of the demo held by test_golden.py)."""

from __future__ import annotations

import dataclasses

import math
from collections import Counter
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest

import skyfall
from skyfall import PhotoScene, Renderer, Weather, _core, io, scenes, snow, windshield


@pytest.fixture
def core_calls(monkeypatch: pytest.MonkeyPatch) -> Iterator[Counter[str]]:
    """Every call into ``skyfall._core`` from the package, by name."""
    calls: Counter[str] = Counter()
    for name in dir(_core):
        f = getattr(_core, name)
        if callable(f) and not isinstance(f, type) and not name.startswith("_"):

            def counted(*args: Any, _f: Any = f, _name: str = name, **kwargs: Any) -> Any:
                calls[_name] += 1
                return _f(*args, **kwargs)

            monkeypatch.setattr(_core, name, counted)
    yield calls


@pytest.mark.parametrize("kind", ["boxes", "photo", "photo8"])
def test_a_frame_is_one_core_call(core_calls: Counter[str], kind: str) -> None:
    r = Renderer(64, 48, backend="cpu")
    street = scenes.street(lamps=True)
    w = Weather(rain_rate_mm_h=20.0, visibility_m=800.0, sky_illuminance_lux=50.0)
    if kind == "boxes":
        scene: Any = street
        draw = lambda: r.render(scene, w, seed=1)  # noqa: E731
    else:
        clear = r.render(street, Weather())
        image = io.to_srgb8(clear.rgb) if kind == "photo8" else clear.rgb
        scene = PhotoScene(image, clear.depth_m, camera=street.camera.with_resolution(64, 48), lights=street.lights, encoding=None if kind == "photo8" else "linear")
        draw = (lambda: r.render_srgb8(scene, w, seed=1)) if kind == "photo8" else (lambda: r.render(scene, w, seed=1))
    draw()  # the scene's ambient-light map is built and cached
    core_calls.clear()
    draw()
    want = "render_photo8" if kind == "photo8" else "render_frame"
    assert core_calls == Counter({want: 1}), core_calls


def test_the_core_reads_the_objects_and_names_what_is_wrong() -> None:
    # A stand-in weather past Python's checks: the core's own check names the field.
    r = Renderer(16, 12, backend="cpu")
    street = scenes.street()
    req = r._request(street, Weather(rain_rate_mm_h=5.0))

    class Stand:
        def __init__(self, w: Weather, **changes: Any) -> None:
            for k in w.__dataclass_fields__:
                setattr(self, k, changes.get(k, getattr(w, k)))

    for change, name in [({"visibility_m": 0.0}, "visibility_m"), ({"rain_method": "hail"}, "rain_method"), ({"sky": 16}, "sky"), ({"sun_elevation_deg": 30.0}, "sun")]:
        req["weather"] = Stand(Weather(rain_rate_mm_h=5.0), **change)  # type: ignore[typeddict-item]
        with pytest.raises(ValueError, match=name):
            _core.render_frame(req)
    req["weather"] = "rain"  # type: ignore[typeddict-item]
    with pytest.raises((TypeError, AttributeError)):
        _core.render_frame(req)


def test_the_haze_model_is_the_cores() -> None:
    # Koschmieder: visibility V is where the contrast falls to 2 %; rain adds its own σ.
    w = Weather(rain_rate_mm_h=10.0, visibility_m=2000.0)
    assert w.air_extinction_per_m == pytest.approx(-math.log(0.02) / 2000.0, rel=2e-4)
    assert w.rain_extinction_per_m == pytest.approx(float(skyfall.physics.rain_extinction_per_m(10.0)))
    assert w.extinction_per_m == w.air_extinction_per_m + w.rain_extinction_per_m
    assert w.cloud_base_height_m == skyfall.sky.cloud_base_m(10.0)
    # and a frame's transmittance is e^(-σ d) with that σ along the ray of each pixel
    r = Renderer(32, 24, backend="cpu")
    depth = np.full((24, 32), 100.0, np.float32)
    photo = PhotoScene(np.full((24, 32, 3), 0.3, np.float32), depth, vertical_fov_deg=40.0, encoding="linear")
    t = r.render(photo, Weather(visibility_m=2000.0)).layers["transmittance"]
    fx, fy, cx, cy = photo.camera.intrinsics()
    y, x = np.mgrid[0:24, 0:32] + 0.5
    d = 100.0 * np.sqrt(((x - cx) / fx) ** 2 + ((y - cy) / fy) ** 2 + 1.0)
    np.testing.assert_allclose(t, np.exp(-(-math.log(0.02) / 2000.0) * d), rtol=2e-4)


def test_layers_are_the_cores() -> None:
    r = Renderer(16, 12, backend="cpu")
    glass = windshield.Windshield(5.0, glass_width_mm=100.0, glass_height_mm=100.0, wipers=0)
    snowy = Weather(rain_rate_mm_h=5.0, snow_rate_mm_h=0.5, visibility_m=500.0, windshield=glass)
    cover = snow.accumulate(scenes.street(), snowy, duration_s=600.0, dt_s=600.0, resolution_m=4.0)
    sunny = dataclasses.replace(snowy, sky=12, sun_elevation_deg=30.0, sun_azimuth_deg=200.0, clouds="cumulus", rain_duration_s=None)
    f = r.render(scenes.street(), dataclasses.replace(sunny, snow_cover=cover))
    assert list(f.layers) == list(_core.LAYERS)
    assert "cloud_alpha" not in r.render(scenes.street(), dataclasses.replace(snowy, snow_cover=cover)).layers
    rain_only = r.render(scenes.street(), Weather(rain_rate_mm_h=5.0, visibility_m=500.0))
    assert list(rain_only.layers) == ["transmittance", "rain_alpha", "rain_depth_m"]
    snow_only = r.render(scenes.street(), Weather(snow_rate_mm_h=0.5))
    assert list(snow_only.layers) == ["transmittance", "snow_alpha"]
    assert list(r.render(scenes.street(), Weather(visibility_m=500.0)).layers) == ["transmittance"]
    assert r.render(scenes.street(), Weather()).layers == {}


def test_map_failures_name_what_the_user_set() -> None:
    # A camera far from a box scene's boxes, and an ambient spacing too fine for the scene:
    # the messages name the camera's position_m and ambient_spacing_m (and what would work),
    # not the map's bounds or its own spacing_m.
    r = Renderer(16, 12, backend="cpu")
    far = skyfall.Camera((1e7, 1.6, 1e7))
    with pytest.raises(ValueError, match=r"camera at position_m = \(1e\+07, 1.6, 1e\+07\)") as e:
        r.render(scenes.street(), Weather(rain_rate_mm_h=5.0), camera=far)
    assert "bounds" not in str(e.value)
    with pytest.raises(ValueError, match=r"^ambient_spacing_m = 0.05 m needs .* use ambient_spacing_m >= ([0-9.]+) m") as e:
        r.render(scenes.street(), Weather(rain_rate_mm_h=5.0), ambient_spacing_m=0.05)
    suggested = float(str(e.value).rsplit(">= ", 1)[1].split()[0])
    r.render(scenes.street(), Weather(rain_rate_mm_h=5.0), ambient_spacing_m=suggested, ambient_samples=4)
