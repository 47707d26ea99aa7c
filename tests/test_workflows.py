"""The workflows of issue 15 that need no batch: a frame's layers whatever its passes
(``Frame.layer``), frames shown in Jupyter (``_repr_png_``, ``_repr_html_``, decoded back
with Pillow, a decoder independent of the OpenImageIO that encoded them), the sliders of
``skyfall.widgets.explore`` (against direct renders), and ``skyfall.testing.with_weather``."""

from __future__ import annotations

import base64
import dataclasses
import io as pyio
import math
import re
import sys

import numpy as np
import pytest
from PIL import Image

from skyfall import Camera, PhotoScene, Renderer, Weather, _core, display, io, scenes, snow, testing, widgets
from skyfall.windshield import Windshield

W, H = 48, 27


@pytest.fixture(scope="module")
def renderer() -> Renderer:
    return Renderer(W, H, backend="cpu")


def decode_png(data: bytes) -> np.ndarray:
    with Image.open(pyio.BytesIO(data)) as im:
        assert im.format == "PNG"
        return np.asarray(im)


# ---- Frame.layer --------------------------------------------------------------------------


def test_every_layer_has_a_neutral_value_declared_with_it():
    assert list(_core.LAYER_NEUTRAL) == list(_core.LAYERS)
    assert all(isinstance(v, float) for v in _core.LAYER_NEUTRAL.values())


def test_drawn_layers_are_the_frames_own_arrays(renderer):
    glass = Windshield(20.0, glass_width_mm=200.0, glass_height_mm=150.0, wipers=0)
    glass.step(0.5)
    cover = snow.accumulate(scenes.street(), Weather(snow_rate_mm_h=2.0), duration_s=600.0, dt_s=600.0, resolution_m=4.0)
    weather = Weather(
        rain_rate_mm_h=25.0,
        snow_rate_mm_h=0.5,
        visibility_m=300.0,
        windshield=glass,
        sky=12,
        sun_elevation_deg=30.0,
        sun_azimuth_deg=200.0,
        clouds="cumulus",
        rain_duration_s=None,
    )
    frame = renderer.render(scenes.street(), dataclasses.replace(weather, snow_cover=cover))
    assert set(frame.layers) == set(_core.LAYERS)
    for name in _core.LAYERS:
        assert frame.layer(name) is frame.layers[name]


def test_layers_a_frame_did_not_draw_are_what_a_drawing_pass_leaves_untouched(renderer):
    clear = renderer.render(scenes.street(), Weather())
    assert clear.layers == {}  # unchanged: only what was drawn
    with pytest.raises(KeyError):
        clear.layers["rain_alpha"]
    # the passes' own output where they drew nothing: where no streak lies (alpha 0, depth
    # inf; light rain close by, so that some pixels have none) and in next to no haze
    # (visibility 1e12 m and no rain: transmittance within 1e-6 of 1, the sky's path included)
    # (and a dry windshield: its layers drawn, with no drop on them)
    dry = Windshield(0.0, glass_width_mm=100.0, glass_height_mm=100.0, wipers=0)
    rain = renderer.render(scenes.street(), Weather(rain_rate_mm_h=0.5, rain_near_m=1.0, windshield=dry), seed=3)
    snowy = renderer.render(scenes.street(), Weather(snow_rate_mm_h=0.2, snow_near_m=0.5), seed=3)
    haze = renderer.render(scenes.street(), Weather(visibility_m=1e12))
    bare = snow.accumulate(scenes.street(), Weather(), duration_s=0.0, resolution_m=4.0)  # no snow: depth 0
    cover = renderer.render(scenes.street(), Weather(snow_cover=bare)).layers["snow_depth_m"]
    empty = rain.layers["rain_alpha"] == 0.0
    assert empty.any() and (~empty).any()
    clear_of_flakes = snowy.layers["snow_alpha"] == 0.0
    assert clear_of_flakes.any() and (~clear_of_flakes).any()
    # A cumulus 5 km ahead under a sun: sky pixels off the cloud are the cloud pass's and the
    # sun's untouched values.
    sunny = renderer.render(scenes.street(), Weather(sky=12, sun_elevation_deg=30.0, sun_azimuth_deg=200.0, clouds="cumulus"))
    cloudless = sunny.layers["cloud_alpha"] == 0.0
    sky_px = np.isinf(sunny.depth_m)
    assert cloudless.any() and (~cloudless).any() and sky_px.any()
    # A street wet after the rain: its sky is the wet stage's untouched value.
    wet = renderer.render(scenes.street(), Weather(rain_rate_mm_h=1.0, rain_duration_s=None, dry_s=1.0))
    wet_sky = np.isinf(wet.depth_m)
    assert wet_sky.any() and (wet.layers["wetness"] > 0).any()
    for name in _core.LAYERS:
        layer = clear.layer(name)
        assert layer.shape == (H, W) and layer.dtype == np.float32 and not layer.flags.writeable
        if name == "transmittance":
            untouched = haze.layers[name]
        elif name == "snow_alpha":
            untouched = snowy.layers[name][clear_of_flakes]
        elif name == "snow_depth_m":
            untouched = cover
        elif name == "cloud_alpha":
            untouched = sunny.layers[name][cloudless]
        elif name == "sun_transmittance":
            untouched = sunny.layers[name][sky_px]
        elif name in ("wetness", "puddle_mask"):
            untouched = wet.layers[name][wet_sky]
        else:
            untouched = rain.layers[name][empty]
        assert len(np.unique(layer)) == 1
        np.testing.assert_allclose(untouched, layer[0, 0], rtol=1e-6)
        with pytest.raises(ValueError):
            layer[0, 0] = 0.5  # read-only


def test_a_frame_with_haze_only_gives_zero_rain():
    frame = Renderer(W, H, backend="cpu").render(scenes.street(), Weather(visibility_m=200.0))
    assert sorted(frame.layers) == ["transmittance"]
    assert frame.layer("transmittance") is frame.layers["transmittance"]
    assert not frame.layer("rain_alpha").any() and np.isinf(frame.layer("rain_depth_m")).all()


def test_an_unknown_layer_is_refused_with_the_valid_names(renderer):
    frame = renderer.render(scenes.street())
    with pytest.raises(ValueError, match=r"name = 'rain_mask' is not a layer") as err:
        frame.layer("rain_mask")
    assert all(repr(n) in str(err.value) for n in _core.LAYERS)


# ---- Jupyter display ----------------------------------------------------------------------


def test_repr_png_decodes_to_the_frames_srgb8(renderer):
    frame = renderer.render(scenes.street(), Weather(rain_rate_mm_h=25.0, visibility_m=300.0), seed=1)
    np.testing.assert_array_equal(decode_png(frame._repr_png_()), io.to_srgb8(frame.rgb))


def test_repr_html_shows_the_image_and_each_drawn_layer(renderer):
    frame = renderer.render(scenes.street(), Weather(rain_rate_mm_h=25.0, visibility_m=300.0), seed=1)
    page = frame._repr_html_()
    images = [decode_png(base64.b64decode(b)) for b in re.findall(r'src="data:image/png;base64,([^"]+)"', page)]
    assert len(images) == 1 + len(frame.layers)
    np.testing.assert_array_equal(images[0], io.to_srgb8(frame.rgb))
    names = list(frame.layers)
    alpha = images[1 + names.index("rain_alpha")]
    np.testing.assert_array_equal(alpha, np.rint(frame.layers["rain_alpha"] * 255).astype(np.uint8))
    depth = images[1 + names.index("rain_depth_m")]
    d = frame.layers["rain_depth_m"]
    assert (depth[np.isinf(d)] == 0).all() and (depth[d < 1.0] >= 128).all()
    assert all(n in page for n in names)


def test_without_openimageio_a_frame_falls_back_to_its_text(renderer, monkeypatch):
    frame = renderer.render(scenes.street())
    monkeypatch.setitem(sys.modules, "OpenImageIO", None)  # `import OpenImageIO` now fails
    with pytest.raises(ImportError):
        display.png_bytes(io.to_srgb8(frame.rgb))
    assert frame._repr_png_() is None and frame._repr_html_() is None  # IPython's "none here"


def test_a_large_frame_is_shown_small():
    frame = Renderer(600, 90, backend="cpu").render(scenes.street(), Weather(visibility_m=300.0))
    page = frame._repr_html_()
    first = decode_png(base64.b64decode(re.findall(r"base64,([^\"]+)", page)[0]))
    step = math.ceil(600 / display.THUMBNAIL_PX)
    np.testing.assert_array_equal(first, io.to_srgb8(frame.rgb)[::step, ::step])


# ---- widgets.explore ----------------------------------------------------------------------


def test_the_sliders_spans_are_valid_ranges():
    ranges = {"wind_x_m_s": "wind_m_s"}
    for name, (lo, hi) in widgets.SLIDER_SPANS.items():
        r_lo, r_hi = _core.RANGES[ranges.get(name, name)][:2]
        assert r_lo <= lo < hi <= r_hi, name


def test_explore_renders_what_its_sliders_say():
    street = scenes.street()
    explorer = widgets.explore(street, width=W, height=H, seed=2)
    assert set(explorer.sliders) == {"rain_rate_mm_h", "wind_x_m_s", "visibility_m", "exposure_s", "time_s"}
    assert all(s.continuous_update for s in explorer.sliders.values())  # every slider renders as it moves
    start = explorer.image.value
    direct = Renderer(W, H, backend="cpu")
    np.testing.assert_array_equal(decode_png(start), direct.render_srgb8(street, Weather(rain_rate_mm_h=10.0), seed=2))
    values = {"rain_rate_mm_h": 40.0, "wind_x_m_s": 6.0, "visibility_m": 400.0, "exposure_s": 1 / 250, "time_s": 0.5}
    seen = [start]
    for name, value in values.items():
        explorer.sliders[name].value = value  # as a user's drag does
        assert explorer.image.value not in seen, name  # each move re-rendered a new frame
        seen.append(explorer.image.value)
    cam = street.camera
    camera = Camera(
        tuple(cam.position_m), yaw_deg=cam.yaw_deg, pitch_deg=cam.pitch_deg, vertical_fov_deg=cam.vertical_fov_deg, exposure_s=1 / 250
    )
    want = direct.render_srgb8(
        street,
        Weather(rain_rate_mm_h=40.0, wind_m_s=(6.0, 0.0, 0.0), visibility_m=explorer.sliders["visibility_m"].value),
        camera=camera,
        time_s=0.5,
        seed=2,
    )
    np.testing.assert_allclose(explorer.sliders["visibility_m"].value, 400.0, rtol=1e-9)
    np.testing.assert_array_equal(decode_png(explorer.image.value), want)


def test_explore_a_photo_at_its_own_size():
    photo = PhotoScene(np.full((20, 30, 3), 140, np.uint8))
    explorer = widgets.explore(photo, weather=Weather(rain_rate_mm_h=5.0, visibility_m=math.inf))
    assert "exposure_s" not in explorer.sliders  # a photo keeps its camera
    assert explorer.sliders["visibility_m"].value == widgets.SLIDER_SPANS["visibility_m"][1]
    explorer.sliders["rain_rate_mm_h"].value = 30.0
    want = Renderer(30, 20, backend="cpu").render_srgb8(photo, Weather(rain_rate_mm_h=30.0))  # the top: clear
    np.testing.assert_array_equal(decode_png(explorer.image.value), want)
    with pytest.raises(TypeError, match="scene must be"):
        widgets.explore(photo.srgb8)  # type: ignore[arg-type]


# ---- skyfall.testing ----------------------------------------------------------------------


def photo8() -> np.ndarray:
    rng = np.random.default_rng(0)
    return rng.integers(0, 256, (H, W, 3), dtype=np.uint8)


def test_with_weather_is_the_photo_rendered_directly():
    image = photo8()
    for rate in (0.0, 10.0):
        got = testing.with_weather(image, rain_rate_mm_h=rate, seed=4, visibility_m=500.0)
        want = Renderer(W, H, backend="cpu").render_srgb8(PhotoScene(image), Weather(rain_rate_mm_h=rate, visibility_m=500.0), seed=4)
        np.testing.assert_array_equal(got, want)
    depth = np.full((H, W), 3.0, np.float32)
    got = testing.with_weather(image, rain_rate_mm_h=10.0, depth_m=depth, scene_options={"vertical_fov_deg": 40.0})
    want = Renderer(W, H, backend="cpu").render_srgb8(PhotoScene(image, depth, vertical_fov_deg=40.0), Weather(rain_rate_mm_h=10.0))
    np.testing.assert_array_equal(got, want)


def test_with_weather_changes_more_pixels_as_it_rains_harder():
    image = photo8()
    assert testing.with_weather(image).tobytes() == image.tobytes()  # clear: the bytes as they are
    changed = [float((testing.with_weather(image, rain_rate_mm_h=r) != image).any(-1).mean()) for r in (1.0, 50.0)]
    assert 0.0 < changed[0] < changed[1]


def test_with_weather_says_what_is_wrong():
    with pytest.raises(TypeError, match="image_uint8 must be a uint8 array"):
        testing.with_weather(photo8() / 255.0)
    with pytest.raises(ValueError, match=r"image_uint8 must have shape \(H, W, 3\)"):
        testing.with_weather(photo8()[..., 0])
    with pytest.raises(ValueError, match="rain_rate_mm_h"):
        testing.with_weather(photo8(), rain_rate_mm_h=600.0)
    with pytest.raises(ValueError, match="Renderer"):
        testing.with_weather(photo8(), renderer=Renderer(10, 10, backend="cpu"))


def test_renderer_cache_makes_one_renderer_per_size():
    cache = testing.RendererCache()
    a, b = cache(W, H), cache(H, W)
    assert a is cache(W, H) and a is not b and (b.width, b.height) == (H, W)
    assert cache.for_image(np.zeros((H, W, 3), np.uint8)) is a
    with pytest.raises(ValueError, match="width"):
        cache(0, 10)
    with pytest.raises(ValueError, match="backend"):
        testing.RendererCache("tpu")


def test_weather_fields_pass_through_unchanged():
    # the helper's keyword arguments are Weather's own: a field it does not know is an error
    assert {f.name for f in dataclasses.fields(Weather)} >= {"visibility_m", "wind_m_s", "rain_near_m"}
    with pytest.raises(TypeError, match="hail_rate"):
        testing.with_weather(photo8(), hail_rate_mm_h=1.0)
