"""Snowfall in frames, on both backends: flakes through the particle toolkit (Koitabashi,
Matsubara, Moriya & Takahashi's falling snow with wind), their layer, the haze they add, mixed
precipitation, the 8-bit path, determinism and the hard cases."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from skimage.metrics import structural_similarity

from skyfall import Camera, PhotoScene, Renderer, Weather, io, scenes

W, H = 160, 96


@pytest.fixture(scope="module")
def cpu() -> Renderer:
    return Renderer(W, H, backend="cpu")


@pytest.fixture(scope="module")
def gpu() -> Renderer:
    # make test installs Mesa's lavapipe when no Vulkan driver exists: a missing GPU fails here.
    return Renderer(W, H, backend="gpu")


def open_air(depth: float = np.inf) -> PhotoScene:
    img = np.full((H, W, 3), 0.1, np.float32)
    cam = Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0)
    return PhotoScene(img, np.full((H, W), depth, np.float32), camera=cam, encoding="linear", airlight="sky")


def photo8(seed: int = 0) -> PhotoScene:
    rng = np.random.default_rng(seed)
    img = rng.integers(0, 256, (H, W, 3), dtype=np.uint8)
    y, x = np.mgrid[0:H, 0:W]
    depth = (1.0 + 0.05 * x + 0.2 * y).astype(np.float32)
    depth[:20] = np.inf
    depth[:, :30] = 0.7  # a near wall
    return PhotoScene(img, depth, camera=Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0))


def test_no_snow_changes_no_bits_and_draws_no_flakes(cpu):
    # snow_rate_mm_h = 0 is the frame of a weather without snow, bit for bit, whatever the
    # snow's other fields, with no snow layer and no flake counted.
    base = Weather(rain_rate_mm_h=8.0, visibility_m=900.0)
    dry = Weather(rain_rate_mm_h=8.0, visibility_m=900.0, snow_rate_mm_h=0.0, snow_near_m=20.0, snow_opacity="levels")
    a, b = cpu.render(scenes.street(), base, seed=5), cpu.render(scenes.street(), dry, seed=5)
    assert a.rgb.tobytes() == b.rgb.tobytes()
    assert a.layers.keys() == b.layers.keys() and "snow_alpha" not in b.layers
    for k in a.layers:
        assert a.layers[k].tobytes() == b.layers[k].tobytes()
    assert "snow_flakes" not in b.stats
    assert dry.snow_extinction_per_m == 0.0 and dry.extinction_per_m == base.extinction_per_m
    np.testing.assert_array_equal(b.layer("snow_alpha"), 0.0)


def test_snow_thickens_the_haze_by_its_own_extinction():
    w = Weather(snow_rate_mm_h=2.0, visibility_m=5000.0)
    assert w.snow_extinction_per_m == pytest.approx(physics_snow_sigma(2.0), rel=1e-4)
    assert w.extinction_per_m == pytest.approx(w.air_extinction_per_m + w.snow_extinction_per_m, rel=1e-12)
    # heavier snow, thicker air; visibility in heavy snow (2.5 mm/h) under 400 m
    assert Weather(snow_rate_mm_h=5.0).snow_extinction_per_m > w.snow_extinction_per_m
    assert 3.912 / Weather(snow_rate_mm_h=2.5).snow_extinction_per_m < 400.0


def physics_snow_sigma(rate: float) -> float:
    """sigma_snow written out independently in numpy: Gunn & Marshall's slope
    2.55 R^-0.48 /mm (melted diameter D), Locatelli & Hobbs' m = 0.073 S^1.4 mg and
    v = 0.8 S^0.16 m/s (S the size, mm; m = pi D^3 / 6 mg), truncated at S = 10 mm, N0 from
    the flux relation (sum of N m v = the rate), Mitchell's A = 0.3012 S^1.88 mm^2, extinction
    efficiency 2; the trapezoid rule on a fine grid."""
    d_max = (0.073 * 10.0**1.4 * 6.0 / np.pi) ** (1.0 / 3.0)
    d = np.linspace(0.0, d_max, 200_001)
    m = np.pi / 6.0 * d**3
    s = (m / 0.073) ** (1.0 / 1.4)
    shape = np.exp(-2.55 * rate**-0.48 * d)
    n0 = rate * 1e6 / 3600.0 / np.trapezoid(shape * m * 0.8 * s**0.16, d)
    return float(np.trapezoid(n0 * shape * 2.0 * 0.3012 * s**1.88, d) * 1e-6)


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_heavier_snow_covers_more_and_the_layer_is_the_flakes(backend, cpu, gpu):
    r = {"cpu": cpu, "gpu": gpu}[backend]
    frames = [r.render(open_air(), Weather(snow_rate_mm_h=s, snow_near_m=5.0), seed=4) for s in (0.2, 1.0, 5.0)]
    means = [f.layers["snow_alpha"].mean() for f in frames]
    assert np.all(np.diff(means) > 0), means
    for f in frames:
        assert "rain_alpha" not in f.layers and f.stats["snow_streaks"] > 0
        a = f.layers["snow_alpha"]
        assert a.min() >= 0.0 and a.max() <= 1.0
    # flakes are white (albedo 0.9 under the sky): over a dark wall 3 m away they brighten
    # the pixels they cover, by about their coverage times (0.9 - 0.1)
    f = r.render(open_air(3.0), Weather(snow_rate_mm_h=5.0, snow_near_m=5.0), seed=4)
    a, lum = f.layers["snow_alpha"], f.rgb.mean(axis=2)
    hi, lo = a > np.quantile(a, 0.95), a < np.quantile(a, 0.05)
    gain = (lum[hi].mean() - lum[lo].mean()) / (a[hi].mean() - a[lo].mean())
    assert 0.4 < gain < 1.0, gain


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_flakes_are_depth_tested(backend, cpu, gpu):
    r = {"cpu": cpu, "gpu": gpu}[backend]
    weather = Weather(snow_rate_mm_h=3.0, snow_near_m=6.0)
    near = r.render(open_air(0.3), weather, seed=1)
    far = r.render(open_air(np.inf), weather, seed=1)
    # behind a wall 0.3 m away only the few flakes nearer than it show
    assert near.layers["snow_alpha"].mean() < 0.1 * far.layers["snow_alpha"].mean()


def test_mixed_precipitation_draws_both_into_their_own_layers(cpu, gpu):
    # (the levels, not the extinction: the rain's haze would dim the flakes a little more)
    mixed = Weather(rain_rate_mm_h=10.0, snow_rate_mm_h=1.0, wind_m_s=(2.0, 0.0, 0.0), snow_opacity="levels")
    rain_only = Weather(rain_rate_mm_h=10.0, wind_m_s=(2.0, 0.0, 0.0))
    snow_only = Weather(snow_rate_mm_h=1.0, wind_m_s=(2.0, 0.0, 0.0), snow_opacity="levels")
    m = cpu.render(open_air(), mixed, seed=2)
    ro, so = cpu.render(open_air(), rain_only, seed=2), cpu.render(open_air(), snow_only, seed=2)
    assert {"rain_alpha", "rain_depth_m", "snow_alpha"} <= m.layers.keys()
    # each layer is its own effect's: the same as that effect alone (their haze aside, the
    # particles are the same; one sorted list composites both)
    np.testing.assert_allclose(m.layers["rain_alpha"], ro.layers["rain_alpha"], atol=1e-5)
    np.testing.assert_allclose(m.layers["snow_alpha"], so.layers["snow_alpha"], atol=1e-5)
    assert m.stats["rain_streaks"] == ro.stats["rain_streaks"] and m.stats["snow_streaks"] == so.stats["snow_streaks"]
    g = gpu.render(open_air(), mixed, seed=2)
    for k in ("rain_alpha", "snow_alpha"):
        assert np.abs(g.layers[k] - m.layers[k]).max() < 2e-3, k
    assert np.abs(g.rgb - m.rgb).max() < 2e-3


def ssim(a: np.ndarray, b: np.ndarray) -> float:
    rng = float(max(a.max(), b.max()) - min(a.min(), b.min())) or 1.0
    return float(structural_similarity(a, b, data_range=rng, channel_axis=-1 if a.ndim == 3 else None))


@pytest.mark.parametrize("opacity", ["extinction", "levels"])
def test_gpu_matches_cpu_on_a_snowy_street(cpu, gpu, opacity):
    weather = Weather(snow_rate_mm_h=2.0, wind_m_s=(3.0, 0.0, 1.0), visibility_m=3000.0, snow_opacity=opacity)
    c = cpu.render(scenes.street(), weather, seed=6)
    g = gpu.render(scenes.street(), weather, seed=6)
    assert c.stats == g.stats and c.stats["snow_streaks"] > 1000
    assert ssim(c.rgb, g.rgb) >= 0.99
    # the shader's cos and FMA differ by ulps: a star's arm edge may fall on the other side
    # of a pixel centre; nearly every pixel agrees to 1e-3
    diff = np.abs(c.rgb - g.rgb).max(axis=2)
    assert (diff > 1e-3).mean() <= 0.005, (diff > 1e-3).mean()
    da = np.abs(c.layers["snow_alpha"] - g.layers["snow_alpha"])
    assert (da > 1e-3).mean() <= 0.005 and da.max() < 0.05


def test_the_8bit_path_is_the_float_frame_encoded_with_snow(cpu):
    scene = photo8(1)
    weather = Weather(snow_rate_mm_h=4.0, rain_rate_mm_h=5.0, visibility_m=400.0, wind_m_s=(1.5, 0.0, 0.0))
    frame = cpu.render(scene, weather, seed=3)
    want = io.to_srgb8(frame.rgb)
    snow_a = np.full((H, W), -1.0, np.float32)
    rain_a = np.full((H, W), -1.0, np.float32)
    got = cpu.render_srgb8(scene, weather, seed=3, layers={"rain_alpha": rain_a, "snow_alpha": snow_a}).image
    diff = np.abs(got.astype(int) - want)
    assert diff.max() <= 1 and np.mean(diff > 0) < 1e-3
    np.testing.assert_allclose(snow_a, frame.layers["snow_alpha"], atol=1e-6)
    np.testing.assert_allclose(rain_a, frame.layers["rain_alpha"], atol=1e-6)
    assert frame.layers["snow_alpha"].max() > 0.05
    # without snow the 8-bit snow layer is zeros
    none = np.full((H, W), -1.0, np.float32)
    cpu.render_srgb8(scene, Weather(rain_rate_mm_h=5.0), seed=3, layers={"snow_alpha": none})
    np.testing.assert_array_equal(none, 0.0)


def test_flakes_are_coherent_from_frame_to_frame(cpu):
    # 2 ms apart the flakes have moved by about a millimetre: the snow layer barely changes;
    # a second later it is another picture.
    weather = Weather(snow_rate_mm_h=3.0, wind_m_s=(2.0, 0.0, 0.0), snow_near_m=5.0)
    a, b, c = (cpu.render(open_air(), weather, seed=9, time_s=t).layers["snow_alpha"] for t in (5.0, 5.002, 6.0))
    assert ssim(a, b) > 0.9 > ssim(a, c)


DETERMINISM = """
import hashlib, numpy as np
from skyfall import Renderer, Weather, scenes
f = Renderer(96, 64, backend="cpu").render(scenes.street(), Weather(snow_rate_mm_h=3.0, rain_rate_mm_h=2.0, wind_m_s=(4.0, 0.0, -1.0)), seed=12, time_s=3.25)
print(hashlib.sha256(f.rgb.tobytes() + f.layers["snow_alpha"].tobytes()).hexdigest())
"""


def test_snow_is_the_same_bits_in_two_processes():
    runs = [subprocess.run([sys.executable, "-c", DETERMINISM], capture_output=True, text=True, check=True).stdout for _ in range(2)]
    assert runs[0] == runs[1] and len(runs[0].strip()) == 64


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_heavy_snow_in_a_gale_is_finite(backend, cpu, gpu):
    r = {"cpu": cpu, "gpu": gpu}[backend]
    # (a 1.5 m region: at 3 m the streaks' tile lists outgrow lavapipe's 128 MiB buffers, a
    # clear error naming snow_near_m)
    f = r.render(scenes.street(), Weather(snow_rate_mm_h=100.0, wind_m_s=(60.0, 0.0, -60.0), snow_near_m=1.5), seed=1)
    assert np.isfinite(f.rgb).all() and np.isfinite(f.layers["snow_alpha"]).all()
    assert f.layers["snow_alpha"].max() > 0.5


def test_bad_snow_inputs_are_clear_errors():
    with pytest.raises(ValueError, match=r"snow_rate_mm_h = 101.0 is outside the valid range \[0, 100\] mm/h"):
        Weather(snow_rate_mm_h=101.0)
    with pytest.raises(ValueError, match="snow_rate_mm_h"):
        Weather(snow_rate_mm_h=float("nan"))
    with pytest.raises(ValueError, match=r"snow_near_m = 0.0 is outside the valid range \(0, 50\] m"):
        Weather(snow_near_m=0.0)
    with pytest.raises(ValueError, match="snow_opacity = 'fog' is not one of"):
        Weather(snow_opacity="fog")
    with pytest.raises(TypeError, match="snow_opacity must be a str"):
        Weather(snow_opacity=3)  # type: ignore[arg-type]
    # a region too large for memory is refused by name, before any flake is made
    with pytest.raises(ValueError, match="snow_near_m = 50"):
        Renderer(64, 48, backend="cpu").render(scenes.street(), Weather(snow_rate_mm_h=100.0, snow_near_m=50.0))


def test_an_8bit_clip_fills_the_snow_layer_frame_by_frame(cpu):
    scene = photo8(2)
    weather = Weather(snow_rate_mm_h=2.0, wind_m_s=(1.0, 0.0, 0.0))
    alpha = np.full((H, W), -1.0, np.float32)
    for k, (img, _) in enumerate(cpu.render_sequence_srgb8(scene, weather, n_frames=2, fps=10.0, seed=4, layers={"snow_alpha": alpha})):
        want = np.full((H, W), -1.0, np.float32)
        assert img.tobytes() == cpu.render_srgb8(scene, weather, seed=4, time_s=k / 10.0, layers={"snow_alpha": want}).image.tobytes()
        np.testing.assert_array_equal(alpha, want)
        assert alpha.max() > 0.0


@pytest.mark.parametrize("exposure_s", [0.004, 0.001])
def test_snow_alpha_is_a_coverage_at_most_1_at_short_shutters(exposure_s, cpu, gpu):
    # A flake's sprite peaks at ~1.6 times its mean: on a short path its fragments' α·coverage
    # passed 1 (1.05 here, 1.135 on chelsea at 3 m), and 1 − ∏(1 − a) with it.
    cam = Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0, exposure_s=exposure_s)
    img8 = np.full((H, W, 3), 90, np.uint8)
    depth = np.full((H, W), 3.0, np.float32)
    float_scene = PhotoScene(np.full((H, W, 3), 0.1, np.float32), depth, camera=cam, encoding="linear", airlight="sky")
    scene8 = PhotoScene(img8, depth, camera=cam)
    weather = Weather(snow_rate_mm_h=3.0)
    peaks = []
    for seed in range(4):
        for r in (cpu, gpu):
            a = r.render(float_scene, weather, seed=seed).layers["snow_alpha"]
            assert a.min() >= 0.0 and a.max() <= 1.0, (r.backend, seed, a.max())
            peaks.append(a.max())
        out = np.full((H, W), -1.0, np.float32)
        cpu.render_srgb8(scene8, weather, seed=seed, layers={"snow_alpha": out})
        assert out.min() >= 0.0 and out.max() <= 1.0, (seed, out.max())
    assert max(peaks) > 0.99  # the flakes that passed 1 are opaque, not gone


def _map_bounds(renderer: Renderer, scene: PhotoScene | scenes.BoxScene, weather: Weather) -> tuple[np.ndarray, np.ndarray]:
    """The world box the frame's ambient-light map spans, m."""
    m = renderer._request(scene, weather)["ambient"]
    lo = np.asarray(m.origin_m, dtype=np.float64)
    return lo, lo + m.spacing_m * (np.asarray(m.dims, dtype=np.float64) - 1.0)


def test_the_ambient_map_spans_the_flakes_region_without_rain() -> None:
    # The flakes read their sky light from the ambient-light map as the drops do, out to
    # snow_near_m (8 m by default). The map's extent used to follow the rain alone, so snow
    # without rain got a map of +-1 m around the camera and every flake beyond it read the
    # map's edge: here, an awning 2-6 m ahead would not shade the flakes beneath it.
    cam = Camera((0.0, 1.6, 0.0))
    awning = [{"min": (-3.0, 3.0, -6.0), "max": (3.0, 3.2, -2.0)}]
    photo = PhotoScene(np.full((18, 32, 3), 90, np.uint8), np.full((18, 32), 20.0, np.float32), camera=cam, occluders=awning)
    r = Renderer(32, 18, backend="cpu")
    eye = np.asarray(cam.position_m, dtype=np.float64)
    for weather, reach in (
        (Weather(snow_rate_mm_h=2.0), 8.0),
        (Weather(snow_rate_mm_h=2.0, snow_near_m=12.0), 12.0),
        (Weather(snow_rate_mm_h=2.0, snow_near_m=3.0, rain_rate_mm_h=5.0, rain_near_m=6.0), 6.0),  # the wider of the two
        (Weather(rain_rate_mm_h=5.0, rain_near_m=4.0), 4.0),
    ):
        lo, hi = _map_bounds(r, photo, weather)
        assert np.all(lo <= eye - reach) and np.all(hi >= eye + reach), (weather, lo, hi)
    # without particles, a metre around the camera is enough
    lo, hi = _map_bounds(r, photo, Weather())
    assert np.all(hi - lo <= 2.0 + 1e-9)
    # the awning now shades the flakes under it: a flake 4 m ahead under it receives less sky
    # light than one in the open beside it (read from the map the frame uses)
    amb = r._request(photo, Weather(snow_rate_mm_h=2.0))["ambient"]
    under, beside = amb.sample(np.array([[0.0, 2.0, -4.0], [0.0, 2.0, 4.0]], np.float32))[:, 0]
    assert under < 0.8 * beside
