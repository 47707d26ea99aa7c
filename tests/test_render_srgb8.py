"""Renderer.render_srgb8: the fused 8-bit photo path against the float frame, against an
independent numpy + colour-science haze, and its fallbacks and errors."""

from __future__ import annotations

import colour
import numpy as np
import pytest

from skyfall import Camera, PhotoScene, Renderer, Weather, io, scenes
from skyfall._reference import path_to_cloud_base_m

W, H = 160, 101  # 101 rows: the last band of rows is short


@pytest.fixture(scope="module")
def cpu() -> Renderer:
    return Renderer(W, H, backend="cpu")


def photo8(seed: int = 0, near_wall: bool = True) -> PhotoScene:
    rng = np.random.default_rng(seed)
    img = rng.integers(0, 256, (H, W, 3), dtype=np.uint8)
    y, x = np.mgrid[0:H, 0:W]
    depth = (1.0 + 0.05 * x + 0.2 * y).astype(np.float32)
    depth[:20] = np.inf  # sky
    if near_wall:
        depth[:, :30] = 0.7
    cam = Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0)
    return PhotoScene(img, depth, camera=cam)


def test_the_fused_path_is_the_float_frame_encoded(cpu):
    scene = photo8(1)
    weather = Weather(rain_rate_mm_h=40.0, visibility_m=300.0, wind_m_s=(2.0, 0.0, 0.0))
    frame = cpu.render(scene, weather, seed=3)
    want = io.to_srgb8(frame.rgb)
    alpha = np.full((H, W), -1.0, np.float32)
    got = cpu.render_srgb8(scene, weather, seed=3, layers={"rain_alpha": alpha}).image
    assert got.dtype == np.uint8 and got.shape == (H, W, 3)
    # the same bits again (bands run in parallel; the streak order is a total order)
    assert cpu.render_srgb8(scene, weather, seed=3).tobytes() == got.tobytes()
    diff = np.abs(got.astype(int) - want)
    # The rain is applied as P*C + Q (the same sums, reassociated): within one code.
    assert diff.max() <= 1
    assert np.mean(diff > 0) < 1e-3
    np.testing.assert_allclose(alpha, frame.layers["rain_alpha"], atol=1e-6)
    assert frame.layers["rain_alpha"].max() > 0.01
    # and the rain did change the picture: many bytes differ from the haze-only frame
    haze_only = cpu.render_srgb8(scene, Weather(visibility_m=300.0), seed=3)
    assert np.mean(haze_only != got) > 0.05


def test_haze_matches_numpy_and_colour_science(cpu):
    # Yamamoto & Tadamura eq. 2, written independently, decoded and encoded by colour-science.
    scene = photo8(2, near_wall=False)
    weather = Weather(visibility_m=80.0)
    sigma = weather.extinction_per_m
    got = cpu.render_srgb8(scene, weather)
    fx, fy, cx, cy = scene.camera.intrinsics()
    y, x = np.mgrid[0:H, 0:W] + 0.5
    u, v = (x - cx) / fx, (y - cy) / fy
    per_depth = np.sqrt(u**2 + v**2 + 1)
    dist = scene.depth_m.astype(np.float64) * per_depth
    # a sky pixel is hazed up to the cloud base above the eye, a shell over the Earth's sphere
    # (a level camera: sin el = -v / |ray|)
    sin_el = -v / per_depth
    ceiling = weather.cloud_base_height_m - 1.6
    with np.errstate(invalid="ignore", over="ignore"):
        t_sky = np.exp(-sigma * path_to_cloud_base_m(sin_el, ceiling))
        t = np.where(np.isinf(dist), t_sky, np.exp(-sigma * dist))[..., None]
    # the airlight is the photo's own, estimated from it (He, Sun & Tang)
    air = np.array(scene.airlight_linear)
    linear = colour.cctf_decoding(scene.srgb8 / 255.0, function="sRGB") * t + air * (1 - t)
    want = np.round(255 * colour.cctf_encoding(np.clip(linear, 0, 1), function="sRGB")).astype(int)
    diff = np.abs(got.astype(int) - want)
    assert diff.max() <= 1 and np.mean(diff > 0) < 1e-3


def test_clear_weather_gives_the_bytes_back(cpu):
    scene = photo8(3)
    out = np.zeros((H, W, 3), np.uint8)
    alpha = np.ones((H, W), np.float32)
    got = cpu.render_srgb8(scene, Weather(), out=out, layers={"rain_alpha": alpha}).image
    assert got is out
    assert got.tobytes() == scene.srgb8.tobytes()
    assert not alpha.any()


def test_other_scenes_and_float_photos_render_then_encode(cpu):
    # Box scenes and linear float photos take the float frame, encoded: the same bytes.
    weather = Weather(rain_rate_mm_h=20.0, visibility_m=500.0)
    street = scenes.street()
    want = io.to_srgb8(cpu.render(street, weather, seed=1).rgb)
    assert cpu.render_srgb8(street, weather, seed=1).tobytes() == want.tobytes()
    lin = PhotoScene(photo8(4).image, photo8(4).depth_m, camera=photo8(4).camera, encoding="linear")
    alpha = np.empty((H, W), np.float32)
    got = cpu.render_srgb8(lin, weather, seed=1, layers={"rain_alpha": alpha}).image
    frame = cpu.render(lin, weather, seed=1)
    assert got.tobytes() == io.to_srgb8(frame.rgb).tobytes()
    assert alpha.tobytes() == frame.layers["rain_alpha"].tobytes()


def test_gpu_backend_gives_the_same_bytes_within_a_code():
    gpu = Renderer(W, H, backend="gpu")
    cpu = Renderer(W, H, backend="cpu")
    scene = photo8(5)
    weather = Weather(rain_rate_mm_h=30.0, visibility_m=400.0)
    a = gpu.render_srgb8(scene, weather, seed=2).astype(int)
    b = cpu.render_srgb8(scene, weather, seed=2).astype(int)
    assert np.mean(np.abs(a - b) <= 1) > 0.99


def test_bad_outputs_are_refused(cpu):
    scene = photo8(6)
    with pytest.raises(ValueError, match="out must be .* got dtype float32"):
        cpu.render_srgb8(scene, out=np.zeros((H, W, 3), np.float32))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="the photo is"):
        Renderer(W + 2, H, backend="cpu").render_srgb8(scene)
    # what is wrong is named: the dtype, the shape, the layout, the type
    with pytest.raises(ValueError, match=r"layers\['rain_alpha'\] must be .* shape \(101, 160\), got dtype float64"):
        cpu.render_srgb8(scene, layers={"rain_alpha": np.zeros((H, W), np.float64)})  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"out must be .*, got shape \(101, 161, 3\)"):
        cpu.render_srgb8(scene, out=np.zeros((H, W + 1, 3), np.uint8))
    with pytest.raises(ValueError, match=r"layers\['rain_alpha'\] .* got an array that is not C-contiguous"):
        cpu.render_srgb8(scene, layers={"rain_alpha": np.zeros((W, H), np.float32).T})
    read_only = np.zeros((H, W, 3), np.uint8)
    read_only.flags.writeable = False
    with pytest.raises(ValueError, match="out .* got a read-only array"):
        cpu.render_srgb8(scene, out=read_only)
    with pytest.raises(TypeError, match=r"layers\['rain_alpha'\] must be .* got list"):
        cpu.render_srgb8(scene, layers={"rain_alpha": [[0.0] * W] * H})  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="weather"):
        cpu.render_srgb8(scene, "rain")  # type: ignore[arg-type]


def test_a_photo_of_another_size_is_named_before_the_outputs_made_for_it():
    # The README's order: outputs sized from the photo, a renderer of another size. The
    # renderer's size is what is wrong, and it is what the error says (it used to blame
    # rain_alpha_out).
    scene = photo8(7)
    alpha = np.empty(scene.depth_m.shape, np.float32)
    image = np.empty((H, W, 3), np.uint8)
    for backend in ("cpu", "gpu"):
        other = Renderer(2 * W, 2 * H, backend=backend)
        with pytest.raises(ValueError, match=r"the photo is 160x101 px, the renderer 320x202 px: .*Renderer\(160, 101\)"):
            other.render_srgb8(scene, Weather(rain_rate_mm_h=10.0), out=image, layers={"rain_alpha": alpha})
        with pytest.raises(ValueError, match="the photo is 160x101 px"):
            other.render(scene, Weather(rain_rate_mm_h=10.0))


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_outputs_that_overlap_the_inputs_are_refused(backend):
    # A photo's arrays are the caller's: writing into them would change the scene itself (on
    # the GPU path rain_alpha_out=depth used to overwrite the depth map silently).
    r = Renderer(W, H, backend=backend)
    img = np.random.default_rng(1).integers(0, 256, (H, W, 3), dtype=np.uint8)
    depth = np.full((H, W), 5.0, np.float32)
    scene = PhotoScene(img, depth, camera=Camera((0.0, 1.6, 0.0)))
    rain = Weather(rain_rate_mm_h=10.0)
    before = (img.copy(), depth.copy())
    with pytest.raises(ValueError, match="out overlaps the scene's image"):
        r.render_srgb8(scene, rain, out=img)
    with pytest.raises(ValueError, match=r"layers\['rain_alpha'\] overlaps the scene's depth_m"):
        r.render_srgb8(scene, rain, layers={"rain_alpha": depth})
    buf = np.empty(H * W * 4, np.float32)
    with pytest.raises(ValueError, match=r"out overlaps layers\['rain_alpha'\]"):
        r.render_srgb8(scene, rain, out=buf.view(np.uint8)[: H * W * 3].reshape(H, W, 3), layers={"rain_alpha": buf[: H * W].reshape(H, W)})
    assert np.array_equal(img, before[0]) and np.array_equal(depth, before[1])
    float_scene = PhotoScene(io.decode_srgb8(img), depth, camera=Camera((0.0, 1.6, 0.0)), encoding="linear")
    with pytest.raises(ValueError, match=r"layers\['rain_alpha'\] overlaps the scene's image"):
        r.render_srgb8(float_scene, rain, layers={"rain_alpha": float_scene.image.reshape(-1)[: H * W].reshape(H, W)})


def test_fuses_srgb8_says_which_path_render_srgb8_takes():
    from skyfall import snow, windshield

    r = Renderer(32, 24, backend="cpu")
    photo8 = PhotoScene(np.full((24, 32, 3), 120, np.uint8), depth_m=np.full((24, 32), 30.0, np.float32))
    assert r.fuses_srgb8(photo8, Weather(rain_rate_mm_h=5.0))
    assert not r.fuses_srgb8(scenes.street(), Weather())
    glass = windshield.Windshield(5.0, glass_width_mm=100.0, glass_height_mm=100.0, wipers=0)
    assert not r.fuses_srgb8(photo8, Weather(windshield=glass))
    cover = snow.accumulate(scenes.empty(), Weather(snow_rate_mm_h=1.0), duration_s=600.0, dt_s=600.0, resolution_m=10.0)
    assert not r.fuses_srgb8(photo8, Weather(snow_cover=cover))
    # srgb8_path names the three paths
    assert r.srgb8_path(photo8, Weather(rain_rate_mm_h=5.0), layers=("rain_alpha",)) == "fused"
    assert r.srgb8_path(photo8, Weather(rain_rate_mm_h=5.0), layers=("transmittance",)) == "banded"
    assert r.srgb8_path(photo8, Weather(snow_cover=cover)) == "banded"
    assert r.srgb8_path(scenes.street(), Weather()) == "banded"
    assert r.srgb8_path(photo8, Weather(windshield=glass)) == "banded"


@pytest.mark.parametrize("level", ["scalar", "avx2"])
def test_every_simd_level_gives_the_same_bytes(cpu, monkeypatch, level):
    # The fused path's kernels at the best level the CPU has against a capped one (the scalar
    # twins, or AVX2 below AVX-512): identical bytes and masks; a level above the CPU's is
    # capped at it, so this runs everywhere. And io.to_srgb8's encoder alike.
    scene = photo8(4)
    weather = Weather(rain_rate_mm_h=40.0, visibility_m=300.0, wind_m_s=(2.0, 0.0, 0.0))
    alpha_best = np.empty((H, W), np.float32)
    best = cpu.render_srgb8(scene, weather, seed=5, layers={"rain_alpha": alpha_best}).image
    linear = np.linspace(-0.1, 1.1, 3 * W * H, dtype=np.float32).reshape(H, W, 3)
    encoded = io.to_srgb8(linear)
    monkeypatch.setenv("SKYFALL_SIMD", level)
    alpha = np.empty((H, W), np.float32)
    capped = cpu.render_srgb8(scene, weather, seed=5, layers={"rain_alpha": alpha}).image
    np.testing.assert_array_equal(capped, best)
    np.testing.assert_array_equal(alpha, alpha_best)
    np.testing.assert_array_equal(io.to_srgb8(linear), encoded)
    assert (best != scene.srgb8).mean() > 0.5 and alpha_best.max() > 0.005
    monkeypatch.setenv("SKYFALL_SIMD", "")
    monkeypatch.setenv("SKYFALL_SCALAR_KERNELS", "shade,transmittance")
    np.testing.assert_array_equal(cpu.render_srgb8(scene, weather, seed=5), best)


def _float_then_encode(r: Renderer, scene, weather, layers, **kw):
    frame = r.render(scene, weather, layers=layers, **kw)
    return io.to_srgb8(frame.rgb), frame.layers


@pytest.mark.parametrize(
    "case",
    [
        "clouds over a photo",
        "snow cover on a photo",
        "box scene with lamps at dusk",
        "snowfall on a box scene",
        "a layer the fused path does not fill",
        "a photo through a windshield",
    ],
)
def test_every_stage_is_drawn_by_the_8_bit_output_as_the_float_frame_encoded(cpu, case):
    """What the fused path does not draw goes band by band through the stages, each band
    encoded as it is finished (_core.render_frame8): the bytes of the float frame encoded by
    io.to_srgb8, and the same layers, on every row (101 rows: the last band is short)."""
    from skyfall import snow

    layers: tuple[str, ...] = ("rain_alpha",)
    kw: dict = {"seed": 3, "ambient_spacing_m": 8.0}
    if case == "clouds over a photo":
        scene, weather = photo8(5), Weather(clouds="broken", sun_elevation_deg=30.0, sun_azimuth_deg=180.0, rain_rate_mm_h=5.0)
        layers = ("cloud_alpha", "rain_alpha")
    elif case == "snow cover on a photo":
        cover = snow.accumulate(scenes.empty(), Weather(snow_rate_mm_h=2.0), duration_s=1800.0, dt_s=600.0, resolution_m=2.0)
        # a photo of flat ground (depth from the camera's height, 1.6 m) under a sky
        flat = photo8(6)
        fx, fy, cx, cy = flat.camera.intrinsics()
        rows = np.arange(H) + 0.5 - cy
        depth = np.where(rows > 0, 1.6 * fy / np.maximum(rows, 1e-6), np.inf)[:, None].repeat(W, 1).astype(np.float32)
        scene = PhotoScene(flat.srgb8, depth, camera=flat.camera)
        weather = Weather(snow_cover=cover, visibility_m=400.0)
        layers = ("snow_depth_m", "transmittance")
    elif case == "box scene with lamps at dusk":
        scene, weather = scenes.street(lamps=True), Weather(rain_rate_mm_h=20.0, visibility_m=300.0)
        layers = ("rain_alpha", "transmittance", "snow_alpha")  # snow_alpha: no stage draws it, neutral
    elif case == "snowfall on a box scene":
        scene, weather = scenes.street(), Weather(snow_rate_mm_h=3.0)
        layers = ("snow_alpha",)
    elif case == "a photo through a windshield":
        from skyfall import windshield

        glass = windshield.Windshield(30.0, glass_width_mm=300.0, glass_height_mm=250.0, wipers=1, wiper_period_s=1.0, seed=2)
        glass.step(0.7)
        scene, weather = photo8(8), Weather(rain_rate_mm_h=10.0, visibility_m=300.0, windshield=glass)
        layers = ("drop_mask", "rain_alpha", "drop_height")
    else:
        scene, weather = photo8(7), Weather(rain_rate_mm_h=30.0, visibility_m=200.0)
        layers = ("rain_alpha", "transmittance", "rain_depth_m")
    assert not cpu.fuses_srgb8(scene, weather, layers=layers)
    got = cpu.render_srgb8(scene, weather, layers=layers, **kw)
    want, want_layers = _float_then_encode(cpu, scene, weather, layers, **kw)
    assert got.image.tobytes() == want.tobytes()
    assert list(got.layers) == list(layers)
    for name in layers:
        np.testing.assert_array_equal(got.layers[name], want_layers[name], err_msg=name)
    # the effect drew: its first layer is not neutral everywhere (snow_alpha on the street at
    # dusk is the layer no stage draws: its neutral 0 everywhere)
    first = got.layers[layers[0]]
    assert np.ptp(first) > 0 or case == "box scene with lamps at dusk", case


def test_the_banded_8_bit_output_hazes_as_numpy_and_colour_science_do(cpu):
    # The haze of test_haze_matches_numpy_and_colour_science through the banded path (a
    # transmittance layer asked for, which the fused path does not fill), against the same
    # independent reference, and its transmittance layer against exp(-sigma d) on ground pixels.
    scene = photo8(2, near_wall=False)
    weather = Weather(visibility_m=80.0)
    got = cpu.render_srgb8(scene, weather, layers=("transmittance",))
    fused = cpu.render_srgb8(scene, weather)
    diff = np.abs(got.image.astype(int) - fused.astype(int))
    assert diff.max() <= 1 and np.mean(diff > 0) < 1e-3
    fx, fy, cx, cy = scene.camera.intrinsics()
    y, x = np.mgrid[0:H, 0:W] + 0.5
    dist = scene.depth_m.astype(np.float64) * np.sqrt(((x - cx) / fx) ** 2 + ((y - cy) / fy) ** 2 + 1)
    ground = np.isfinite(dist)
    np.testing.assert_allclose(got.layers["transmittance"][ground], np.exp(-weather.extinction_per_m * dist[ground]), rtol=1e-4)
