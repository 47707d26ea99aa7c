"""Lamps and headlights on box scenes, on both backends: lit surfaces against the analytic
illuminance, shadows, emitters and glows (depth-tested), culling, and lights that are off."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from skyfall import Camera, PointLight, Renderer, SpotLight, Weather, scenes

W, H = 160, 120
E = 30.0  # lux of sky: dusk


@pytest.fixture(scope="module", params=["cpu", "gpu"])
def renderer(request: pytest.FixtureRequest) -> Renderer:
    return Renderer(W, H, backend=request.param)


def ground_points(cam: Camera, depth: np.ndarray) -> np.ndarray:
    """World point of every pixel (H, W, 3) from its depth along the optical axis (sky: 0)."""
    depth = np.where(np.isfinite(depth), depth, 0.0)
    fx, fy, cx, cy = cam.with_resolution(W, H).intrinsics()
    ys, xs = np.mgrid[0:H, 0:W]
    pc = np.stack([(xs + 0.5 - cx) / fx * depth, -(ys + 0.5 - cy) / fy * depth, -depth], axis=-1)
    return pc @ cam.rotation.T + cam.position_m


def test_a_lamp_over_open_ground_gives_the_analytic_illuminance(renderer):
    # albedo 0.2 ground, 2000 cd 5 m up: radiance 0.2 (1 + I h / r^3 / E) at every ground pixel
    # (the open sky's 1 from the map, as the unlit frame has it).
    cam = Camera((0.0, 1.6, 0.0), pitch_deg=-25.0, vertical_fov_deg=70.0)
    lamp = PointLight((1.0, 5.0, -8.0), 2000.0, color=(1.0, 0.8, 0.5))
    scene = scenes.boxes([], ground=True, ground_albedo=0.2, camera=cam, lights=(lamp,))
    clear = Weather(sky_illuminance_lux=E)
    lit = renderer.render(scene, clear)
    sky_only = renderer.render(replace(scene, lights=()), clear)
    ground = np.isfinite(lit.depth_m)
    p = ground_points(cam, lit.depth_m)[ground]
    r = np.linalg.norm(np.asarray(lamp.position_m) - p, axis=1)
    e = lamp.intensity_cd * (lamp.position_m[1] - p[:, 1]) / r**3
    want = sky_only.rgb[ground] + 0.2 * np.outer(e / E, lamp.color)
    np.testing.assert_allclose(lit.rgb[ground], want, rtol=2e-5)
    assert ground.mean() > 0.5 and (e / E).max() > 1.0  # a real pool, in most of the frame


def test_a_spot_lights_its_cone_only(renderer):
    cam = Camera((0.0, 1.6, 0.0), pitch_deg=-25.0, vertical_fov_deg=70.0)
    spot = SpotLight((0.0, 3.0, -6.0), (0.0, -1.0, 0.0), 10000.0, cone_deg=20.0, inner_cone_deg=15.0)
    scene = scenes.boxes([], ground=True, ground_albedo=0.2, camera=cam, lights=(spot,))
    lit = renderer.render(scene, Weather(sky_illuminance_lux=E))
    dark = renderer.render(replace(scene, lights=()), Weather(sky_illuminance_lux=E))
    ground = np.isfinite(lit.depth_m)
    p = ground_points(cam, lit.depth_m)
    off_axis = np.degrees(np.arctan2(np.hypot(p[..., 0], p[..., 2] + 6.0), 3.0))
    inner, outer = ground & (off_axis < 14.0), ground & (off_axis > 21.0)
    e = 10000.0 * 3.0 / np.sum((p[inner] - np.asarray(spot.position_m)) ** 2, axis=1) ** 1.5
    np.testing.assert_allclose(lit.rgb[inner][:, 1], dark.rgb[inner][:, 1] + 0.2 * e / E, rtol=2e-5)
    np.testing.assert_array_equal(lit.rgb[outer], dark.rgb[outer])
    assert inner.sum() > 50 and outer.sum() > 100


def test_a_box_shadows_the_ground_behind_it(renderer):
    # a wall between a low lamp and the ground beyond it: that ground gets the sky's light only
    cam = Camera((0.0, 6.0, 4.0), pitch_deg=-45.0, vertical_fov_deg=70.0)
    lamp = PointLight((0.0, 1.0, -4.0), 2000.0)
    wall = {"min": (-20.0, 0.0, -2.5), "max": (20.0, 2.0, -2.0), "albedo": 0.5}
    scene = scenes.boxes([wall], ground=True, ground_albedo=0.2, camera=cam, lights=(lamp,))
    lit = renderer.render(scene, Weather(sky_illuminance_lux=E))
    dark = renderer.render(replace(scene, lights=()), Weather(sky_illuminance_lux=E))
    p = ground_points(cam, lit.depth_m)
    ground = np.isfinite(lit.depth_m) & (np.abs(p[..., 1]) < 1e-3)
    # the lamp at y = 1 behind a 2 m wall at z = -2: the ground at z > -2 (on the camera's side)
    # is in its shadow wholly beyond the wall's shadow line
    behind = ground & (p[..., 2] > -1.5)
    front = ground & (p[..., 2] < -6.0) & (p[..., 2] > -9.0) & (np.abs(p[..., 0]) < 3.0)  # seen over the wall, near the lamp
    np.testing.assert_array_equal(lit.rgb[behind], dark.rgb[behind])
    assert (lit.rgb[front] > dark.rgb[front] + 0.05).all()
    assert behind.sum() > 200 and front.sum() > 50


def test_lamps_show_with_glows_unless_hidden(renderer):
    # A lamp 30 m ahead over open ground in mist: a bright disc at its image and a glow around;
    # behind a wall: neither (the wall's pixels as without the lamp).
    cam = Camera((0.0, 5.0, 0.0), vertical_fov_deg=40.0)
    lamp = PointLight((0.0, 5.0, -30.0), 2000.0)
    mist = Weather(sky_illuminance_lux=E, visibility_m=300.0)
    scene = scenes.boxes([], ground=True, ground_albedo=0.1, camera=cam, lights=(lamp,))
    seen = renderer.render(scene, mist).rgb[..., 1]
    none = renderer.render(replace(scene, lights=()), mist).rgb[..., 1]
    uv, _ = cam.with_resolution(W, H).project([lamp.position_m])
    x, y = int(uv[0, 0]), int(uv[0, 1])
    assert seen[y, x] > 100 * none[y, x]  # the disc
    ring = seen[y, x + 10] - none[y, x + 10]
    assert ring > 0.01 and seen[y, x + 30] - none[y, x + 30] < ring  # the glow falls off
    wall = {"min": (-10.0, 0.0, -12.0), "max": (10.0, 12.0, -11.0), "albedo": 0.5}
    hidden = replace(scene, boxes=scenes.boxes([wall]).boxes)
    hid = renderer.render(hidden, mist).rgb
    hid_none = renderer.render(replace(hidden, lights=()), mist).rgb
    # the wall faces the camera, away from the lamp: no light on it, no glow through it
    np.testing.assert_array_equal(hid, hid_none)


def test_lights_that_are_off_change_nothing_and_culling_still_counts(renderer):
    dusk = Weather(rain_rate_mm_h=20.0, sky_illuminance_lux=E)
    street = scenes.street()
    off = replace(street, lights=(PointLight((0.0, 5.0, -10.0), 0.0),))
    base = renderer.render(street, dusk, seed=3)
    assert renderer.render(off, dusk, seed=3).rgb.tobytes() == base.rgb.tobytes()
    lit_street = scenes.street(lamps=True, headlights=True)
    lit = renderer.render(lit_street, dusk, seed=3)
    # near the camera the lamps and headlights light every drop past the sky's 1.0: cull at 3
    culled = renderer.render(lit_street, dusk, seed=3, cull_threshold=3.0)
    assert culled.stats["rain_culled"] > 0 and culled.stats["rain_streaks"] > 0
    assert culled.stats["rain_culled"] + culled.stats["rain_streaks"] == lit.stats["rain_streaks"]
    # the lights light the street whether or not the faint drops are culled
    assert np.median(culled.rgb) > 2 * np.median(base.rgb)
    no_rain = renderer.render(lit_street, replace(dusk, rain_streaks=False), seed=3)
    assert np.abs(culled.rgb - lit.rgb).mean() < 0.5 * np.abs(lit.rgb - no_rain.rgb).mean()


def test_both_backends_light_the_dusk_street_alike():
    dusk = Weather(rain_rate_mm_h=20.0, sky_illuminance_lux=E)
    street = scenes.street(lamps=True, headlights=True)
    cpu = Renderer(W, H, backend="cpu").render(street, dusk, seed=1).rgb
    gpu = Renderer(W, H, backend="gpu").render(street, dusk, seed=1).rgb
    rel = np.abs(cpu - gpu) / np.maximum(np.abs(cpu), 1.0)
    assert (rel > 1e-3).mean() < 0.005 and np.median(rel) < 1e-6
