"""``layers=``: every entry point returns the ground-truth layers asked for by name (the core's
``_core.LAYERS``), each with its neutral value where no pass drew it; unknown names are refused
with the list of layers; the old ``rain_alpha_out`` / ``snow_alpha_out`` keywords still work
and warn."""

from __future__ import annotations

import numpy as np
import pytest

from skyfall import Camera, PhotoScene, Renderer, Weather, _core, scenes
from skyfall.render import FUSED_LAYERS, Srgb8Frame

W, H = 64, 36
RAIN = Weather(rain_rate_mm_h=30.0, visibility_m=400.0)


@pytest.fixture(scope="module")
def cpu() -> Renderer:
    return Renderer(W, H, backend="cpu")


def photo8() -> PhotoScene:
    rng = np.random.default_rng(4)
    image = rng.integers(0, 256, (H, W, 3), dtype=np.uint8)
    depth = np.full((H, W), 12.0, np.float32)
    depth[: H // 3] = np.inf
    return PhotoScene(image, depth, camera=Camera((0.0, 1.6, 0.0)))


def test_render_returns_exactly_the_layers_asked_for(cpu: Renderer) -> None:
    street = scenes.street()
    everything = cpu.render(street, RAIN, seed=3)
    assert "snow_alpha" not in everything.layers  # no snow: not drawn
    asked = ("snow_alpha", "rain_alpha", "rain_depth_m", "cloud_alpha")
    frame = cpu.render(street, RAIN, seed=3, layers=asked)
    assert tuple(frame.layers) == asked
    np.testing.assert_array_equal(frame.rgb, everything.rgb)
    np.testing.assert_array_equal(frame.layers["rain_alpha"], everything.layers["rain_alpha"])
    np.testing.assert_array_equal(frame.layers["rain_depth_m"], everything.layers["rain_depth_m"])
    # the layers no pass drew: their neutral value, as writable float32 (H, W) arrays
    for name in ("snow_alpha", "cloud_alpha"):
        a = frame.layers[name]
        assert a.dtype == np.float32 and a.shape == (H, W) and a.flags.writeable
        assert np.all(a == _core.LAYER_NEUTRAL[name])
    assert cpu.render(street, RAIN, seed=3, layers=()).layers == {}


def test_render_into_out_reuses_its_arrays_for_the_layers_not_drawn(cpu: Renderer) -> None:
    street = scenes.street()
    first = cpu.render(street, RAIN, seed=1, layers=("rain_alpha", "snow_alpha"))
    snow = first.layers["snow_alpha"]
    snow[...] = 0.5  # a value the next frame must overwrite
    again = cpu.render(street, RAIN, seed=2, layers=("rain_alpha", "snow_alpha"), out=first)
    assert again.layers["snow_alpha"] is snow and not snow.any()
    assert again.layers["rain_alpha"] is first.layers["rain_alpha"]
    np.testing.assert_array_equal(again.layers["rain_alpha"], cpu.render(street, RAIN, seed=2).layers["rain_alpha"])


def test_unknown_layer_names_are_refused_with_the_valid_ones(cpu: Renderer) -> None:
    listed = ", ".join(map(repr, _core.LAYERS))
    for call in (
        lambda: cpu.render(scenes.street(), RAIN, layers=("rain_alpha", "rain_mask")),
        lambda: cpu.render_srgb8(photo8(), RAIN, layers=("rain_mask",)),
        lambda: cpu.render_srgb8(photo8(), RAIN, layers={"rain_mask": np.zeros((H, W), np.float32)}),
        lambda: cpu.render_sequence(scenes.street(), RAIN, n_frames=2, layers=("rain_mask",)),
        lambda: cpu.render_sequence_srgb8(photo8(), RAIN, n_frames=2, layers=("rain_mask",)),
    ):
        with pytest.raises(ValueError, match="'rain_mask' is not a layer") as e:
            call()
        assert listed in str(e.value)
    with pytest.raises(TypeError, match="sequence of layer names"):
        cpu.render(scenes.street(), RAIN, layers="rain_alpha")
    with pytest.raises(TypeError, match="layer names"):
        cpu.render(scenes.street(), RAIN, layers=(1,))  # type: ignore[arg-type]


def test_render_srgb8_with_layers_returns_the_image_and_the_layers(cpu: Renderer) -> None:
    scene = photo8()
    image = cpu.render_srgb8(scene, RAIN, seed=5)
    assert isinstance(image, np.ndarray) and image.dtype == np.uint8  # no layers: the image, as before
    assert cpu.fuses_srgb8(scene, RAIN, layers=FUSED_LAYERS)
    got = cpu.render_srgb8(scene, RAIN, seed=5, layers=("rain_alpha", "snow_alpha"))
    assert isinstance(got, Srgb8Frame)
    img, layers = got
    np.testing.assert_array_equal(img, image)
    assert tuple(layers) == ("rain_alpha", "snow_alpha")
    float_frame = cpu.render(scene, RAIN, seed=5)
    np.testing.assert_allclose(layers["rain_alpha"], float_frame.layers["rain_alpha"], atol=1e-6)
    assert layers["rain_alpha"].max() > 0.001 and not layers["snow_alpha"].any()
    # a dict names the arrays to fill: those come back, filled
    alpha = np.full((H, W), -1.0, np.float32)
    out = np.empty((H, W, 3), np.uint8)
    again = cpu.render_srgb8(scene, RAIN, seed=5, out=out, layers={"rain_alpha": alpha})
    assert again.image is out and again.layers["rain_alpha"] is alpha
    np.testing.assert_array_equal(alpha, layers["rain_alpha"])


def test_a_layer_the_fused_path_does_not_fill_takes_the_float_path(cpu: Renderer) -> None:
    scene = photo8()
    assert not cpu.fuses_srgb8(scene, RAIN, layers=("rain_alpha", "transmittance"))
    image, layers = cpu.render_srgb8(scene, RAIN, seed=5, layers=("transmittance", "rain_depth_m", "snow_depth_m"))
    frame = cpu.render(scene, RAIN, seed=5)
    np.testing.assert_array_equal(layers["transmittance"], frame.layers["transmittance"])
    np.testing.assert_array_equal(layers["rain_depth_m"], frame.layers["rain_depth_m"])
    assert np.all(layers["snow_depth_m"] == 0.0)  # no cover: its neutral value
    # the float path encoded: within one code of the fused path's bytes
    fused = cpu.render_srgb8(scene, RAIN, seed=5)
    assert np.abs(image.astype(int) - fused.astype(int)).max() <= 1


def test_the_sequences_return_the_layers_of_each_frame(cpu: Renderer) -> None:
    street = scenes.street()
    frames = list(cpu.render_sequence(street, RAIN, n_frames=2, fps=10.0, seed=2, layers=("rain_alpha", "snow_alpha")))
    for k, frame in enumerate(frames):
        assert tuple(frame.layers) == ("rain_alpha", "snow_alpha")
        np.testing.assert_array_equal(frame.layers["rain_alpha"], cpu.render(street, RAIN, seed=2, time_s=k / 10.0).layers["rain_alpha"])
    scene = photo8()
    alpha = np.empty((H, W), np.float32)
    seq = list(cpu.render_sequence_srgb8(scene, RAIN, n_frames=2, fps=10.0, seed=2, layers={"rain_alpha": alpha}))
    assert all(isinstance(f, Srgb8Frame) and f.layers["rain_alpha"] is alpha for f in seq)
    for k, f in enumerate(cpu.render_sequence_srgb8(scene, RAIN, n_frames=2, fps=10.0, seed=2, layers=("rain_alpha",))):
        want = cpu.render_srgb8(scene, RAIN, seed=2, time_s=k / 10.0, layers=("rain_alpha",))
        np.testing.assert_array_equal(f.image, want.image)
        np.testing.assert_array_equal(f.layers["rain_alpha"], want.layers["rain_alpha"])
    assert not np.array_equal(*(f.layers["rain_alpha"] for f in cpu.render_sequence_srgb8(scene, RAIN, n_frames=2, fps=10.0, seed=2, layers=("rain_alpha",))))


def test_the_old_out_keywords_still_fill_their_arrays_and_warn(cpu: Renderer) -> None:
    scene = photo8()
    rain = np.empty((H, W), np.float32)
    snow = np.full((H, W), 7.0, np.float32)
    with pytest.warns(DeprecationWarning, match=r"rain_alpha_out= and snow_alpha_out= deprecated: .*layers=") as record:
        image = cpu.render_srgb8(scene, RAIN, seed=5, rain_alpha_out=rain, snow_alpha_out=snow)
    assert [x.filename for x in record] == [__file__]  # the warning names the caller's line
    assert isinstance(image, np.ndarray)  # the image alone, as before
    want = cpu.render_srgb8(scene, RAIN, seed=5, layers=("rain_alpha",))
    np.testing.assert_array_equal(image, want.image)
    np.testing.assert_array_equal(rain, want.layers["rain_alpha"])
    assert not snow.any()
    with pytest.warns(DeprecationWarning, match="rain_alpha_out= deprecated"):
        images = list(cpu.render_sequence_srgb8(scene, RAIN, n_frames=1, seed=5, rain_alpha_out=rain))
    assert isinstance(images[0], np.ndarray)
    np.testing.assert_array_equal(images[0], image)
    # the old names still name the arrays in the messages
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match="rain_alpha_out must be .* got dtype float64"):
        cpu.render_srgb8(scene, RAIN, rain_alpha_out=np.zeros((H, W)))  # type: ignore[arg-type]
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match="give the layers once"):
        cpu.render_srgb8(scene, RAIN, rain_alpha_out=rain, layers=("rain_alpha",))  # type: ignore[call-overload]
