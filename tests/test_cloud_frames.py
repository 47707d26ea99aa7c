"""Clouds in frames (``Weather(clouds=...)``) and the sun's direct light through them.

References: the clouds' own attenuation volume sampled in float64 by the core
(``_core.CloudField.sun_share``, an independent code path from the frames' float32 one), the
clear-sky direct illuminance written out here from its published constants (Navvab et al.
1984 as given by Tregenza & Sharples, Kasten & Young's air mass), the CPU backend for the GPU.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from skimage.metrics import structural_similarity

from skyfall import Camera, PhotoScene, Renderer, Weather, clouds, scenes, sky

W, H = 64, 40
LUMA = np.array([0.2126, 0.7152, 0.0722])
"""Rec. 709 luminance weights: the sun's light in a box scene has the sun's colour, of luminance 1."""
SUNNY = {"sky": 12, "sun_elevation_deg": 35.0, "sun_azimuth_deg": 160.0}


def _points(cam: Camera, depth: np.ndarray) -> np.ndarray:
    """World points of each pixel's surface (depth along the axis), (H, W, 3)."""
    return cam.position_m + cam.ray_directions() * depth[..., None]


def _unit_rays(cam: Camera) -> np.ndarray:
    """Unit view directions of each pixel, (H * W, 3)."""
    d = cam.ray_directions().reshape(-1, 3)
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def _clear_sky_sun_lux(elevation_deg: float) -> float:
    h = elevation_deg
    m = 1.0 / (math.sin(math.radians(h)) + 0.50572 * (h + 6.07995) ** -1.6364)
    return 133_800.0 * math.exp(-m * 3.0 / (9.9 + 0.043 * m))


def test_the_sun_lights_open_ground_by_the_clear_sky_model() -> None:
    # No clouds: open ground of albedo a receives a (E_amb + E_sun/E sin h c_sun), c_sun the
    # sun's colour (luminance 1: tested against colour-science in test_sky_colour.py); the
    # sky's share is the frame without a sun (the same sky, sun_illuminance_lux=0).
    scene = scenes.empty(ground_albedo=(0.3, 0.3, 0.3), camera=Camera(pitch_deg=-30.0))
    r = Renderer(W, H, backend="cpu")
    lit = r.render(scene, Weather(**SUNNY))
    dark = r.render(scene, Weather(**SUNNY, sun_illuminance_lux=0.0))
    assert "sun_transmittance" in lit.layers and "sun_transmittance" not in dark.layers
    ground = np.isfinite(lit.depth_m)
    assert ground.mean() > 0.5
    rel = _clear_sky_sun_lux(35.0) / 10_000.0
    sun_rgb = np.array(sky.colours(weather=Weather(**SUNNY)).sun)
    assert sun_rgb @ [0.2126, 0.7152, 0.0722] == pytest.approx(1.0, rel=1e-5)
    want = dark.rgb[ground] + 0.3 * rel * math.sin(math.radians(35.0)) * sun_rgb
    np.testing.assert_allclose(lit.rgb[ground], want, rtol=2e-5)
    assert Weather(**SUNNY).sun_relative == pytest.approx(rel, rel=1e-6)
    np.testing.assert_array_equal(lit.layers["sun_transmittance"][ground], 1.0)
    # The overcast sky and the overcast-like CIE types have no direct sun; a given value wins.
    assert Weather().sun_direction is None and Weather(sky=5).sun_relative == 0.0
    w = Weather(sky=3, sun_elevation_deg=35.0, sun_azimuth_deg=0.0, sun_illuminance_lux=50_000.0)
    assert w.sun_relative == pytest.approx(5.0, rel=1e-6)


def test_cloud_shadow_on_open_ground_is_the_volume_along_the_sun_ray() -> None:
    # A broken field over open ground: the ground's sun_transmittance is the clouds' Γ at each
    # ground point, as the core's float64 volume sampler gives it, and the ground's radiance
    # follows it (a E_amb + a (E_sun/E) sin h Γ).
    cam = Camera(position_m=(0.0, 1.6, 0.0), pitch_deg=-40.0, vertical_fov_deg=70.0)
    scene = scenes.empty(ground_albedo=(0.3, 0.3, 0.3), camera=cam)
    sun_at = {"sky": 12, "sun_elevation_deg": 60.0, "sun_azimuth_deg": 0.0}
    # Three particles placed so that their shadows (the sun north, 60 deg up) fall on the
    # ground the camera sees: each 150 m above its shadow and 150 / tan 60 m towards the sun.
    feet = np.array([[-3.0, 0.0, -5.0], [4.0, 0.0, -9.0], [0.5, 0.0, -3.5]])
    up = np.array([0.0, 150.0, -150.0 / math.tan(math.radians(60.0))])
    cloud = clouds.Cloud(feet + up, np.array([2.0, 3.0, 1.0]), np.array([4.0, 2.0, 6.0]), np.ones(3))
    r = Renderer(96, 64, backend="cpu")
    f = r.render(scene, Weather(**sun_at, clouds=cloud))
    clear = r.render(scene, Weather(**sun_at, sun_illuminance_lux=0.0))
    # The particles in the sky change the sky's light a little (the ambient map's, which the
    # clear frame's ground takes): its ratio, from the map the frame is lit by (open ground:
    # one node; the clouds seen from the ground under the camera).
    field = clouds.frame_field(cloud, Weather(**sun_at).sun_direction)
    none, zero = np.zeros((0, 9), np.float32), np.zeros(3)
    lit = sky.cached_core_map(none, Weather(**sun_at, clouds=cloud), zero, zero, 1.0, sky.MAP_SAMPLES, "s", field, zero)
    open_sky = sky.cached_core_map(none, Weather(**sun_at), zero, zero, 1.0, sky.MAP_SAMPLES)
    k = lit.values.reshape(-1)[0] * lit.light_colour[0] / (open_sky.values.reshape(-1)[0] * sky.colours(weather=Weather(**sun_at)).sky_light[0])
    # (brighter: seen from the ground they lie nearly towards the sun, whose light they
    # scatter forwards)
    assert 1.0 < k < 1.3
    ground = np.isfinite(f.depth_m)
    pts = _points(cam.with_resolution(96, 64), f.depth_m)[ground]
    want = field.sun_share(np.ascontiguousarray(pts, dtype=np.float64))
    got = f.layers["sun_transmittance"][ground]
    assert want.min() < 0.5 and want.max() > 0.99, "the test should see shadow and sun"
    np.testing.assert_allclose(got, want, atol=2e-3)
    rel = Weather(**sun_at).sun_relative * sky.colours(weather=Weather(**sun_at)).sun[0]
    np.testing.assert_allclose(f.rgb[ground][:, 0], k * clear.rgb[ground][:, 0] + 0.3 * rel * math.sin(math.radians(60.0)) * got, rtol=1e-4)


def test_one_particle_in_front_of_a_dark_sky_dims_it_by_its_column() -> None:
    # A photo of a black sky (depth inf) with no sun and no light reaching the cloud would show
    # only the cloud's extinction; with the sky's light, the centre pixel is a α D plus T of the
    # background: between the background's e^(-τ) and 1.
    cam = Camera(position_m=(0.0, 0.0, 0.0), pitch_deg=89.0, vertical_fov_deg=20.0, width=33, height=33)
    tau = 2.0
    axis = np.array([0.0, math.sin(math.radians(89.0)), -math.cos(math.radians(89.0))])
    one = clouds.Cloud(1000.0 * axis[None, :], np.array([60.0]), np.array([tau]), np.array([1.0]))
    sky = np.full((33, 33, 3), 0.5, np.float32)
    photo = PhotoScene(sky, np.full((33, 33), np.inf, np.float32), camera=cam, encoding="linear")
    r = Renderer(33, 33, backend="cpu")
    f = r.render(photo, Weather(clouds=one))
    a = f.layers["cloud_alpha"]
    assert a[16, 16] == pytest.approx(1.0 - math.exp(-tau), abs=1e-3)
    assert a[0, 0] == 0.0 and f.rgb[0, 0, 0] == pytest.approx(0.5, abs=1e-6)
    # The centre pixel: the sky behind dimmed by e^(-τ), plus the particle's own light.
    assert f.rgb[16, 16, 0] > 0.5 * math.exp(-tau)


def test_clouds_leave_what_they_do_not_cover_bit_for_bit() -> None:
    # Clouds nowhere in the frame nor in its sky (below the horizon, far off): the frame's rgb
    # and layers are those without clouds, plus a cloud_alpha of zeros. (Clouds anywhere in
    # the sky change its light, the ambient map's: tests/test_cloud_sky_light.py.)
    scene = scenes.street()
    behind = clouds.particles("cumulus", n_particles=300, extent_m=500.0, altitude_m=800.0)
    behind = clouds.Cloud(behind.positions_m + np.array([0.0, -3000.0, 8000.0]), behind.radii_m, behind.optical_depths, behind.albedos)
    r = Renderer(W, H, backend="cpu")
    base = r.render(scene, Weather(rain_rate_mm_h=5.0))
    with_c = r.render(scene, Weather(rain_rate_mm_h=5.0, clouds=behind))
    np.testing.assert_array_equal(with_c.rgb, base.rgb)
    for k, v in base.layers.items():
        np.testing.assert_array_equal(with_c.layers[k], v)
    np.testing.assert_array_equal(with_c.layers["cloud_alpha"], 0.0)
    assert "cloud_alpha" not in base.layers


def test_clouds_are_deterministic_and_render_srgb8_draws_them() -> None:
    scene = scenes.street()
    w = Weather(clouds="broken", **SUNNY)
    r = Renderer(W, H, backend="cpu")
    a, b = r.render(scene, w), r.render(scene, w)
    np.testing.assert_array_equal(a.rgb, b.rgb)
    assert a.layers["cloud_alpha"].max() > 0.5
    photo = PhotoScene(np.full((H, W, 3), 128, np.uint8), np.full((H, W), np.inf, np.float32), camera=Camera(pitch_deg=20.0))
    assert not r.fuses_srgb8(photo, w)
    out = r.render_srgb8(photo, w)
    plain = r.render_srgb8(photo, Weather(**SUNNY))
    assert out.shape == (H, W, 3) and np.abs(out.astype(int) - plain.astype(int)).max() > 20


def test_bad_clouds_are_refused_by_name() -> None:
    with pytest.raises(ValueError, match="clouds = 'nimbus' is not a preset"):
        Weather(clouds="nimbus")
    with pytest.raises(TypeError, match="clouds must be a skyfall.clouds.Cloud"):
        Weather(clouds=3)
    with pytest.raises(ValueError, match="sun_illuminance_lux: a sun needs a position: give sun_elevation_deg and sun_azimuth_deg"):
        Weather(sun_illuminance_lux=1000.0)
    with pytest.raises(ValueError, match="sun_illuminance_lux"):
        Weather(sky=12, sun_elevation_deg=30.0, sun_azimuth_deg=0.0, sun_illuminance_lux=-1.0)
    # A field built for another sun than the weather's is refused by the core.
    from skyfall import _core

    scene = scenes.street()
    r = Renderer(W, H, backend="cpu")
    req = r._request(scene, Weather(**SUNNY))
    req["clouds"] = clouds.frame_field("cumulus", None)
    with pytest.raises(ValueError, match="built for another sun"):
        _core.render_frame(req)


@pytest.mark.parametrize("weather", [{"clouds": "broken", **SUNNY}, {"clouds": "stratocumulus", "rain_rate_mm_h": 2.0}])
def test_gpu_draws_the_clouds_as_the_cpu(weather: dict) -> None:
    scene = scenes.street()
    cam = Camera(position_m=(1.5, 1.6, 0.0), pitch_deg=15.0)
    w = Weather(**weather)
    cpu = Renderer(96, 54, backend="cpu").render(scene, w, camera=cam)
    gpu = Renderer(96, 54, backend="gpu").render(scene, w, camera=cam)
    assert set(cpu.layers) == set(gpu.layers)
    for k in ("cloud_alpha", "sun_transmittance"):
        if k in cpu.layers:
            assert structural_similarity(cpu.layers[k], gpu.layers[k], data_range=1.0) >= 0.99
            np.testing.assert_allclose(gpu.layers[k], cpu.layers[k], atol=2e-3)
    scale = 1.0 / max(float(np.percentile(cpu.rgb, 99)), 1e-6)
    x, y = np.clip(cpu.rgb * scale, 0, 1), np.clip(gpu.rgb * scale, 0, 1)
    assert structural_similarity(x, y, channel_axis=2, data_range=1.0) >= 0.99
    assert cpu.layers["cloud_alpha"].max() > 0.3


def test_the_demo_shows_clouds_and_their_shadow_on_the_street() -> None:
    # What out/street_clouds.png is for: clouds in the sky, and a cloud's shadow over the
    # near street while the far street lies in the sun (the sun reaches both without clouds).
    from skyfall._demo import STREET_CLOUDS

    r = Renderer(320, 180, backend="cpu")
    f = STREET_CLOUDS.render(r)
    clear = r.render(STREET_CLOUDS.scene(), dataclasses.replace(STREET_CLOUDS.weather, clouds=None), camera=STREET_CLOUDS.camera())
    sky_px = np.isinf(f.depth_m)
    assert (f.layers["cloud_alpha"][sky_px] > 0.9).mean() > 0.1
    lit = (clear.layers["sun_transmittance"] > 0.99) & np.isfinite(f.depth_m)
    st = f.layers["sun_transmittance"]
    near, far = lit & (f.depth_m < 25.0), lit & (f.depth_m > 60.0)
    assert near.sum() > 500 and far.sum() > 50
    assert st[near].mean() < 0.3 and st[far].mean() > 0.6


def _sun_light(r: Renderer, scene, w: Weather, cloud: clouds.Cloud, diffuse: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """(the frame's light from the sun alone: the frame under the sun less the one without it;
    the frame without it), rgb (H, W, 3)."""
    from skyfall import _core

    out = []
    for weather in (w, Weather(sky=w.sky, sun_elevation_deg=w.sun_elevation_deg, sun_azimuth_deg=w.sun_azimuth_deg, sun_illuminance_lux=0.0)):
        req = r._request(scene, weather)
        req["clouds"] = clouds.frame_field(cloud, weather.sun_direction, diffuse=diffuse)
        out.append(_core.render_frame(req)[0].astype(np.float64))
    return out[0] - out[1], out[1]


def test_thin_clouds_single_scattering_matches_the_path_tracer() -> None:
    # Optically thin particles: the splat's alpha * source is the volume's single scattering,
    # and the Monte Carlo reference's first order gives it independently (analytic optical
    # depths along its rays, the exact phase function and transmittance).
    n = 9
    cam = Camera((0.0, 1000.0, 600.0), vertical_fov_deg=8.0, width=n, height=n)
    thin = clouds.Cloud(
        np.array([[0.0, 1000.0, 0.0], [15.0, 1010.0, -20.0]]), np.array([20.0, 15.0]), np.array([0.05, 0.08]), np.array([1.0, 1.0])
    )
    w = Weather(sky=12, sun_elevation_deg=30.0, sun_azimuth_deg=120.0)
    r = Renderer(n, n, backend="cpu")
    got = _sun_light(r, scenes.boxes([], ground=False, camera=cam), w, thin, diffuse=False)[0].reshape(-1, 3) @ LUMA
    c = cam.with_resolution(n, n)
    d = _unit_rays(c)
    mc, single, err = clouds.path_traced(thin, w.sun_direction, sun_relative=w.sun_relative, eye_m=c.position_m, directions=d, paths=4000, max_orders=3, seed=2)
    lit = single > 0.2 * single.max()
    assert lit.sum() >= 9
    # Pixel by pixel within the reference's noise (its standard error, all orders: about the
    # first order's here), and the summed light within 3 %.
    assert (np.abs(got[lit] - single[lit]) < 4.0 * err[lit] + 0.03 * single[lit]).all()
    assert got[lit].sum() / single[lit].sum() == pytest.approx(1.0, abs=0.03)
    assert (mc >= single).all() and np.median((mc - single)[lit] / single[lit]) < 0.1  # thin: little beyond first order
    # Optically thicker particles (τ 1 and 1.5, two suns): single scattering with the full
    # phase sees the full extinction towards the sun (the volume's δ-M share would scatter the
    # forward peak twice: 1.3-1.5x), the summed light within 6 % of the first order.
    thick = clouds.Cloud(thin.positions_m, thin.radii_m, np.array([1.0, 1.5]), thin.albedos)
    for sun in ((30.0, 120.0), (35.0, 10.0)):
        ws = Weather(sky=12, sun_elevation_deg=sun[0], sun_azimuth_deg=sun[1])
        got = _sun_light(r, scenes.boxes([], ground=False, camera=cam), ws, thick, diffuse=False)[0].reshape(-1, 3) @ LUMA
        _, first, _ = clouds.path_traced(thick, ws.sun_direction, sun_relative=ws.sun_relative, eye_m=c.position_m, directions=d, paths=2000, max_orders=1, seed=2)
        lit = first > 0.2 * first.max()
        assert lit.sum() >= 20
        assert got[lit].sum() / first[lit].sum() == pytest.approx(1.0, abs=0.06), sun
    # seeded
    again = clouds.path_traced(thin, w.sun_direction, sun_relative=w.sun_relative, eye_m=c.position_m, directions=d[:3], paths=50, max_orders=3, seed=2)
    np.testing.assert_array_equal(again[0], clouds.path_traced(thin, w.sun_direction, sun_relative=w.sun_relative, eye_m=c.position_m, directions=d[:3], paths=50, max_orders=3, seed=2)[0])
    with pytest.raises(ValueError, match="paths"):
        clouds.path_traced(thin, w.sun_direction, sun_relative=1.0, eye_m=c.position_m, directions=d, paths=0)


@pytest.mark.parametrize(
    ("view", "offset", "pitch", "fov", "sun", "depth", "paths"),
    [("side", (0.0, 0.0, 1200.0), 0.0, 18.0, (45.0, 120.0), 4.0, 96), ("below", (0.0, -700.0, 300.0), 60.0, 30.0, (60.0, 250.0), 2.0, 160)],
)
def test_a_thick_clouds_light_is_within_the_path_tracers_bounds(
    view: str, offset: tuple, pitch: float, fov: float, sun: tuple, depth: float, paths: int
) -> None:
    # A cloud the diffuse term's weights were not fitted to (seed 13, suns outside the fit's;
    # benches/clouds_fit.py), where multiple scattering is 90 % of the light: the frames'
    # summed sun light (single scattering + the diffuse term) within 0.8-1.25x of the path
    # tracer's, every order (the bounds), seen from the side and from below. The
    # two-stream sum the weights replaced gave 1.3-2.8x from the side. The billowed cloud's
    # reference sums have a heavy tail at optical depth x2 seen from the side: at 160 paths per
    # pixel the ratio read 1.04-1.25 over four seeds (their sums 188-225, each claiming 3 %), so
    # that view is tested at x4, where three seeds read 1.09-1.12.
    n = 16
    base = clouds.particles("cumulus", n_particles=600, extent_m=300.0, altitude_m=1000.0, seed=13)
    cloud = dataclasses.replace(base, optical_depths=base.optical_depths * depth)
    eye = base.positions_m.mean(axis=0) + np.array(offset)
    cam = Camera(eye, pitch_deg=pitch, vertical_fov_deg=fov, width=n, height=n)
    w = Weather(sky=12, sun_elevation_deg=sun[0], sun_azimuth_deg=sun[1])
    r = Renderer(n, n, backend="cpu")
    got = _sun_light(r, scenes.boxes([], ground=False, camera=cam), w, cloud)[0].reshape(-1, 3) @ LUMA
    d = _unit_rays(cam.with_resolution(n, n))
    mc, first, err = clouds.path_traced(cloud, w.sun_direction, sun_relative=w.sun_relative, eye_m=eye, directions=d, paths=paths, max_orders=512, seed=3)
    lit = mc > 0.05 * mc.max()
    assert lit.sum() >= 40 and first[lit].sum() < 0.2 * mc[lit].sum()
    noise = np.sqrt((err[lit] ** 2).sum()) / mc[lit].sum()  # the reference's own, relative
    assert noise < 0.05, noise
    ratio = got[lit].sum() / mc[lit].sum()
    assert 0.8 <= ratio <= 1.25, f"{view}: frames / path tracer {ratio:.3f} (noise {noise:.1%})"


def test_a_photos_clouds_take_its_skys_colour_but_the_suns_light_stays_white() -> None:
    # A photo under a blue sky (its airlight bluish): the clouds' sky-lit light is blue like it,
    # their sunlit light (the frame with the sun less the frame without) grey, at the photo's
    # luminance.
    n = 24
    cam = Camera((0.0, 1000.0, 600.0), vertical_fov_deg=10.0, width=n, height=n)
    blue = (0.2, 0.3, 0.6)
    photo = PhotoScene(np.tile(np.array(blue, np.float32), (n, n, 1)), np.full((n, n), np.inf, np.float32), camera=cam, encoding="linear", airlight=blue)
    one = clouds.Cloud(np.array([[0.0, 1000.0, 0.0]]), np.array([25.0]), np.array([3.0]), np.array([1.0]))
    w = Weather(sky=12, sun_elevation_deg=30.0, sun_azimuth_deg=120.0)
    sun, without = _sun_light(Renderer(n, n, backend="cpu"), photo, w, one)
    c = n // 2
    assert sun[c, c].min() > 0.0
    np.testing.assert_allclose(sun[c, c] / sun[c, c].mean(), 1.0, rtol=1e-4)  # grey
    sky_lit = without[c, c]
    assert sky_lit[2] > 1.5 * sky_lit[0]  # the sky's light on the cloud is blue like the sky


def test_the_sun_on_a_snow_cover_is_its_surfaces_share_on_both_backends() -> None:
    # Under a snow cover the visible surface is the snow's: sun_transmittance is the share the
    # cover's surface receives (lit ground 1, a building's shadow 0, a cloud's Gamma), the
    # same on both backends, and the shaded frame follows it.
    from skyfall import snow

    scene = scenes.street()
    sunny = {"sky": 12, "sun_elevation_deg": 50.0, "sun_azimuth_deg": 185.0}
    cover = snow.accumulate(scene, Weather(snow_rate_mm_h=3.0), duration_s=1800.0, dt_s=900.0, resolution_m=2.0)
    cam = Camera(position_m=(1.5, 1.6, 0.0), pitch_deg=8.0)
    cpu_r, gpu_r = Renderer(96, 54, backend="cpu"), Renderer(96, 54, backend="gpu")
    for weather in (Weather(**sunny), Weather(**sunny, clouds="broken")):
        cpu = cpu_r.render(scene, dataclasses.replace(weather, snow_cover=cover), camera=cam)
        gpu = gpu_r.render(scene, dataclasses.replace(weather, snow_cover=cover), camera=cam)
        np.testing.assert_allclose(gpu.layers["sun_transmittance"], cpu.layers["sun_transmittance"], atol=2e-3)
    clear = cpu_r.render(scene, Weather(**sunny, snow_cover=cover), camera=cam)
    st = clear.layers["sun_transmittance"]
    covered = clear.layers["snow_depth_m"] > 0.0
    assert covered.any() and st[covered].min() < 0.5 and st[covered].max() > 0.9
    dark = cpu_r.render(scene, Weather(**sunny, sun_illuminance_lux=0.0, snow_cover=cover), camera=cam)
    lit, shaded = covered & (st > 0.9), covered & (st == 0.0)
    assert (clear.rgb[lit][:, 1] > dark.rgb[lit][:, 1] + 1.0).all()  # the sun on the snow
    np.testing.assert_array_equal(clear.rgb[shaded], dark.rgb[shaded])  # none in the shadow


def test_clouds_drift_with_the_wind_in_a_sequence() -> None:
    # A cumulus ahead of the camera, the wind 20 m/s along +x: at t = 5 s the frame is the one
    # of the same cloud moved 100 m along x, at t = 0 the cloud's own frame (bit for bit), and
    # across a sequence the cloud's coverage moves right by the projection of wind * t.
    c = clouds.particles("cumulus", n_particles=300, extent_m=500.0, altitude_m=800.0, seed=2)
    c = c.translated((0.0, 0.0, -2500.0))
    cam = Camera((0.0, 1.6, 0.0), pitch_deg=20.0, vertical_fov_deg=40.0)
    scene = scenes.boxes([], camera=cam)
    r = Renderer(W, H, backend="cpu")
    wind = (20.0, 0.0, 0.0)
    still = r.render(scene, Weather(clouds=c))
    at0 = r.render(scene, Weather(clouds=c, wind_m_s=wind))
    np.testing.assert_array_equal(at0.rgb, still.rgb)
    at5 = r.render(scene, Weather(clouds=c, wind_m_s=wind), time_s=5.0)
    moved = r.render(scene, Weather(clouds=c.translated((100.0, 0.0, 0.0)), wind_m_s=wind))
    np.testing.assert_array_equal(at5.rgb, moved.rgb)
    np.testing.assert_array_equal(at5.layers["cloud_alpha"], moved.layers["cloud_alpha"])
    frames = r.render_sequence(scene, Weather(clouds=c, wind_m_s=wind), n_frames=3, fps=0.2)
    xs = np.arange(W) + 0.5
    centres = [float((f.layers["cloud_alpha"].sum(axis=0) * xs).sum() / f.layers["cloud_alpha"].sum()) for f in frames]
    # 100 m at about 2.6 km (the cloud's distance) is fx * 100 / z px to the right per frame.
    z = float(np.linalg.norm(c.positions_m.mean(axis=0) - np.array(cam.position_m)))
    fx = cam.with_resolution(W, H).intrinsics()[0]
    step = fx * 100.0 / z
    assert centres[1] - centres[0] == pytest.approx(step, rel=0.1), (centres, step)
    assert centres[2] - centres[1] == pytest.approx(step, rel=0.1), (centres, step)


def test_a_cumulus_has_a_dark_base_and_against_the_sun_a_silver_lining() -> None:
    # The cumulus preset from the ground, the sun 25 deg up: lit from behind the camera its flat
    # base is darker than its sunlit turrets (the base sees the light come through the cloud);
    # with the sun behind it, its thin edges scatter the sun forwards (Henyey-Greenstein, g 0.86)
    # and outshine both its core and the sky beside it. Measured: base 0.66 of the top; edges
    # 3.4x the core and 2.0x the sky.
    cam = Camera((0.0, 2.0, 0.0), pitch_deg=14.0, vertical_fov_deg=24.0)
    r = Renderer(160, 90, backend="cpu")
    luma = np.array([0.2126, 0.7152, 0.0722])
    seen = {}
    for az in (180.0, 0.0):
        w = Weather(sky=12, sun_elevation_deg=25.0, sun_azimuth_deg=az, clouds="cumulus", visibility_m=30_000.0)
        f = r.render(scenes.boxes([], camera=cam), w)
        seen[az] = (f.layers["cloud_alpha"], f.rgb @ luma)
    a, lum = seen[180.0]
    core = a > 0.98
    rows = np.nonzero(core.any(axis=1))[0]
    sixth = max(1, len(rows) // 6)
    top, base = rows[:sixth], rows[-sixth:]
    assert len(rows) > 20
    assert np.median(lum[base][core[base]]) < 0.8 * np.median(lum[top][core[top]])
    a, lum = seen[0.0]
    edge, core, sky = (a > 0.05) & (a < 0.5), a > 0.98, a < 0.01
    assert edge.sum() > 50 and core.sum() > 200
    assert np.median(lum[edge]) > 2.0 * np.median(lum[core])
    assert np.median(lum[edge]) > 1.3 * np.median(lum[sky])
