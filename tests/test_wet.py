"""Wet surfaces (``Weather.rain_duration_s``, ``dry_s``), against references computed here:
Lekner & Dorf's wet albedo and Fresnel's equations in numpy, the mirror image of the sky in
the frame's own sky pixels (a puddle's), the CIE overcast sky averaged over the film's GGX
lobe by quadrature (the film's grained image), a lamp's mirrored position, the shelter of a
slab, the puddles' share from the relief's water balance, drying in time, and dry weather
that leaves the frame's bits alone."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from skyfall import Camera, PhotoScene, PointLight, Renderer, Weather, io, scenes

W, H = 96, 72
N_WATER = 1.33
AFTER_RAIN = Weather(rain_rate_mm_h=5.0, rain_duration_s=None, dry_s=1.0)
"""Surfaces as wet as they get, a second after the rain stopped: no rain in the air."""


def fresnel(cos_i: np.ndarray, n: float = N_WATER) -> np.ndarray:
    """Unpolarised reflectance from air into index n (Fresnel's equations)."""
    c = np.clip(cos_i, 0.0, 1.0)
    ct = np.sqrt(1.0 - (1.0 - c**2) / n**2)
    rs = ((c - n * ct) / (c + n * ct)) ** 2
    rp = ((ct - n * c) / (ct + n * c)) ** 2
    return 0.5 * (rs + rp)


def wet_albedo(a: np.ndarray, n: float = N_WATER) -> np.ndarray:
    """Lekner & Dorf (1988): (1 - R)(1 - p) a / (1 - p a), R the film's reflectance for diffuse
    light (integrated here), p = 1 - (1 - R)/n^2 its internal reflection of diffuse light."""
    th = (np.arange(100_000) + 0.5) / 100_000 * np.pi / 2
    r_diffuse = np.sum(fresnel(np.cos(th), n) * np.sin(2 * th)) * (np.pi / 2 / 100_000)
    p = 1.0 - (1.0 - r_diffuse) / n**2
    return (1.0 - r_diffuse) * a * (1.0 - p) / (1.0 - p * a)


ALPHA_FILM, ALPHA_PUDDLE = 0.12, 0.04
"""The GGX roughness of the film and of a puddle (``skyfall_core::wet::optics``)."""


def lobe_directions(d: np.ndarray, alpha: float = ALPHA_FILM, k: int = 24) -> np.ndarray:
    """The directions a view ray d (..., 3) leaves level ground (normal +y) about the microfacet
    normals of a GGX lobe, by a k x k midpoint quadrature of its sampling (tan^2 theta =
    alpha^2 u/(1-u), phi = 2 pi u2), a ray sent into the ground mirrored about +y instead:
    (..., k*k, 3)."""
    u = (np.arange(k) + 0.5) / k
    u1, u2 = (g.ravel() for g in np.meshgrid(u, u))
    tan = alpha * np.sqrt(u1 / (1.0 - u1))
    cos_t = 1.0 / np.sqrt(1.0 + tan**2)
    sin_t = tan * cos_t
    m = np.stack([sin_t * np.cos(2 * np.pi * u2), cos_t, sin_t * np.sin(2 * np.pi * u2)], axis=-1)
    d = d[..., None, :] / np.linalg.norm(d, axis=-1, keepdims=True)[..., None, :]
    r = d - 2.0 * np.sum(d * m, axis=-1, keepdims=True) * m
    mirror = d * np.array([1.0, -1.0, 1.0])
    return np.where(r[..., 1:2] > 0.0, r, np.broadcast_to(mirror, r.shape))


def view_rays(cam: Camera) -> np.ndarray:
    """Each pixel's view ray in the world (H, W, 3), not normalised."""
    fx, fy, cx, cy = cam.with_resolution(W, H).intrinsics()
    ys, xs = np.mgrid[0:H, 0:W]
    d = np.stack([(xs + 0.5 - cx) / fx, -(ys + 0.5 - cy) / fy, -np.ones((H, W))], axis=-1)
    return d @ cam.rotation.T


def level_camera() -> Camera:
    return Camera((0.0, 1.5, 0.0), vertical_fov_deg=60.0)


def view_cosines(cam: Camera) -> np.ndarray:
    """cos of the angle between each pixel's view ray and the vertical (H, W), level camera."""
    fx, fy, cx, cy = cam.with_resolution(W, H).intrinsics()
    ys, xs = np.mgrid[0:H, 0:W]
    d = np.stack([(xs + 0.5 - cx) / fx, -(ys + 0.5 - cy) / fy, -np.ones((H, W))], axis=-1)
    d = d @ cam.rotation.T
    return np.abs(d[..., 1]) / np.linalg.norm(d, axis=-1)


@pytest.fixture(scope="module")
def cpu() -> Renderer:
    return Renderer(W, H, backend="cpu")


@pytest.mark.parametrize("albedo", [0.05, 0.2, 0.5, 0.8])
def test_open_ground_darkens_as_lekner_and_dorf_and_mirrors_the_sky(cpu, albedo):
    # A level camera over open ground under the overcast sky: the view ray of ground row y is the
    # sky row H-1-y mirrored. A puddle mirrors it: wet = dry * A_wet(a)/a + F(cos) * sky[H-1-y],
    # on every puddle pixel (edges, top and bottom rows of the ground included). The film
    # elsewhere mirrors the sky about its GGX grain: its reflection over F, averaged along a
    # row, is the CIE overcast sky (1 + 2 sin elevation, fitted to the frame's sky pixels)
    # averaged over the lobe by quadrature here.
    cam = level_camera()
    scene = scenes.boxes([], ground=True, ground_albedo=albedo, camera=cam)
    dry = cpu.render(scene, Weather())
    wet = cpu.render(scene, AFTER_RAIN)
    ground = np.isfinite(dry.depth_m)
    assert ground[H // 2 :].all() and not ground[: H // 2].any()
    puddle = wet.layers["puddle_mask"] == 1.0
    film = ground & ~puddle
    assert 0.05 < puddle[ground].mean() < 0.6 and not puddle[~ground].any()
    assert set(np.unique(wet.layers["puddle_mask"])) == {0.0, 1.0}
    mirrored_sky = dry.rgb[::-1]
    cos = view_cosines(cam)[..., None]
    darkened = dry.rgb * (wet_albedo(albedo) / albedo)
    want = darkened + fresnel(cos) * mirrored_sky
    np.testing.assert_allclose(wet.rgb[puddle], want[puddle], rtol=2e-4, atol=1e-6)
    np.testing.assert_array_equal(wet.rgb[~ground], dry.rgb[~ground])
    np.testing.assert_array_equal(wet.layers["wetness"], ground.astype(np.float32))
    assert "wetness" not in dry.layers and "puddle_mask" not in dry.layers
    # the sky is the CIE overcast sky: radiance c (1 + 2 sin elevation)
    d = view_rays(cam)
    sin_el = d[..., 1] / np.linalg.norm(d, axis=-1)
    law = 1.0 + 2.0 * sin_el[~ground]
    c = np.sum(dry.rgb[~ground][:, 1] * law) / np.sum(law**2)
    np.testing.assert_allclose(dry.rgb[~ground][:, 1], c * law, rtol=1e-4)
    lobe = c * (1.0 + 2.0 * lobe_directions(d[film])[..., 1]).mean(axis=-1)
    seen = (wet.rgb - darkened)[..., 1][film] / fresnel(cos[..., 0])[film]
    rows = np.nonzero(film)[0]
    for y in np.unique(rows):
        at = rows == y
        assert abs(seen[at].mean() / lobe[at].mean() - 1.0) < 0.1, (y, seen[at].mean(), lobe[at].mean())
    assert abs(seen.mean() / lobe.mean() - 1.0) < 0.02, (seen.mean(), lobe.mean())
    # and it is not the puddles' mirror image: the lobe reaches higher, brighter sky
    assert np.mean(seen) > 1.02 * np.mean(mirrored_sky[..., 1][film])


def ggx_highlight(n, v, l, alpha: float | np.ndarray = ALPHA_FILM) -> np.ndarray:
    """The film's GGX BRDF (Trowbridge-Reitz D, Smith's G, Fresnel at v.h), sr^-1, per row of
    unit vectors: Walter et al. 2007's microfacet model."""
    h = v + l
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    nv, nl, nh = (np.sum(n * a, axis=-1) for a in (v, l, h))
    a2 = alpha**2
    d = a2 / (np.pi * (nh**2 * (a2 - 1.0) + 1.0) ** 2)

    def g1(c):
        return 2 * c / (c + np.sqrt(a2 + (1 - a2) * c**2))

    return fresnel(np.sum(v * h, axis=-1)) * d * g1(nv) * g1(nl) / (4 * nv * nl)


def test_a_lamp_is_mirrored_where_geometry_puts_it(cpu):
    # A lamp 4 m up, 20 m ahead, over dark open ground at dusk. Its highlight is the GGX lobe
    # computed here on every ground pixel (the film's roughness, a puddle's where the frame's
    # puddle_mask says); the streak runs through the pixel where the line from the eye to the
    # lamp's mirror image (y -> -y) meets the ground, in its column, its peak pulled a few
    # pixels towards the horizon (grazing light: Fresnel and 1/cos).
    cam = level_camera()
    lamp = PointLight((1.0, 4.0, -20.0), 8000.0)
    e_sky = 1.0
    scene = scenes.boxes([], ground=True, ground_albedo=0.05, camera=cam, lights=(lamp,))
    weather = replace(AFTER_RAIN, sky_illuminance_lux=e_sky)
    frame = cpu.render(scene, weather)
    dry = cpu.render(scene, Weather(sky_illuminance_lux=e_sky))
    ground = np.isfinite(dry.depth_m)
    # the sky's own image on the wet ground: the same wet frame without the lamp, whose
    # diffuse light (darkened) is added back (the lamp's emitter disc, drawn after the wet
    # stage, is not in the film's mirror: its highlight stands for it)
    unlit = replace(scene, lights=())
    sky_part = cpu.render(unlit, weather).rgb - cpu.render(unlit, Weather(sky_illuminance_lux=e_sky)).rgb * (wet_albedo(0.05) / 0.05)
    highlight = (frame.rgb - dry.rgb * (wet_albedo(0.05) / 0.05) - sky_part)[..., 1]
    puddle = frame.layers["puddle_mask"] == 1.0
    # the reference: lamp illuminance on the ground I cos / r^2 over E, times the BRDF
    fx, fy, cx, cy = cam.with_resolution(W, H).intrinsics()
    ys, xs = np.mgrid[0:H, 0:W]
    d = np.stack([(xs + 0.5 - cx) / fx, -(ys + 0.5 - cy) / fy, -np.ones((H, W))], axis=-1) @ cam.rotation.T
    eye = np.asarray(cam.position_m)
    p = eye + d * np.where(ground, dry.depth_m, 0.0)[..., None]
    ground &= np.abs(p[..., 1]) < 1e-3  # not the lamp's emitter disc
    assert ground.sum() > 0.45 * W * H
    to_lamp = np.asarray(lamp.position_m) - p
    r = np.linalg.norm(to_lamp, axis=-1, keepdims=True)
    l = to_lamp / r
    v = -d / np.linalg.norm(d, axis=-1, keepdims=True)
    n = np.broadcast_to([0.0, 1.0, 0.0], p.shape)
    e = lamp.intensity_cd * l[..., 1] / r[..., 0] ** 2 / e_sky
    alpha = np.where(puddle, ALPHA_PUDDLE, ALPHA_FILM)
    assert 0.05 < puddle[ground].mean() < 0.6
    want = ggx_highlight(n[ground], v[ground], l[ground], alpha[ground]) * e[ground]
    np.testing.assert_allclose(highlight[ground], want, rtol=2e-3, atol=2e-5 * want.max())
    # where it lies: through the mirror point, in its column
    mirror = np.array(lamp.position_m) * np.array([1.0, -1.0, 1.0])
    hit = eye + eye[1] / (eye[1] - mirror[1]) * (mirror - eye)
    pc = cam.rotation.T @ (hit - eye)
    px, py = cx + fx * pc[0] / -pc[2], cy - fy * pc[1] / -pc[2]
    # (on the surface the mirror point lies on: a puddle's lobe is narrower and its peak higher)
    same = ground & (puddle == puddle[int(py), int(px)])
    y, x = np.unravel_index(np.argmax(np.where(same, highlight, 0.0)), highlight.shape)
    assert abs(x + 0.5 - px) <= 1.0, (x, px)
    assert highlight[int(py), int(px)] > 0.3 * highlight[y, x]
    assert highlight[y, x] > 100 * np.median(highlight[ground])


@pytest.mark.parametrize("wind", [(0.0, 0.0, 0.0), (3.0, 0.0, 0.0)])
def test_ground_under_a_slab_stays_dry_as_the_rain_slants(cpu, wind):
    # A slab 3 m up: a ground point is dry when every quartile drop's path up from it meets the
    # slab; in a calm that is the slab's footprint exactly. Checked on every ground pixel away
    # from the footprint's edge. The volume quartile drops of 5 mm/h (0.9-1.8 mm) fall at
    # 3.3-6.1 m/s (Gunn & Kinzer), bracketed here by 3 and 7 m/s: in 3 m/s of wind the dry
    # patch moves 1.3-3 m downwind.
    cam = Camera((0.0, 1.5, 6.0), pitch_deg=-30.0, vertical_fov_deg=70.0)
    slab = {"min": (-2.0, 3.0, -3.0), "max": (2.0, 3.2, 1.0), "albedo": 0.5}
    scene = scenes.boxes([slab], ground=True, ground_albedo=0.2, camera=cam)
    frame = cpu.render(scene, Weather(rain_rate_mm_h=5.0, rain_duration_s=None, wind_m_s=wind, rain_streaks=False))
    wet = frame.layers["wetness"]
    depth = frame.depth_m
    fx, fy, cx, cy = cam.with_resolution(W, H).intrinsics()
    ys, xs = np.mgrid[0:H, 0:W]
    d = np.stack([(xs + 0.5 - cx) / fx, -(ys + 0.5 - cy) / fy, -np.ones((H, W))], axis=-1) @ cam.rotation.T
    p = np.asarray(cam.position_m) + d * np.where(np.isfinite(depth), depth, 0.0)[..., None]
    ground = np.isfinite(depth) & (np.abs(p[..., 1]) < 1e-3)
    shift = 3.0 * wind[0] / np.array([7.0, 3.0])  # least and most slanted quartile drop
    under = ground & (p[..., 0] > -2.0 + shift[1] + 0.1) & (p[..., 0] < 2.0 + shift[0] - 0.1) & (p[..., 2] > -2.9) & (p[..., 2] < 0.9)
    clear = ground & ((p[..., 0] < -2.1 + shift[0]) | (p[..., 0] > 2.1 + shift[1]) | (p[..., 2] < -3.1) | (p[..., 2] > 1.1))
    assert under.sum() > 50 and clear.sum() > 50
    assert (wet[under] == 0.0).all()
    assert (wet[clear] == 1.0).all()
    assert (frame.layers["puddle_mask"][under] == 0.0).all() and frame.layers["puddle_mask"][clear].mean() > 0.05


@pytest.mark.parametrize("x0", [0.0, -500.0])
def test_puddles_cover_the_share_the_reliefs_water_balance_gives(x0):
    # Open ground seen from 60 m up (about 120 x 90 m of it). Of the water a surface holds, the
    # first 0.2 mm is the film and the rest pools in a relief uniform in depth over 16 mm: the
    # puddles cover sqrt(2 (water - 0.2) / 16) of the ground. 6 mm/h for 4 and 6 min holds
    # 0.4 and 0.6 mm, a long rain the 1 mm of storage, and half an hour of drying at 0.25 mm/h
    # takes 0.125 mm of it. Each puddle lies inside the next larger (one relief, a rising
    # level), so they grow with the rain and shrink as it dries, in place.
    r = Renderer(160, 120, backend="cpu")
    cam = Camera((x0, 60.0, 0.0), pitch_deg=-89.0, vertical_fov_deg=90.0)
    scene = scenes.boxes([], ground=True, ground_albedo=0.2, camera=cam)
    cases = [(240.0, 0.0, 0.4), (360.0, 0.0, 0.6), (None, 1800.0, 0.875), (None, 0.0, 1.0)]
    masks = []
    for duration, dry, water in cases:
        frame = r.render(scene, Weather(rain_rate_mm_h=6.0, rain_duration_s=duration, dry_s=dry, rain_streaks=False), layers=("puddle_mask",))
        assert np.isfinite(frame.depth_m).all()
        mask = frame.layers["puddle_mask"]
        assert abs(mask.mean() - np.sqrt(2.0 * (water - 0.2) / 16.0)) < 0.015, (water, mask.mean())
        masks.append(mask == 1.0)
    for smaller, larger in zip(masks[:-1], masks[1:]):
        assert (larger | ~smaller).all() and larger.sum() > smaller.sum()
    # a film no thicker than the wet film holds no puddle
    thin = r.render(scene, Weather(rain_rate_mm_h=6.0, rain_duration_s=120.0, rain_streaks=False), layers=("puddle_mask", "wetness"))
    assert (thin.layers["wetness"] == 1.0).all() and (thin.layers["puddle_mask"] == 0.0).all()


def test_surfaces_dry_after_the_rain_and_no_rain_falls(cpu):
    # 10 mm/h for 60 s leaves 1/6 mm on open ground (wetness 1/6 / 0.2); it evaporates at
    # 0.25 mm/h once the rain stops: the open ground's wetness (the layer's maximum) is that
    # water balance, falling monotonically to 0.
    scene = scenes.street()
    rain = dict(rain_rate_mm_h=10.0, rain_duration_s=60.0)
    times = (0.0, 600.0, 1200.0, 1800.0, 2400.0)
    wet = [cpu.render(scene, Weather(**rain, dry_s=t)).layers.get("wetness", np.zeros(1)).max() for t in times]
    want = [max(0.0, (10.0 * 60.0 - 0.25 * t) / 3600.0) / 0.2 for t in times]
    np.testing.assert_allclose(wet, want, rtol=1e-5, atol=1e-7)
    assert all(b < a for a, b in zip(wet[:-1], wet[1:-1]))
    after = cpu.render(scene, Weather(**rain, dry_s=600.0))
    assert "rain_alpha" not in after.layers and not after.stats.get("streaks_drawn")
    dried = cpu.render(scene, Weather(**rain, dry_s=4 * 3600.0))
    nothing = cpu.render(scene, Weather())
    np.testing.assert_array_equal(dried.rgb, nothing.rgb)
    assert set(dried.layers) == set(nothing.layers)


def test_dry_weather_leaves_the_frame_unchanged(cpu):
    scene = scenes.street(lamps=True)
    for w in (Weather(rain_rate_mm_h=10.0), Weather(rain_rate_mm_h=0.0, rain_duration_s=None)):
        assert "wetness" not in cpu.render(scene, w, seed=3).layers
    a = cpu.render(scene, Weather(rain_rate_mm_h=10.0, rain_duration_s=0.0), seed=3)
    b = cpu.render(scene, Weather(rain_rate_mm_h=10.0), seed=3)
    np.testing.assert_array_equal(a.rgb, b.rgb)


def test_a_photo_of_open_ground_darkens_and_mirrors_its_own_sky():
    # The same analytic frame as a photo: its depth map the ground plane, its sky rows a
    # gradient; the screen-space march finds no surface above the ground, so each puddle pixel
    # mirrors the photo's sky pixel at the mirrored row, and the film elsewhere, averaged along
    # a row, the sky pixels its GGX lobe's directions fall on (the photo's mean sky where they
    # leave the frame), by quadrature here.
    cam = level_camera().with_resolution(W, H)
    fx, fy, cx, cy = cam.intrinsics()
    ys = np.arange(H)[:, None] + 0.5
    down = (ys - cy) / fy
    depth = np.where(down > 0, 1.5 / np.maximum(down, 1e-9), np.inf) * np.ones((1, W))
    sky_rows = np.linspace(0.9, 0.6, H // 2)[:, None, None] * np.array([0.8, 0.9, 1.0])
    rgb = np.empty((H, W, 3))
    rgb[: H // 2] = sky_rows
    rgb[H // 2 :] = np.array([0.2, 0.15, 0.1])
    photo = PhotoScene(rgb.astype(np.float32), depth_m=depth.astype(np.float32), camera=cam, encoding="linear")
    r = Renderer(W, H, backend="cpu")
    dry = r.render(photo, Weather())
    wet = r.render(photo, AFTER_RAIN)
    ground = np.isfinite(depth)
    inner = ground.copy()
    inner[:, [0, -1]] = False
    inner[[H // 2, -1]] = False  # the depth map's neighbours define the normal
    cos = view_cosines(cam)[..., None]
    a = np.array([0.2, 0.15, 0.1])
    darkened = dry.rgb * (wet_albedo(a) / a)
    want = darkened + fresnel(cos) * dry.rgb[::-1]
    puddle = wet.layers["puddle_mask"] == 1.0
    film = inner & ~puddle
    assert 0.05 < puddle[inner].mean() < 0.6 and not puddle[~ground].any()
    np.testing.assert_allclose(wet.rgb[inner & puddle], want[inner & puddle], rtol=1e-3, atol=1e-5)
    assert (wet.layers["wetness"][inner] == 1.0).all() and (wet.layers["wetness"][~ground] == 0.0).all()
    # the film: where each of its lobe's directions falls in the frame
    r = lobe_directions(view_rays(cam)[film]) @ cam.rotation  # camera coordinates
    z = -r[..., 2]
    px = np.floor(cx + fx * r[..., 0] / np.where(z > 0, z, 1.0)).astype(int)
    py = np.floor(cy - fy * r[..., 1] / np.where(z > 0, z, 1.0)).astype(int)
    inside = (z > 1e-6) & (px >= 0) & (py >= 0) & (px < W) & (py < H)
    pxc, pyc = np.clip(px, 0, W - 1), np.clip(py, 0, H - 1)
    on_sky = inside & ~ground[pyc, pxc]
    mean_sky = rgb[: H // 2].reshape(-1, 3).mean(axis=0)
    lobe = np.where(on_sky[..., None], rgb[pyc, pxc], mean_sky).mean(axis=-2)
    seen = (wet.rgb - darkened)[film] / fresnel(cos)[film]
    rows = np.nonzero(film)[0]
    for y in np.unique(rows):
        at = rows == y
        np.testing.assert_allclose(seen[at].mean(axis=0), lobe[at].mean(axis=0), rtol=0.05, err_msg=str(y))
    np.testing.assert_allclose(seen.mean(axis=0), lobe.mean(axis=0), rtol=0.01)


def test_the_8bit_output_draws_the_wet_stage(cpu):
    scene = scenes.street(lamps=True)
    weather = Weather(rain_rate_mm_h=10.0, rain_duration_s=None, sky_illuminance_lux=300.0)
    frame = cpu.render(scene, weather, seed=1)
    image, layers = cpu.render_srgb8(scene, weather, seed=1, layers=("wetness",))
    assert cpu.srgb8_path(scene, weather) == "banded"
    assert np.abs(image.astype(int) - io.to_srgb8(frame.rgb).astype(int)).max() <= 1
    np.testing.assert_array_equal(layers["wetness"], frame.layers["wetness"])


def test_the_8bit_path_follows_the_cores_plan_of_the_film():
    # render_srgb8's path is read from the core's plan (_core.frame_plan), not from the
    # weather's fields: a film the drying has emptied (1 mm of storage at 0.25 mm/h: gone after
    # 4 h) declares no wet stage, and the 8-bit photo takes the fused path again.
    from skyfall import _core

    r = Renderer(32, 24, backend="cpu")
    photo8 = PhotoScene(np.full((24, 32, 3), 120, np.uint8), depth_m=np.full((24, 32), 30.0, np.float32))
    cases = {
        "rain, dry surfaces": (Weather(rain_rate_mm_h=5.0), False),
        "rain, wet surfaces": (Weather(rain_rate_mm_h=5.0, rain_duration_s=None), True),
        "1 h after the rain": (Weather(rain_rate_mm_h=5.0, rain_duration_s=None, dry_s=3600.0), True),
        "4 h 10 min after the rain": (Weather(rain_rate_mm_h=5.0, rain_duration_s=None, dry_s=4 * 3600.0 + 600.0), False),
    }
    for name, (weather, wet) in cases.items():
        plan = {stage: (srgb8, gpu, layers) for stage, srgb8, gpu, layers in _core.frame_plan(r._request(photo8, weather))}
        assert ("wet" in plan) == wet, (name, plan)
        if wet:
            assert plan["wet"] == (False, True, ["wetness", "puddle_mask"]), name
        assert all(srgb8 for srgb8, _, _ in plan.values()) == (not wet), (name, plan)
        assert r.srgb8_path(photo8, weather) == ("banded" if wet else "fused"), name
        # and the bytes are the float frame's either way
        image = r.render_srgb8(photo8, weather, seed=2)
        want = io.to_srgb8(r.render(photo8, weather, seed=2).rgb)
        assert np.abs(image.astype(int) - want.astype(int)).max() <= 1, name


BOX_CASES = {
    "the dusk street, lamps and headlights": (dict(lamps=True, headlights=True), Weather(rain_rate_mm_h=5.0, sky_illuminance_lux=30.0, rain_duration_s=None), 0.1),
    "the street by day after the rain": ({}, AFTER_RAIN, 1.0),
    "under a sun, in a cross wind": ({}, Weather(sky=12, sun_elevation_deg=40.0, sun_azimuth_deg=200.0, rain_rate_mm_h=5.0, rain_duration_s=600.0, wind_m_s=(3.0, 0.0, 0.0)), 0.2),
}


@pytest.mark.parametrize("case", list(BOX_CASES))
def test_the_gpu_draws_wet_box_scenes_as_the_cpu_does(case):
    # The GPU's wet stage of a box scene (the scene pass's wet_main, then its main casting the
    # mirror rays, then the grain's row averaging) against the CPU's, on the frame's codes at
    # the demo's exposure and on both layers.
    kwargs, weather, exposure = BOX_CASES[case]
    scene = scenes.street(**kwargs)
    a = Renderer(W, H, backend="cpu").render(scene, weather, seed=1)
    b = Renderer(W, H, backend="gpu").render(scene, weather, seed=1)
    diff = np.abs(io.to_srgb8(a.rgb * exposure).astype(int) - io.to_srgb8(b.rgb * exposure).astype(int))
    assert diff.max() <= 2 and np.mean(diff > 1) < 0.001, (diff.max(), np.mean(diff > 1))
    np.testing.assert_allclose(b.layers["wetness"], a.layers["wetness"], atol=1e-6)
    assert np.mean(a.layers["puddle_mask"] != b.layers["puddle_mask"]) < 0.002
    assert a.layers["wetness"].max() == 1.0 and a.layers["puddle_mask"].max() == 1.0
    # and the wet frame is not the dry one
    dry = Renderer(W, H, backend="gpu").render(scene, replace(weather, rain_duration_s=0.0), seed=1)
    assert np.mean(np.abs(dry.rgb - b.rgb) > 1e-3) > 0.05


def test_auto_draws_a_wet_street_on_the_gpu():
    # backend="auto" on a GPU (lavapipe stands in for the hardware GPU "auto" would take) draws
    # a wet street there now: the GPU's bits, which are not the CPU's.
    gpu = Renderer(W, H, backend="gpu")
    auto = Renderer(W, H, backend="auto")
    auto._device, auto.backend = gpu._device, "gpu"
    wet = Weather(rain_rate_mm_h=5.0, rain_duration_s=None)
    on_auto = auto.render(scenes.street(), wet, seed=1).rgb
    np.testing.assert_array_equal(on_auto, gpu.render(scenes.street(), wet, seed=1).rgb)
    assert not np.array_equal(on_auto, Renderer(W, H, backend="cpu").render(scenes.street(), wet, seed=1).rgb)


@pytest.mark.parametrize("weather", [AFTER_RAIN, Weather(rain_rate_mm_h=5.0, rain_duration_s=60.0, wind_m_s=(3.0, 0.0, 0.0))], ids=["after the rain", "a minute in a cross wind"])
def test_the_gpu_draws_wet_photos_as_the_cpu_does(weather):
    # The street kept as a photo with its depth and its boxes as occluders: the GPU's wet pass
    # (wet_photo.wgsl: normals from the depth map, the march, the occluders' shelter) against
    # the CPU's stage, within one code and the same wetness to f32 rounding.
    from skyfall._demo.photo import street_photo

    photo = street_photo(W)
    h = photo.shape[0]
    a = Renderer(W, h, backend="cpu").render(photo, weather, seed=1)
    b = Renderer(W, h, backend="gpu").render(photo, weather, seed=1)
    diff = np.abs(io.to_srgb8(a.rgb).astype(int) - io.to_srgb8(b.rgb).astype(int))
    assert diff.max() <= 1 and np.mean(diff > 0) < 0.01, (diff.max(), np.mean(diff > 0))
    np.testing.assert_allclose(b.layers["wetness"], a.layers["wetness"], atol=1e-6)
    assert 0.05 < a.layers["wetness"].mean() < 0.5
    # the puddles (the relief's noise, hashed alike on both) agree but where f32 rounding moves
    # a point across a puddle's edge
    assert np.mean(a.layers["puddle_mask"] != b.layers["puddle_mask"]) < 0.002
    if weather.rain_duration_s is None:
        assert a.layers["puddle_mask"].mean() > 0.02


@pytest.mark.parametrize("value", [-1.0, 2e7, float("nan")])
def test_bad_durations_are_refused_by_name(value):
    with pytest.raises(ValueError, match="rain_duration_s"):
        Weather(rain_rate_mm_h=1.0, rain_duration_s=value)
    with pytest.raises(ValueError, match="dry_s"):
        Weather(rain_rate_mm_h=1.0, dry_s=value)
