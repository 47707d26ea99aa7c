"""Renderer.render_sequence and render_sequence_srgb8: frames one at a time, equal to render
and render_srgb8 at the same times bit for bit, out= reused, every argument checked at call."""

from __future__ import annotations

import gc
import tracemalloc
from collections.abc import Iterator

import numpy as np
import pytest

from skyfall import Camera, Frame, PhotoScene, Renderer, Weather, scenes

W, H = 96, 64
RAIN = Weather(rain_rate_mm_h=30.0, visibility_m=800.0, wind_m_s=(2.0, 0.0, 0.0))


@pytest.fixture(scope="module", params=["cpu", "gpu"])
def renderer(request: pytest.FixtureRequest) -> Renderer:
    return Renderer(W, H, backend=request.param)


def photo8() -> PhotoScene:
    rng = np.random.default_rng(2)
    depth = np.full((H, W), 12.0, np.float32)
    depth[: H // 4] = np.inf
    return PhotoScene(rng.integers(0, 256, (H, W, 3), dtype=np.uint8), depth, camera=Camera((0.0, 1.6, 0.0)))


def same_frame(a: Frame, b: Frame) -> None:
    assert a.rgb.tobytes() == b.rgb.tobytes() and a.depth_m.tobytes() == b.depth_m.tobytes()
    assert sorted(a.layers) == sorted(b.layers) and a.stats == b.stats
    for k in a.layers:
        assert a.layers[k].tobytes() == b.layers[k].tobytes(), k


def test_frames_are_render_at_their_times_bit_for_bit(renderer):
    opts = {"seed": 4, "cull_threshold": 0.5, "ambient_spacing_m": 2.0, "ambient_samples": 16}
    seq = renderer.render_sequence(scenes.street(), RAIN, n_frames=3, fps=24.0, start_s=0.5, **opts)
    assert isinstance(seq, Iterator) and not isinstance(seq, list)
    frames = list(seq)
    assert len(frames) == 3
    for k, f in enumerate(frames):
        same_frame(f, renderer.render(scenes.street(), RAIN, time_s=0.5 + k / 24.0, **opts))
    assert not np.array_equal(frames[0].layers["rain_alpha"], frames[1].layers["rain_alpha"])  # the rain moves
    # the options are passed on: another spacing or threshold gives other frames
    other = next(renderer.render_sequence(scenes.street(), RAIN, n_frames=1, fps=24.0, start_s=0.5, seed=4))
    assert other.stats != frames[0].stats or other.rgb.tobytes() != frames[0].rgb.tobytes()


def test_with_out_every_frame_comes_back_in_the_same_arrays(renderer):
    out = renderer.render(scenes.street(), Weather(visibility_m=800.0))  # haze, no rain layers yet: the first frame adds them
    want = [renderer.render(scenes.street(), RAIN, seed=1, time_s=k / 30.0) for k in range(4)]
    arrays = None
    for k, f in enumerate(renderer.render_sequence(scenes.street(), RAIN, n_frames=4, seed=1, out=out)):
        assert f.rgb is out.rgb and f.depth_m is out.depth_m and f.layers["transmittance"] is out.layers["transmittance"]
        if arrays is None:
            arrays = (f.layers["rain_alpha"], f.layers["rain_depth_m"])
        assert f.layers["rain_alpha"] is arrays[0] and f.layers["rain_depth_m"] is arrays[1]
        same_frame(f, want[k])


def test_memory_does_not_grow_with_the_number_of_frames():
    r = Renderer(160, 120, backend="cpu")
    frame_bytes = 160 * 120 * 4 * 7  # rgb, depth and three layers, float32
    next(r.render_sequence(scenes.street(), RAIN, n_frames=1))  # ambient map and caches built

    def peak(n: int) -> int:
        gc.collect()
        tracemalloc.start()
        try:
            for f in r.render_sequence(scenes.street(), RAIN, n_frames=n):
                assert f.rgb.shape == (120, 160, 3)
            return tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()

    one, twelve = peak(1), peak(12)
    assert one >= frame_bytes  # the frames are seen by tracemalloc (numpy reports them)
    # a list of 12 frames would be 11 frames more; one at a time, at most the next frame more
    assert twelve < one + 1.5 * frame_bytes, (one, twelve)


def test_srgb8_frames_are_render_srgb8_at_their_times(renderer):
    scene = photo8()
    want = [renderer.render_srgb8(scene, RAIN, seed=2, time_s=1.0 + k / 30.0) for k in range(3)]
    alpha_want = [renderer.render(scene, RAIN, seed=2, time_s=1.0 + k / 30.0).layers["rain_alpha"] for k in range(3)]
    fresh = list(renderer.render_sequence_srgb8(scene, RAIN, n_frames=3, seed=2, start_s=1.0))
    assert [f.tobytes() for f in fresh] == [w.tobytes() for w in want]
    assert len({id(f) for f in fresh}) == 3  # a new array per frame without out=
    out = np.empty((H, W, 3), np.uint8)
    alpha = np.full((H, W), -1.0, np.float32)
    for k, (img, layers) in enumerate(renderer.render_sequence_srgb8(scene, RAIN, n_frames=3, seed=2, start_s=1.0, out=out, layers={"rain_alpha": alpha})):
        assert img is out and img.tobytes() == want[k].tobytes() and layers["rain_alpha"] is alpha
        np.testing.assert_allclose(alpha, alpha_want[k], atol=1e-6)
    # box scenes take the float path and encode it, the same as render_srgb8
    street = next(renderer.render_sequence_srgb8(scenes.street(), RAIN, n_frames=1, seed=2))
    assert street.tobytes() == renderer.render_srgb8(scenes.street(), RAIN, seed=2).tobytes()


@pytest.mark.parametrize("srgb8", [False, True])
@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"n_frames": 0}, ValueError, r"n_frames = 0 is outside the valid range \[1, 1000000\]"),
        ({"fps": 0.0}, ValueError, r"fps = 0.0 is outside the valid range \(0, 10000\]"),
        ({"start_s": float("nan")}, ValueError, r"start_s = nan"),
        ({"fps": 1e-300, "n_frames": 2}, ValueError, r"start_s = 0.0 and fps = 1e-300"),
        ({"seed": -1}, ValueError, r"seed = -1"),
        ({"cull_threshold": -1.0}, ValueError, r"cull_threshold = -1.0"),
        ({"ambient_spacing_m": 0.01}, ValueError, r"ambient_spacing_m = 0.01"),
        ({"ambient_samples": 2}, ValueError, r"ambient_samples = 2"),
        ({"progress": "yes"}, TypeError, r"progress must be True or False, got str"),
        ({"camera": "front"}, TypeError, r"camera must be a skyfall.Camera"),
        ({"weather": "rain"}, TypeError, r"weather must be a skyfall.Weather"),
        ({"scene": "street"}, TypeError, r"scene must be a BoxScene or PhotoScene"),
    ],
)
def test_bad_arguments_raise_at_the_call_not_at_the_first_frame(srgb8, kwargs, error, message):
    r = Renderer(16, 12, backend="cpu")
    args = {"scene": scenes.street(), "weather": RAIN, "n_frames": 2, **kwargs}
    scene, weather = args.pop("scene"), args.pop("weather")
    method = r.render_sequence_srgb8 if srgb8 else r.render_sequence
    with pytest.raises(error, match=message):
        method(scene, weather, **args)  # no next(): the call itself raises


def test_bad_outputs_raise_at_the_call():
    r = Renderer(W, H, backend="cpu")
    with pytest.raises(ValueError, match=r"out's rgb must be .* got shape"):
        r.render_sequence(scenes.street(), RAIN, n_frames=2, out=Renderer(W + 1, H, backend="cpu").render(scenes.street()))
    with pytest.raises(TypeError, match="out must be a skyfall.Frame"):
        r.render_sequence(scenes.street(), RAIN, n_frames=2, out=np.zeros((H, W, 3), np.float32))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"layers\['rain_alpha'\] must be .* got dtype float64"):
        r.render_sequence_srgb8(photo8(), RAIN, n_frames=2, layers={"rain_alpha": np.zeros((H, W))})  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="the photo is"):
        Renderer(W + 2, H, backend="cpu").render_sequence_srgb8(photo8(), RAIN, n_frames=2, out=np.empty((H, W, 3), np.uint8))


def test_progress_bar_counts_the_frames(capsys):
    r = Renderer(16, 12, backend="cpu")
    frames = r.render_sequence(scenes.street(), RAIN, n_frames=3, progress=True)
    assert capsys.readouterr().err == ""  # nothing rendered, no bar yet
    assert len(list(frames)) == 3
    assert "3/3" in capsys.readouterr().err
    assert len(list(r.render_sequence_srgb8(scenes.street(), RAIN, n_frames=2, progress=np.bool_(True)))) == 2
    assert "2/2" in capsys.readouterr().err
