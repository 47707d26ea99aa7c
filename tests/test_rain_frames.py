"""Rain streaks in frames, on both backends: physics, depth, stereo, time, lights, ground truth."""

from __future__ import annotations

import numpy as np
import pytest
from skimage.metrics import structural_similarity

from skyfall import Camera, PhotoScene, Renderer, Weather, rain, scenes

W, H = 200, 120


@pytest.fixture(scope="module", params=["cpu", "gpu"])
def renderer(request: pytest.FixtureRequest) -> Renderer:
    # Every frame test on both backends (the GPU's on lavapipe in CI): streaks are prepared on
    # the CPU and composited by either backend, so each property must hold on both.
    return Renderer(W, H, backend=request.param)


def open_air(depth: float = np.inf) -> PhotoScene:
    img = np.full((H, W, 3), 0.1, np.float32)
    cam = Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0)
    return PhotoScene(img, np.full((H, W), depth, np.float32), camera=cam, encoding="linear", airlight="sky")


def test_no_rain_is_the_haze_only_frame(renderer):
    hazy = Weather(visibility_m=500.0)
    a = renderer.render(scenes.street(), hazy)
    b = renderer.render(scenes.street(), Weather(visibility_m=500.0, rain_rate_mm_h=0.0, wind_m_s=(5.0, 0.0, 0.0)))
    assert a.rgb.tobytes() == b.rgb.tobytes()
    assert "rain_alpha" not in b.layers and b.stats == {}


def test_heavier_rain_covers_more(renderer):
    means = [renderer.render(open_air(), Weather(rain_rate_mm_h=r), seed=4).layers["rain_alpha"].mean() for r in (1, 5, 20, 100)]
    assert np.all(np.diff(means) > 0), means


@pytest.mark.parametrize("exposure_s", [1 / 30, 1e-3, 1e-4])
def test_opacity_area_matches_the_drops_seen(renderer, exposure_s):
    # Every streak adds alpha * w * L = pi w^2 / (4 cos theta) px^2 of coverage (the drop's
    # cross-section, its image stretched by sec theta off the axis), w = D f / z:
    # summed over the drops in view (computed here from the drops' positions), it is the
    # frame's total rain_alpha, up to the capsule caps, overlaps and the frame edges (5 %).
    # The per-drop reference draws exactly the drops rain.drops lists. Short exposures too:
    # drops that move less than a pixel (most here at 1e-4 s) still carry pi w^2 / 4 (they carried
    # 1.6x and 3.7x that at 1e-3 and 1e-4 s before paths were lengthened to a pixel).
    weather = Weather(rain_rate_mm_h=20.0, rain_near_m=4.0, rain_method="drops")
    img = np.full((H, W, 3), 0.1, np.float32)
    cam = Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0, exposure_s=exposure_s)
    scene = PhotoScene(img, np.full((H, W), np.inf, np.float32), camera=cam, encoding="linear", airlight="sky")
    frame = renderer.render(scene, weather, seed=2)
    cam = scene.camera
    d = rain.drops(cam.position_m, weather, seed=2, ground=False)
    px, z = cam.project(d.position_m)
    fx, fy, _, _ = cam.intrinsics()
    inside = (z > 0.3) & (px[:, 0] > 30) & (px[:, 0] < W - 30) & (px[:, 1] > 20) & (px[:, 1] < H - 20)
    w = d.diameter_m[inside] * 0.5 * (fx + fy) / z[inside]
    # off the axis by theta a drop images to an ellipse of the disc's area times sec theta
    sec = np.linalg.norm(d.position_m[inside] - np.asarray(cam.position_m), axis=1) / z[inside]
    assert inside.sum() > 500
    got = frame.layers["rain_alpha"][20 : H - 20, 30 : W - 30].sum()
    # streaks of drops near the window's edge spill in or out: compare with both bounds' mean
    assert got == pytest.approx(np.pi / 4 * np.sum(w**2 * sec), rel=0.1)


@pytest.mark.parametrize(("method", "depth"), [("drops", 0.3), ("billboards", 0.8)])
def test_streaks_hide_behind_the_scene(renderer, method, depth):
    # Behind a photo `depth` m away only streaks nearer than that show. Drops fill the space
    # up to 0.3 m; billboards stand on planes through voxel centres, which reach 0.3 m only off
    # to the side of this camera, out of its view.
    w = Weather(rain_rate_mm_h=50.0, rain_method=method)
    near = renderer.render(open_air(depth=depth), w, seed=1)
    far = renderer.render(open_air(), w, seed=1)
    lit = near.layers["rain_alpha"] > 0
    assert lit.any()
    assert near.layers["rain_depth_m"][lit].max() < depth
    assert np.isinf(near.layers["rain_depth_m"][~lit]).all()
    # Opacity is spread evenly in depth (a drop's opacity-area goes as 1/z², the drops in a
    # shell as z² dz), so a wall at `depth` keeps about depth / rain_near_m of it: twice that
    # bounds it.
    ratio = near.layers["rain_alpha"].mean() / far.layers["rain_alpha"].mean()
    assert ratio < 2 * depth / w.rain_near_m, ratio


def test_no_rain_beyond_a_near_wall(renderer):
    cam = Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0)
    wall = scenes.boxes([{"min": (-20, 0, -2.5), "max": (20, 20, -2.0)}], camera=cam)
    f = renderer.render(wall, Weather(rain_rate_mm_h=50.0), seed=3)
    on_wall = np.isfinite(f.depth_m)
    lit = (f.layers["rain_alpha"] > 0) & on_wall
    assert lit.sum() > 100
    assert np.all(f.layers["rain_depth_m"][lit] <= f.depth_m[lit] + 1e-4)
    assert np.all(f.layers["rain_depth_m"][lit] < 2.0 / 0.5)  # within the wall's reach (off-axis rays)


def test_stereo_cameras_see_the_same_drops():
    weather = Weather(rain_rate_mm_h=10.0, wind_m_s=(2.0, 0.0, -1.0))
    left = rain.drops((0.0, 1.6, 0.0), weather, seed=7)
    right = rain.drops((0.5, 1.6, 0.0), weather, seed=7)
    lk = {tuple(i): k for k, i in enumerate(left.id)}
    shared = [(lk[tuple(i)], k) for k, i in enumerate(right.id) if tuple(i) in lk]
    assert len(shared) > 0.5 * len(right.id)
    a, b = np.array(shared).T
    # The same drops: the core keeps them in f32 relative to each centre, so their world
    # positions agree to f32's rounding of a few metres (< 1e-6 m), not bit for bit.
    np.testing.assert_allclose(left.position_m[a], right.position_m[b], rtol=0, atol=1e-6)
    np.testing.assert_array_equal(left.diameter_m[a], right.diameter_m[b])
    # another seed: other drops
    other = rain.drops((0.0, 1.6, 0.0), weather, seed=8)
    assert not np.array_equal(other.position_m[:50], left.position_m[:50])


def test_rain_is_coherent_in_time_and_follows_the_wind():
    weather = Weather(rain_rate_mm_h=10.0, wind_m_s=(3.0, 0.0, 0.0))
    t0 = rain.drops((0.0, 1.6, 0.0), weather, time_s=1.0, seed=5)
    t1 = rain.drops((0.0, 1.6, 0.0), weather, time_s=1.0 + 1 / 120, seed=5)
    k1 = {tuple(i): k for k, i in enumerate(t1.id)}
    pairs = np.array([(k, k1[tuple(i)]) for k, i in enumerate(t0.id) if tuple(i) in k1])
    step = t1.position_m[pairs[:, 1]] - t0.position_m[pairs[:, 0]]
    want = t0.velocity_m_s[pairs[:, 0]] / 120
    ok = np.all(np.abs(step - want) < 1e-4, axis=1)
    assert ok.mean() > 0.9  # the rest (~6 % at up to 7.5 m/s for 1/120 s) wrapped in their voxel
    np.testing.assert_allclose(t0.velocity_m_s[:, 0], 3.0)
    speeds = -t0.velocity_m_s[:, 1]
    assert np.all((speeds > 3.5) & (speeds < 7.5))  # Beard speeds of 0.9-2.1 mm drops


def test_sequences_are_deterministic_and_move(renderer):
    w = Weather(rain_rate_mm_h=20.0)
    seq = list(renderer.render_sequence(open_air(), w, n_frames=3, fps=30.0, seed=9))
    again = list(renderer.render_sequence(open_air(), w, n_frames=3, fps=30.0, seed=9))
    assert len(seq) == 3
    for a, b in zip(seq, again):
        assert a.rgb.tobytes() == b.rgb.tobytes()
    assert not np.array_equal(seq[0].layers["rain_alpha"], seq[1].layers["rain_alpha"])


def test_longer_exposures_give_longer_streaks_of_the_same_opacity_area(renderer):
    w = Weather(rain_rate_mm_h=20.0)
    short = Camera((0.0, 1.6, 0.0), exposure_s=1 / 250)
    long = Camera((0.0, 1.6, 0.0), exposure_s=1 / 30)
    img = np.full((H, W, 3), 0.1, np.float32)
    inf = np.full((H, W), np.inf, np.float32)
    a = renderer.render(PhotoScene(img, inf, camera=short, encoding="linear", airlight="sky"), w, seed=1).layers["rain_alpha"]
    b = renderer.render(PhotoScene(img, inf, camera=long, encoding="linear", airlight="sky"), w, seed=1).layers["rain_alpha"]

    def vertical_correlation(x: np.ndarray, lag: int = 6) -> float:
        x = x - x.mean()
        return float((x[lag:] * x[:-lag]).sum() / (x * x).sum())

    # streaks 8x longer: alpha stays correlated over many more rows
    assert vertical_correlation(b) > 0.5 > vertical_correlation(a)
    assert b.sum() == pytest.approx(a.sum(), rel=0.15)


@pytest.mark.parametrize("background", [0.1, 2.0])
def test_streaks_are_lit_by_the_sky(renderer, background):
    # I_v = r I_R + (1 - r) I_T with r = 0.5, I_R = 1: rain brightens a dark background and
    # darkens one brighter than I_R; where one streak covers a pixel with a, the change is
    # a r (I_R - C). Background 20 m away, behind the 5 m rain region.
    img = np.full((H, W, 3), background, np.float32)
    scene = PhotoScene(img, np.full((H, W), 20.0, np.float32), camera=Camera((0.0, 1.6, 0.0)), encoding="linear", airlight="sky")
    w = Weather(rain_rate_mm_h=50.0)
    clear = renderer.render(scene, Weather(rain_rate_mm_h=50.0, rain_near_m=1e-3), seed=1)  # haze, (almost) no streaks
    wet = renderer.render(scene, w, seed=1)
    a = wet.layers["rain_alpha"]
    # The wet frame's haze leaves out the drawn drops' share within rain_near_m: the background
    # C behind its streaks is the photo hazed by its own transmittance (the airlight A from the
    # clear frame, C = b T + A (1 - T)).
    tc, tw = clear.layers["transmittance"], wet.layers["transmittance"]
    air = (clear.rgb[..., 0] - background * tc) / (1.0 - tc)
    c = background * tw + air * (1.0 - tw)
    change = wet.rgb[..., 0] - c
    assert np.all(np.sign(change[a > 1e-3]) == np.sign(1.0 - background))
    single = (a > 1e-3) & (a < 0.02)  # mostly one streak: 1 - (1 - a r) = a r
    np.testing.assert_allclose(change[single], 0.5 * a[single] * (1.0 - c[single]), rtol=0.05, atol=1e-6)


def test_gpu_backend_draws_the_same_rain():
    gpu = Renderer(W, H, backend="gpu")
    cpu = Renderer(W, H, backend="cpu")
    w = Weather(rain_rate_mm_h=20.0, visibility_m=1000.0)
    g = gpu.render(scenes.street(), w, seed=3)
    c = cpu.render(scenes.street(), w, seed=3)
    same_bg = np.isclose(g.depth_m, c.depth_m, rtol=1e-4) | (np.isinf(g.depth_m) & np.isinf(c.depth_m))
    assert same_bg.mean() > 0.99
    np.testing.assert_allclose(g.layers["rain_alpha"][same_bg], c.layers["rain_alpha"][same_bg], atol=1e-6)
    assert g.stats == c.stats
    # the bar, over the whole rain layer (the few pixels whose rasterised depth differs
    # between the backends included)
    a, b = c.layers["rain_alpha"], g.layers["rain_alpha"]
    assert structural_similarity(a, b, data_range=float(max(a.max(), b.max()))) >= 0.99


def test_bad_rain_parameters():
    with pytest.raises(ValueError, match="wind_m_s"):
        Weather(wind_m_s=(100.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="rain_near_m"):
        Weather(rain_near_m=0.0)
    with pytest.raises(ValueError, match="rain_diameters_mm"):
        Weather(rain_diameters_mm=(2.0, 1.0))
    with pytest.raises(ValueError, match="n_frames"):
        Renderer(8, 8, backend="cpu").render_sequence(open_air(), n_frames=0)
    # non-numbers and wrong objects are TypeErrors that name the argument
    with pytest.raises(TypeError, match="wind_m_s"):
        Weather(wind_m_s="abc")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="rain_diameters_mm"):
        Weather(rain_diameters_mm="abc")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="weather"):
        rain.drops((0.0, 1.6, 0.0), None)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="camera"):
        Renderer(8, 8, backend="cpu").render(scenes.street(), camera={})  # type: ignore[arg-type]
    assert Weather(rain_streaks=np.bool_(False)).rain_streaks is False
    # the core's ±1e7 limits on times and positions, named where the user set them
    with pytest.raises(ValueError, match=r"start_s = nan"):
        Renderer(8, 8, backend="cpu").render_sequence(open_air(), n_frames=2, start_s=float("nan"))
    with pytest.raises(ValueError, match=r"start_s = 0.0 and fps = 1e-300"):
        Renderer(8, 8, backend="cpu").render_sequence(open_air(), n_frames=2, fps=1e-300)
    with pytest.raises(ValueError, match=r"time_s = 20000000.0 is outside the valid range \[-1e7, 1e7\]"):
        Renderer(8, 8, backend="cpu").render(open_air(), time_s=2e7)
    with pytest.raises(ValueError, match=r"position_m .*\[-1e7, 1e7\]"):
        Camera((2e7, 1.6, 0.0))
    # a region whose drops would not fit in memory is refused before any is made (50 m at
    # 200 mm/h: 8e8 drops, 55 GiB)
    with pytest.raises(ValueError, match=r"rain_near_m = 50"):
        rain.drops((0.0, 1.6, 0.0), Weather(rain_rate_mm_h=200.0, rain_near_m=50.0))


def test_rain_beyond_the_memory_budget_is_refused(renderer):
    with pytest.raises(ValueError, match=r"rain_near_m = 50 m at 200"):
        renderer.render(open_air(), Weather(rain_rate_mm_h=200.0, rain_near_m=50.0))


def dusk_scene(lights=()):
    img = np.full((H, W, 3), 0.05, np.float32)
    cam = Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0)
    return PhotoScene(img, np.full((H, W), 30.0, np.float32), camera=cam, lights=tuple(lights), encoding="linear", airlight="sky")


def test_streaks_near_a_lamp_are_brighter(renderer):
    # One 2000 cd lamp 2 m ahead and 1.5 m to the left; dusk sky of 20 lux. Rain brightens the
    # dark background far more around the lamp's image than on the other side of the frame.
    from skyfall import PointLight

    lamp = PointLight((-1.5, 1.6, -2.0), 2000.0)
    w = Weather(rain_rate_mm_h=30.0, sky_illuminance_lux=20.0, rain_near_m=4.0)
    lit = renderer.render(dusk_scene([lamp]), w, seed=2)
    dark = renderer.render(dusk_scene(), w, seed=2)
    np.testing.assert_array_equal(lit.layers["rain_alpha"], dark.layers["rain_alpha"])  # same drops
    gain = (lit.rgb - dark.rgb)[..., 0]
    px, _ = Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0, width=W, height=H).project([lamp.position_m])
    x = int(px[0, 0])
    assert 0 < x < W // 2
    near = gain[:, max(0, x - 20) : x + 20].mean()
    far = gain[:, W - 40 :].mean()
    assert near > 3 * far > 0
    # the lamp's share of the drop light is linear in its intensity (inverse square in
    # distance is checked on the light itself in the Rust tests)
    half = renderer.render(dusk_scene([PointLight((-1.5, 1.6, -2.0), 500.0)]), w, seed=2)
    g_half = (half.rgb - dark.rgb)[..., 0][:, max(0, x - 20) : x + 20].mean()
    assert g_half == pytest.approx(near / 4, rel=0.15)


def test_a_light_of_zero_intensity_changes_nothing_and_culling_counts(renderer):
    from skyfall import PointLight, SpotLight

    w = Weather(rain_rate_mm_h=30.0, sky_illuminance_lux=20.0)
    base = renderer.render(dusk_scene(), w, seed=5)
    off = renderer.render(dusk_scene([PointLight((0.0, 2.0, -2.0), 0.0)]), w, seed=5)
    assert off.rgb.tobytes() == base.rgb.tobytes()
    assert base.stats["rain_culled"] == 0
    # threshold 0 culls nothing: the same bits as no culling
    zero = renderer.render(dusk_scene(), w, seed=5, cull_threshold=0.0)
    assert zero.rgb.tobytes() == base.rgb.tobytes() and zero.stats == base.stats
    # a headlight lights a cone; a threshold above the sky's 1.0 keeps only lit drops
    head = SpotLight((0.0, 0.7, -6.0), (0.0, 0.0, 1.0), 15000.0, cone_deg=20.0)
    lit = renderer.render(dusk_scene([head]), w, seed=5)
    culled = renderer.render(dusk_scene([head]), w, seed=5, cull_threshold=1.5)
    assert culled.stats["rain_culled"] > 0
    assert culled.stats["rain_culled"] + culled.stats["rain_streaks"] == lit.stats["rain_streaks"]
    # what culling drops is faint: the image changes far less than the rain itself
    rain_change = np.abs(lit.rgb - renderer.render(dusk_scene([head]), Weather(sky_illuminance_lux=20.0, visibility_m=1e9, rain_rate_mm_h=30.0, rain_streaks=False), seed=5).rgb).mean()
    assert np.abs(culled.rgb - lit.rgb).mean() < 0.5 * rain_change
    with pytest.raises(ValueError, match="cull_threshold"):
        renderer.render(dusk_scene(), w, cull_threshold=-1.0)
    with pytest.raises(ValueError, match="cone_deg"):
        SpotLight((0, 0, 0), (0, 0, 1), 1.0, cone_deg=120.0)
    with pytest.raises(ValueError, match="intensity_cd"):
        PointLight((0, 0, 0), -5.0)
    with pytest.raises(TypeError, match="intensity_cd"):
        PointLight((0, 0, 0), "bright")  # type: ignore[arg-type]


def test_lights_across_their_documented_ranges(renderer):
    from skyfall import PointLight, SpotLight

    # intensities up to 1e9 cd render (the core once refused anything over 1e7 as "not finite")
    w = Weather(rain_rate_mm_h=30.0, sky_illuminance_lux=20.0)
    bright = renderer.render(dusk_scene([PointLight((0.0, 1.6, -3.0), 2e7)]), w, seed=5)
    assert np.isfinite(bright.rgb).all()
    # a huge or tiny direction still normalises (its norm used to overflow to a zero vector)
    for scale in (1e308, 1e-300):
        d = SpotLight((0, 0, 0), (scale, scale, 0.0), 100.0).direction
        np.testing.assert_allclose(d, (np.sqrt(0.5), np.sqrt(0.5), 0.0))
    with pytest.raises(ValueError, match=r"position_m .*\[-1e7, 1e7\] m"):
        PointLight((2e7, 0.0, 0.0), 1.0)
    with pytest.raises(ValueError, match="direction must not be zero"):
        SpotLight((0, 0, 0), (0.0, 0.0, 0.0), 1.0)


def test_a_moving_camera_sees_the_drops_relative_motion(renderer):
    # Drops fall at 4-7 m/s; a camera moving sideways at 25 m/s sees them sweep across the
    # frame: streaks turn from vertical to nearly horizontal.
    def lag_corr(x: np.ndarray, axis: int, lag: int = 4) -> float:
        x = x - x.mean()
        a = np.take(x, range(lag, x.shape[axis]), axis=axis)
        b = np.take(x, range(0, x.shape[axis] - lag), axis=axis)
        return float((a * b).sum() / (x * x).sum())

    img = np.full((H, W, 3), 0.1, np.float32)
    inf = np.full((H, W), np.inf, np.float32)
    w = Weather(rain_rate_mm_h=30.0, rain_near_m=3.0)
    still = renderer.render(PhotoScene(img, inf, camera=Camera((0.0, 1.6, 0.0)), encoding="linear", airlight="sky"), w, seed=6).layers["rain_alpha"]
    moving_cam = Camera((0.0, 1.6, 0.0), velocity_m_s=(25.0, 0.0, 0.0))
    moving = renderer.render(PhotoScene(img, inf, camera=moving_cam, encoding="linear", airlight="sky"), w, seed=6).layers["rain_alpha"]
    assert lag_corr(still, 0) > lag_corr(still, 1)
    assert lag_corr(moving, 1) > lag_corr(moving, 0)
    with pytest.raises(ValueError, match="velocity_m_s"):
        Camera(velocity_m_s=(2000.0, 0.0, 0.0))


def test_billboards_carry_the_drops_mean_opacity(renderer):
    # Billboards draw each voxel's streaks at the voxel centre's depth. A streak's opacity-area
    # goes as 1/z^2, which is convex, so by Jensen's inequality moving drops to their voxel's
    # centre plane loses opacity (8 % here), and the camera's own voxel shows no billboard at
    # all. The billboards widen their streaks to carry the drops' expected opacity: over 24
    # seeds the two means agree to within their noise (1.1 % std of the ratio at this size).
    img = np.full((H, W, 3), 0.1, np.float32)
    scene = PhotoScene(img, np.full((H, W), np.inf, np.float32), camera=Camera((0.3, 1.6, 0.2)), encoding="linear", airlight="sky")

    def mean_alpha(method: str) -> float:
        w = Weather(rain_rate_mm_h=20.0, rain_method=method)
        return float(np.mean([renderer.render(scene, w, seed=s).layers["rain_alpha"].mean() for s in range(24)]))

    drops, boards = mean_alpha("drops"), mean_alpha("billboards")
    assert -0.05 < boards / drops - 1 < 0.06
    with pytest.raises(ValueError, match="rain_method"):
        Weather(rain_method="sprites")
