"""Clouds in the sky's light: the ambient-light map and the haze under a sky with clouds in it.

A rendered scene's ambient-light map integrates the sky with its clouds: L' = L_received
+ tau (S - L_emitted (1 - T)), T and S the clouds' transmittance and light along each direction
(``_core.CloudDome``, drawn by the frames' own cloud pass). References: that radiance integrated
here over the hemisphere by a midpoint rule in numpy, with the haze's path to the cloud base on
the Earth's sphere written out again (an independent quadrature and code path from the core's
cumulative tables); for the haze, Yamamoto & Tadamura's airlight, proportional to the sky
illuminance at the viewpoint, read off a black ground where a pixel is the airlight alone.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from skyfall import Camera, Renderer, Weather, _core, clouds, sky
from skyfall.scenes import BoxScene

LUMA = np.array([0.2126, 0.7152, 0.0722])
EARTH_RADIUS_M = 6.371e6
DECK = Weather(sky=12, sun_elevation_deg=50.0, sun_azimuth_deg=185.0, clouds="stratocumulus", visibility_m=20_000.0)
"""A sunny sky over the stratocumulus preset's deck (broken, 79 % covered overhead)."""


def _hemisphere(n_el: int = 180, n_az: int = 360) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Midpoint directions over the upper hemisphere (N, 3), their elevations and d(omega)."""
    el = (np.arange(n_el) + 0.5) / n_el * (math.pi / 2)
    az = (np.arange(n_az) + 0.5) / n_az * (2 * math.pi)
    e, a = np.meshgrid(el, az, indexing="ij")
    dirs = np.stack([np.cos(e) * np.sin(a), np.sin(e), -np.cos(e) * np.cos(a)], axis=-1).reshape(-1, 3)
    domega = np.cos(e).reshape(-1) * (math.pi / 2 / n_el) * (2 * math.pi / n_az)
    return dirs, e.reshape(-1), domega


def _to_ceiling_transmittance(w: Weather, sin_el: np.ndarray) -> np.ndarray:
    """e^(-sigma d), d the path from the ground to the cloud base along the Earth's sphere."""
    r, h = EARTH_RADIUS_M, w.cloud_base_height_m
    d = np.sqrt((r + h) ** 2 - (r * np.sqrt(1 - sin_el**2)) ** 2) - r * sin_el
    return np.exp(-w.extinction_per_m * d)


def _dome(w: Weather, eye: tuple[float, float, float]) -> _core.CloudDome:
    field = clouds.frame_field(w.clouds, w.sun_direction)
    return _core.CloudDome(field, w.sky_model(), eye, w.sun_relative)


def _open_map(w: Weather, dome: _core.CloudDome | None, samples: int = sky.MAP_SAMPLES) -> _core.AmbientLightMap:
    none = np.zeros((0, 9), np.float32)
    return w.sky_model().ambient_map(none, bounds_min_m=[0, 0, 0], bounds_max_m=[0, 0, 0], spacing_m=1.0, samples=samples, dome=dome)


def test_the_maps_light_is_the_hemispheres_integral_of_the_sky_with_its_clouds():
    dome = _dome(DECK, (0.0, 0.0, 0.0))
    model = DECK.sky_model()
    dirs, el, domega = _hemisphere()
    t, s = dome.sample(dirs)
    d32 = dirs.astype(np.float32)
    received = model.rgb_relative(d32, received=True)
    emitted = model.rgb_relative(d32, received=False)
    tau = _to_ceiling_transmittance(DECK, np.sin(el))[:, None]
    rgb = received + tau * (s - emitted * (1.0 - t[:, None]))
    lum = rgb @ LUMA
    normals = np.array([[0, 1, 0], [1, 0, 0], [-1, 0, 0], [0, 0, 1], [0, 0, -1]], dtype=np.float64)
    want = np.array([np.sum(lum * np.clip(dirs @ n, 0, None) * domega) for n in normals]) / math.pi
    clouded = _open_map(DECK, dome, 256)
    got = clouded.values.reshape(-1)
    np.testing.assert_allclose(got, want, rtol=2e-3)
    # The deck changes the light a lot (it is not the clear sky's within the tolerance) ...
    clear = _open_map(DECK, None).values.reshape(-1)
    assert got[0] > 1.5 * clear[0], (got, clear)
    # ... and its colour: the clouds' near-white light, not the clear sky's blue.
    up = np.sum(rgb * np.sin(el)[:, None] * domega[:, None], axis=0)
    want_colour = up / (up @ LUMA)
    np.testing.assert_allclose(clouded.light_colour, want_colour, atol=5e-3)
    assert clouded.light_colour[2] / clouded.light_colour[0] < 0.9
    assert model.colours[1][2] / model.colours[1][0] > 1.5
    assert _open_map(DECK, None).light_colour is None


def test_a_sky_without_clouds_in_it_is_the_sky():
    # Nothing along any direction (T = 1, S = 0): a dome of a cloud far below the horizon's
    # reach is the clear sky's map, and the rendered clear frame keeps its map's colour.
    far = clouds.Cloud(
        positions_m=np.array([[0.0, -5000.0, 0.0]]),
        radii_m=np.array([100.0]),
        optical_depths=np.array([5.0]),
        albedos=np.array([1.0]),
    )
    w = Weather(sky=12, sun_elevation_deg=40.0, sun_azimuth_deg=100.0, visibility_m=20_000.0)
    field = clouds.frame_field(far, w.sun_direction)
    dome = _core.CloudDome(field, w.sky_model(), (0.0, 0.0, 0.0), w.sun_relative)
    dirs, _, _ = _hemisphere(12, 24)
    t, s = dome.sample(dirs)
    assert np.all(t == 1.0) and np.all(s == 0.0)
    clouded = _open_map(w, dome, 256).values.reshape(-1)
    # the clear map's table is along every azimuth as well: the same integral, the same sums
    clear = w.sky_model().ambient_map(
        np.zeros((0, 9), np.float32), bounds_min_m=[0, 0, 0], bounds_max_m=[0, 0, 0], spacing_m=1.0, samples=256
    )
    np.testing.assert_array_equal(clouded, clear.values.reshape(-1))


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_the_haze_takes_the_light_of_the_sky_with_its_clouds(backend):
    # A black ground in hazy air: each ground pixel is the airlight alone, A (1 - t). Yamamoto
    # & Tadamura's airlight is proportional to the sky's light at the eye, so under the deck it
    # is the clear sky's times the clouded map's light over the clear map's there.
    # (a haze ceiling at 300 m, so the deck above shows through the haze: in thicker haze the
    # sky is the airlight alone, clouds or not)
    haze = {"sky": 12, "sun_elevation_deg": 50.0, "sun_azimuth_deg": 185.0, "visibility_m": 1000.0, "cloud_base_m": 300.0}
    hazy = Weather(**haze)
    decked = Weather(**haze, clouds="stratocumulus")
    cam = Camera((0.0, 1.6, 0.0), pitch_deg=-6.0, vertical_fov_deg=20.0, width=48, height=32)
    ground = BoxScene(boxes=np.zeros((0, 9), np.float32), ground=True, ground_albedo=(0.0, 0.0, 0.0), camera=cam)
    r = Renderer(48, 32, backend=backend)
    airlight = []
    for w in (hazy, decked):
        f = r.render(ground, w, layers=("transmittance",))
        t = f.layers["transmittance"]
        low = t < 0.9
        assert low.sum() > 200
        # (the green channel: the transmittance layer's; the clear air's red and blue see their
        # own extinction, tests/test_sky_colour.py)
        a = f.rgb[low][:, 1] / (1.0 - t[low])
        assert np.ptp(a) < 1e-3 * a.max()
        airlight.append(a.mean())
    # The frame's dome is seen from the ground under the camera, on 8 m steps.
    dome = _dome(decked, (0.0, 0.0, 0.0))
    ratio = _open_map(decked, dome).sample(np.zeros((1, 3), np.float32))[0, 0] / _open_map(hazy, None).sample(
        np.zeros((1, 3), np.float32)
    )[0, 0]
    assert ratio > 1.08, ratio
    np.testing.assert_allclose(airlight[1], airlight[0] * ratio, rtol=2e-3)


def test_the_sky_light_moves_its_clouds_in_whole_steps_of_drift():
    # In wind the sky light's clouds are the frame's clouds with the drift rounded to 25 m per
    # axis (a function of the time alone, so any frame gets the same map in any process).
    cloud = clouds.particles("cumulus", n_particles=300, extent_m=500.0, altitude_m=800.0, seed=2)
    sun = DECK.sun_direction
    wind = (10.0, 0.0, -4.0)
    assert clouds.sky_field(cloud, wind, 1.2, sun) is clouds.frame_field(cloud, sun)  # (12, 0, -4.8) m: no step yet
    stepped = clouds.sky_field(cloud, wind, 1.3, sun)  # (13, 0, -5.2): 25 m east, none south
    moved = clouds.drifted(cloud, (clouds.SKY_DRIFT_STEP_M / 1.3, 0.0, 0.0), 1.3)
    np.testing.assert_allclose(moved.positions_m - cloud.positions_m, np.tile([25.0, 0.0, 0.0], (cloud.n_particles, 1)))
    points = np.array([[100.0, 0.0, -50.0], [-40.0, 0.0, 30.0], [10.0, 900.0, 0.0]])
    np.testing.assert_array_equal(stepped.sun_share(points), clouds.frame_field(moved, sun).sun_share(points))
    # Frames within one step share the sky light's field (and so its dome and map).
    assert clouds.sky_field(cloud, wind, 1.3, sun) is stepped
    assert clouds.sky_field(cloud, wind, 1.4, sun) is stepped  # (14, 0, -5.6)
    with pytest.raises(ValueError, match="weather.clouds is None"):
        clouds.sky_dome(Weather())


def test_a_photo_keeps_its_own_light_under_clouds():
    # Clouds over a photo draw in its sky, but the photo's light is its own: the map its frame
    # is lit by (the drops', the haze's) has no clouds in its sky.
    from skyfall import PhotoScene

    image = np.full((20, 32, 3), 0.4, np.float32)
    depth = np.full((20, 32), 15.0, np.float32)
    depth[:8] = np.inf
    photo = PhotoScene(image, depth, camera=Camera(width=32, height=20), encoding="linear")
    r = Renderer(32, 20, backend="cpu")
    with_clouds = r._request(photo, DECK)
    without = r._request(photo, Weather(sky=12, sun_elevation_deg=50.0, sun_azimuth_deg=185.0, visibility_m=20_000.0))
    assert "clouds" in with_clouds and with_clouds["ambient"].light_colour is None
    np.testing.assert_array_equal(with_clouds["ambient"].values, without["ambient"].values)
