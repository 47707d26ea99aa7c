"""The windshield as the frame's last stage (``skyfall_core::windshield::stage``), drawn by the
core in the frame's one call: the drops where the glass's geometry (computed here) puts them, the
blades as the numpy reference below draws them, and a preset's glass on the frames' clock (a clip
shows the drops moving; each frame is the same bits whatever frames came before)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skyfall import Camera, PhotoScene, Renderer, Weather
from skyfall import windshield as ws

W, H = 96, 64
GREY = 0.3


def grey_photo() -> PhotoScene:
    """A uniform linear photo 5 m away: refracted through any drop, it stays itself."""
    cam = Camera((0.0, 1.3, 0.0), vertical_fov_deg=50.0)
    return PhotoScene(np.full((H, W, 3), GREY, np.float32), np.full((H, W), 5.0, np.float32), camera=cam, encoding="linear")


def view_of(glass: ws.Windshield, scene: PhotoScene) -> tuple[float, float, float, float, float]:
    """(fx, cx, cy, px per glass mm, foreshortening): the glass just covers the frame, its
    centre at the frame's centre, its slope foreshortened by sin(tilt)."""
    fx, _fy, cx, cy = scene.camera.intrinsics()
    p = glass.params
    fore = math.sin(math.radians(max(p["glass_tilt_deg"], 1.0)))
    d_m = max(min(p["glass_width_mm"] * fx / W, p["glass_height_mm"] * fore * fx / H) * 1e-3, 0.2)
    return fx, cx, cy, fx / (d_m * 1e3), fore


def to_px(glass: ws.Windshield, xy_mm: np.ndarray, s: float, fore: float) -> np.ndarray:
    p = glass.params
    x = W / 2 + (xy_mm[:, 0] - p["glass_width_mm"] / 2) * s
    y = H / 2 + (xy_mm[:, 1] - p["glass_height_mm"] / 2) * s * fore
    return np.stack([x, y], axis=1).astype(np.float32)


def blades_reference(rgb: np.ndarray, glass: ws.Windshield, s: float, fore: float) -> np.ndarray:
    """The wipers' blades over ``rgb``: albedo 0.04, anti-aliased over one pixel across their
    edges and at their tips, in numpy."""
    out = rgb.copy()
    p = glass.params
    yy, xx = np.mgrid[0:H, 0:W].astype(np.float64) + 0.5
    gx = (xx - W / 2) / s + p["glass_width_mm"] / 2
    gy = (yy - H / 2) / (s * fore) + p["glass_height_mm"] / 2
    for (px0, py0), angle, length, width in glass.blades():
        dx, dy = gx - px0, py0 - gy
        c, sn = math.cos(angle), math.sin(angle)
        along, across = dx * c + dy * sn, -dx * sn + dy * c
        cover = np.clip((0.5 * width - np.abs(across)) * s * math.hypot(sn, c * fore) + 0.5, 0, 1)
        cover = (cover * np.clip((length - along) * s + 0.5, 0, 1) * (along >= 0)).astype(np.float32)[..., None]
        out = out * (1 - cover) + cover * np.float32(0.04)
    return out


def test_the_drops_are_where_the_glass_puts_them_and_the_layers_are_their_field() -> None:
    glass = ws.Windshield(60.0, glass_width_mm=400.0, glass_height_mm=300.0, wipers=0, seed=1)
    glass.step(2.0)
    scene = grey_photo()
    frame = Renderer(W, H, backend="cpu").render(scene, Weather(windshield=glass))
    assert set(frame.layers) == {"drop_mask", "drop_height"}
    fx, cx, cy, s, fore = view_of(glass, scene)
    centres_mm, radii_mm = glass.metaballs()
    radii = (radii_mm * s).astype(np.float32)
    keep = radii > 0.05
    field = ws.metaball_height_map(to_px(glass, centres_mm, s, fore)[keep], radii[keep], (H, W))
    slope = 1.5 * s * math.tan(math.radians(30.0))  # the mean of the 40 and 20 deg contact angles
    _, mask = ws.refract(np.full((H, W, 3), GREY, np.float32), field, focal_px=fx, slope_px=slope, principal_px=(cx, cy))
    got = frame.layers["drop_mask"]
    assert 0.05 < got.mean() < 0.95, got.mean()
    # over the whole frame: centre, edges, top and bottom rows
    np.testing.assert_allclose(got, mask, atol=2e-3)
    for rows in (slice(0, 1), slice(H - 1, H), slice(H // 2 - 4, H // 2 + 4)):
        np.testing.assert_allclose(got[rows], mask[rows], atol=2e-3)
    np.testing.assert_allclose(frame.layers["drop_height"], np.maximum(field - 0.5, 0.0), atol=2e-3)
    # a uniform background refracts to itself; no wipers, no blades
    np.testing.assert_allclose(frame.rgb, GREY, atol=1e-6)


def test_the_blades_are_drawn_where_the_wipers_stand() -> None:
    glass = ws.Windshield(10.0, glass_width_mm=500.0, glass_height_mm=300.0, wipers=2, wiper_period_s=2.0, seed=3)
    glass.step(0.4)
    scene = grey_photo()
    frame = Renderer(W, H, backend="cpu").render(scene, Weather(windshield=glass))
    _fx, _cx, _cy, s, fore = view_of(glass, scene)
    want = blades_reference(np.full((H, W, 3), GREY, np.float32), glass, s, fore)
    dark = want[..., 0] < 0.2
    assert 0.01 < dark.mean() < 0.3
    np.testing.assert_allclose(frame.rgb, want, atol=1e-5)


def test_a_clip_through_a_preset_shows_moving_drops_and_each_frame_is_its_own() -> None:
    rng = np.random.default_rng(0)
    scene = PhotoScene(rng.integers(0, 256, (H, W, 3), dtype=np.uint8), np.full((H, W), 8.0, np.float32), camera=Camera((0.0, 1.3, 0.0)))
    weather = Weather(windshield="rain")
    r = Renderer(W, H, backend="cpu")
    times = [0.5 + k / 30.0 for k in range(3)]
    clip = list(r.render_sequence(scene, weather, n_frames=3, fps=30.0, start_s=0.5, seed=0))
    masks = [f.layers["drop_mask"] for f in clip]
    # the glass moves on between frames, a little: the wipers sweep, drops arrive and slide
    for a, b in zip(masks, masks[1:], strict=False):
        changed = np.mean(np.abs(a - b) > 0.5)
        assert 0.0 < changed < 0.5, changed
    # each frame alone, in another order, is the same bits (the clock's grid, not the history)
    for t, f in reversed(list(zip(times, clip, strict=True))):
        again = r.render(scene, weather, time_s=t, seed=0)
        np.testing.assert_array_equal(again.rgb, f.rgb)
        np.testing.assert_array_equal(again.layers["drop_mask"], f.layers["drop_mask"])
    # one epoch later the glass is the same
    epoch = ws.clock("rain", seed=0).epoch_s
    assert epoch == pytest.approx(ws.EPOCH_PERIODS * ws.PRESETS["rain"]["wiper_period_s"])
    later = r.render(scene, weather, time_s=times[1] + epoch, seed=0)
    np.testing.assert_array_equal(later.layers["drop_mask"], masks[1])
    # warm() is the glass the frame draws
    w = ws.warm("rain", times[1], seed=0)
    np.testing.assert_array_equal(r.render(scene, Weather(windshield=w), seed=0).layers["drop_mask"], masks[1])


def test_a_bad_clock_is_refused_naming_its_parameter() -> None:
    with pytest.raises(ValueError, match="is not a preset"):
        ws.clock("hail")
    with pytest.raises(ValueError, match="warm_up_periods"):
        ws.clock("rain", warm_up_periods=0)
    w = ws.Windshield(5.0, glass_width_mm=100.0, glass_height_mm=100.0, wipers=0)
    from skyfall import _core

    with pytest.raises(ValueError, match="period_s"):
        _core.GlassClock(w._core, 0.0, 4)
    with pytest.raises(ValueError, match="epoch_periods"):
        _core.GlassClock(w._core, 1.0, 0)
    with pytest.raises(ValueError, match="time_s"):
        _core.GlassClock(w._core, 1.0, 2).at(math.nan)
