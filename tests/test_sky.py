"""Sky light (Yamamoto & Tadamura): CIE skies against an independent implementation of the published
formula and scipy integrals, illuminance with occlusion against high-resolution numerical
integrals, the ambient map against direct evaluation, and its use in frames on both backends."""

from __future__ import annotations

import csv

import colour
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from skyfall import Camera, PhotoScene, Renderer, Weather, rain, scenes, sky
from skyfall._reference import canyon_illuminance, path_to_cloud_base_m
from conftest import DATA

E = 10000.0


def cie_table() -> dict[int, tuple[float, float, float, float, float]]:
    """a-e per CIE type from tests/data (CIE S 011/E:2003, source line in the file)."""
    lines = [ln for ln in (DATA / "cie_general_sky_15_types.csv").read_text().splitlines() if not ln.startswith("#")]
    rows = list(csv.DictReader(lines))
    return {int(r["type"]): tuple(float(r[k]) for k in "abcde") for r in rows}  # type: ignore[misc]


def cie_relative(el_deg: np.ndarray, az_deg: np.ndarray, t: int, sun_el: float, sun_az: float) -> np.ndarray:
    """L/Lz of CIE type t written from the standard, independently of skyfall."""
    a, b, c, d, e = cie_table()[t]
    z = np.radians(90.0 - np.asarray(el_deg))
    zs = np.radians(90.0 - sun_el)
    daz = np.radians(np.asarray(az_deg) - sun_az)
    chi = np.arccos(np.clip(np.cos(zs) * np.cos(z) + np.sin(zs) * np.sin(z) * np.cos(daz), -1, 1))
    with np.errstate(divide="ignore", over="ignore"):
        phi = np.where(np.cos(z) > 1e-12, 1 + a * np.exp(b / np.maximum(np.cos(z), 1e-12)), 1.0)
    f = lambda x: 1 + c * (np.exp(d * x) - np.exp(d * np.pi / 2)) + e * np.cos(x) ** 2  # noqa: E731
    return phi * f(chi) / ((1 + a * np.exp(b)) * f(zs))


def hemisphere_integral(fn, n_el: int = 400, n_az: int = 800) -> float:
    """Integral of fn(el_deg, az_deg) cos(theta) d(omega) by a fine midpoint grid in (el, az)."""
    el = (np.arange(n_el) + 0.5) / n_el * 90.0
    az = (np.arange(n_az) + 0.5) / n_az * 360.0
    ee, aa = np.meshgrid(el, az, indexing="ij")
    w = np.sin(np.radians(ee)) * np.cos(np.radians(ee)) * (np.pi / 2 / n_el) * (2 * np.pi / n_az)
    return float(np.sum(fn(ee, aa) * w))


# ---- luminance --------------------------------------------------------------------------


def test_overcast_luminance_is_the_seed_formula():
    el = np.array([0.0, 10.0, 45.0, 90.0])
    lz = 9 * E / (7 * np.pi)
    np.testing.assert_allclose(sky.luminance(el, 0.0), lz * (1 + 2 * np.sin(np.radians(el))) / 3, rtol=1e-6)
    assert sky.luminance(-5.0, 0.0) == 0.0
    # CIE type 1 is the general-sky version of the overcast sky: within 5 % of Moon-Spencer
    # from 30 deg up (it is darker near the horizon: -20 % at 10 deg).
    el = np.linspace(30, 90, 7)
    np.testing.assert_allclose(sky.luminance(el, 0.0, sky=1), sky.luminance(el, 0.0), rtol=0.05)


@pytest.mark.parametrize("t", range(1, 16))
def test_cie_types_follow_the_standard_and_give_e(t):
    sun = (35.0, 140.0)
    el = np.array([5.0, 20.0, 40.0, 60.0, 85.0])
    az = np.array([0.0, 100.0, 140.0, 200.0, 300.0])
    got = sky.luminance(el, az, sky=t, sun_elevation_deg=sun[0], sun_azimuth_deg=sun[1])
    want_shape = cie_relative(el, az, t, *sun)
    # The shape is the standard's (independent numpy implementation from the CSV).
    np.testing.assert_allclose(got / got[-1], want_shape / want_shape[-1], rtol=2e-5)
    # Normalised: the open sky's horizontal illuminance (a fine numerical integral here) is E.
    total = hemisphere_integral(lambda e_, a_: sky.luminance(e_, a_, sky=t, sun_elevation_deg=sun[0], sun_azimuth_deg=sun[1]))
    assert total == pytest.approx(E, rel=1e-3)
    # And skyfall's own sampler agrees within 0.1 %.
    e_h = sky.horizontal_illuminance([0, 0, 0], sky=t, sun_elevation_deg=sun[0], sun_azimuth_deg=sun[1])
    assert e_h[0] == pytest.approx(E, rel=1e-3)


def test_sky_inputs_are_checked():
    with pytest.raises(ValueError, match="sun_elevation_deg"):
        sky.luminance(30.0, 0.0, sky=12)
    with pytest.raises(ValueError, match="1-15"):
        Weather(sky=16)
    with pytest.raises(ValueError, match="overcast"):
        Weather(sky="clear")
    with pytest.raises(TypeError):
        Weather(sky=2.5)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="both"):
        Weather(sun_elevation_deg=10.0)
    with pytest.raises(ValueError, match="sun_elevation_deg"):
        Weather(sky=12, sun_elevation_deg=-3.0, sun_azimuth_deg=0.0)
    with pytest.raises(ValueError, match="not both"):
        sky.luminance(30.0, 0.0, sky=3, weather=Weather())
    with pytest.raises(ValueError, match="elevation_deg"):
        sky.luminance(95.0, 0.0)
    with pytest.raises(ValueError, match="samples"):
        sky.horizontal_illuminance([0, 0, 0], samples=2)
    with pytest.raises(ValueError, match="samples"):
        sky.horizontal_illuminance([0, 0, 0], samples=100_000)
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        sky.horizontal_illuminance([[0, 0]])
    with pytest.raises(ValueError, match="spacing_m"):
        sky.ambient_light_map(scenes.street(), spacing_m=0.0)
    with pytest.raises(ValueError, match="nodes"):
        sky.ambient_light_map(scenes.street(), spacing_m=0.05)


def test_rain_flattens_the_sky_towards_its_airlight_but_keeps_e():
    wet = Weather(rain_rate_mm_h=50.0)
    assert wet.cloud_base_height_m == pytest.approx(1500 - 250 * np.log1p(50.0))
    el = np.array([0.0, 5.0, 30.0, 90.0])
    clear = sky.luminance(el, 0.0)
    seen = sky.luminance(el, 0.0, weather=wet)
    # L = s (l tau + l_h (1 - tau)), tau = exp(-sigma d): the cloud base's overcast shape
    # l = (1 + 2 sin el) / 3 attenuated along the path d to a base H up on the Earth's sphere,
    # plus the in-scattered light saturating at its horizon luminance l_h = 1/3, as
    # documented; s keeps E.
    sigma, h = wet.extinction_per_m, wet.cloud_base_height_m
    tau = np.exp(-sigma * path_to_cloud_base_m(np.sin(np.radians(el)), h))
    shape = (1 + 2 * np.sin(np.radians(el))) / 3
    model = shape * tau + (1 - tau) / 3
    np.testing.assert_allclose(seen / seen[-1], model / model[-1], rtol=1e-5)
    assert tau[0] < 1e-100  # 91 km of 50 mm/h rain along the horizon
    assert seen[0] == pytest.approx(wet.airlight_relative * wet.sky_illuminance_lux / np.pi, rel=1e-6)
    assert seen[1] > clear[1] and seen[-1] < clear[-1]  # the low sky brightens, the zenith dims
    assert sky.horizontal_illuminance([0, 0, 0], weather=wet)[0] == pytest.approx(wet.sky_illuminance_lux, rel=1e-3)


# ---- illuminance with occlusion -------------------------------------------------------


def canyon(height: float, width: float) -> scenes.BoxScene:
    """An (effectively) infinitely long canyon along Z: two 2 km walls (the reference's are infinite)."""
    return scenes.boxes(
        [
            {"min": (-width / 2 - 10, 0, -1000), "max": (-width / 2, height, 1000)},
            {"min": (width / 2, 0, -1000), "max": (width / 2 + 10, height, 1000)},
        ]
    )


@pytest.mark.parametrize(("x", "height", "width"), [(0.0, 10.0, 10.0), (0.0, 20.0, 8.0), (3.999, 10.0, 8.0)])
def test_canyon_illuminance_matches_a_numerical_integral(x, height, width):
    ref = canyon_illuminance(x, height, width) * E
    got = sky.horizontal_illuminance([x, 0.0, 0.0], canyon(height, width))[0]
    assert got == pytest.approx(ref, rel=1e-3)  # the issue asks for 1 %
    assert got < 0.8 * E


def test_rain_attenuation_enters_the_occluded_integral():
    wet = Weather(rain_rate_mm_h=30.0)
    ref = canyon_illuminance(0.0, 12.0, 10.0, extinction_per_m=wet.extinction_per_m, cloud_base_m=wet.cloud_base_height_m)
    dry = canyon_illuminance(0.0, 12.0, 10.0)
    got = sky.horizontal_illuminance([0.0, 0.0, 0.0], canyon(12.0, 10.0), weather=wet)[0]
    assert got / E == pytest.approx(ref, rel=1e-3)
    # E is held fixed and the rain scatters the cloud base's light into every direction: the
    # sky flattens, and the canyon floor, which sees only the high sky, gets a smaller share
    # of E (0.438 dry, 0.408 at 30 mm/h here).
    assert ref < dry - 0.02


def test_a_canyon_floor_darkens_in_rain_and_an_open_wall_tends_to_the_uniform_sky():
    # H/W = 2, the case: floor 0.28 E dry; it rose to 0.38 at 10 mm/h and 0.54 at
    # 1 km visibility under the attenuation-only sky. Now the rain flattens the sky towards
    # its airlight: past a bump of at most 1.6 % in drizzle (sigma H ~ 0.3: to first order the
    # in-scattered light at the horizon luminance takes the same amount off every direction,
    # a little more off the low sky than it adds back) the floor's share falls monotonically
    # towards the uniform sky's. An open wall's (after a dip under 1 %) rises to the uniform sky's E/2.
    street = canyon(20.0, 10.0)
    weathers = [Weather(rain_rate_mm_h=r) for r in (0.0, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0)] + [Weather(visibility_m=v) for v in (1000.0, 50.0)]
    depth = [w.extinction_per_m * w.cloud_base_height_m for w in weathers]
    assert depth == sorted(depth)
    floors = [sky.horizontal_illuminance([0.0, 0.0, 0.0], street, weather=w)[0] / w.sky_illuminance_lux for w in weathers]
    walls = [sky.horizontal_illuminance([0.0, 1.0, 0.0], weather=w, normal="+x")[0] / w.sky_illuminance_lux for w in weathers]
    for w, f in zip(weathers[:5], floors):
        ref = canyon_illuminance(0.0, 20.0, 10.0, extinction_per_m=w.extinction_per_m, cloud_base_m=w.cloud_base_height_m)
        assert f == pytest.approx(ref, rel=1e-3)
    assert max(floors) <= floors[0] * 1.016, floors
    assert all(f < floors[0] for f in floors[4:]), floors  # from 10 mm/h on, below the dry floor
    assert all(b <= a for a, b in zip(floors[2:], floors[3:])), floors
    assert floors[-1] < 0.25
    assert walls[0] == pytest.approx(3 / 14 + 4 / (7 * np.pi), rel=1e-3)  # the clear overcast sky's
    assert min(walls) >= walls[0] * 0.99 and all(b >= a for a, b in zip(walls[2:], walls[3:])), walls
    assert walls[-1] == pytest.approx(0.5, rel=1e-3)


def test_points_inside_boxes_see_no_sky_and_roofs_see_all():
    s = scenes.boxes([{"min": (-2, 0, -2), "max": (2, 5, 2)}])
    e = sky.horizontal_illuminance([[0, 2, 0], [0, 5, 0], [0, 9, 0]], s)
    assert e[0] == 0.0
    np.testing.assert_allclose(e[1:], E, rtol=1e-3)
    # A wall facing +X at its foot sees the open vertical sky: E (3/14 + 4/(7 pi)).
    v = sky.horizontal_illuminance([2.0, 0.0, 0.0], s, normal="+x")[0]
    assert v == pytest.approx(E * (3 / 14 + 4 / (7 * np.pi)), rel=1e-3)


# ---- the ambient map ------------------------------------------------------------------


@pytest.fixture(scope="module")
def street_map() -> sky.AmbientLightMap:
    return sky.ambient_light_map(scenes.street(length_m=40.0), spacing_m=2.0, samples=256)


def test_map_nodes_equal_direct_evaluation(street_map):
    m = street_map
    nx, ny, nz, _ = m.grid.shape
    rng = np.random.default_rng(0)
    idx = rng.integers(0, [nx, ny, nz], size=(40, 3))
    pts = m.origin_m + m.spacing_m * idx
    boxes = scenes.street(length_m=40.0).boxes
    inside = np.array(
        [np.any((p[0] > boxes[:, 0]) & (p[0] < boxes[:, 3]) & (p[2] > boxes[:, 2]) & (p[2] < boxes[:, 5]) & (p[1] >= boxes[:, 1]) & (p[1] < boxes[:, 4])) for p in pts]
    )
    direct = sky.horizontal_illuminance(pts[~inside], scenes.street(length_m=40.0), samples=256)
    node_vals = m.grid[idx[~inside, 0], idx[~inside, 1], idx[~inside, 2], 0]
    np.testing.assert_allclose(node_vals, direct, rtol=1e-5, atol=1e-3)
    np.testing.assert_allclose(m.sample(pts[~inside]), direct, rtol=1e-5, atol=1e-3)


def test_map_sampling_is_trilinear(street_map):
    m = street_map
    g = m.grid[..., 0].astype(np.float64)
    rng = np.random.default_rng(1)
    base = rng.integers(0, np.array(g.shape) - 1, size=(50, 3))
    base[:10] = [[int((7.0 - m.origin_m[0]) / m.spacing_m) - 1, 1, k] for k in range(10, 20)]  # at the right-hand wall
    f = rng.uniform(0, 1, size=(50, 3))
    # Trilinear over the cell's open corners, weights renormalised (all corners if none is open).
    num, den, full = np.zeros(50), np.zeros(50), np.zeros(50)
    for corner in range(8):
        off = np.array([(corner >> k) & 1 for k in range(3)])
        w = np.prod(np.where(off == 1, f, 1 - f), axis=1)
        ijk = base + off
        v = g[ijk[:, 0], ijk[:, 1], ijk[:, 2]]
        is_open = ~m.solid[ijk[:, 0], ijk[:, 1], ijk[:, 2]]
        num += w * v * is_open
        den += w * is_open
        full += w * v
    want = np.where(den > 0, num / np.where(den > 0, den, 1), full)
    assert np.any((den > 0) & (den < 1))  # some cells straddle a wall
    got = m.sample(m.origin_m + m.spacing_m * (base + f))
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-2)
    # Outside the grid: the nearest boundary value.
    far = m.sample(m.origin_m - 100.0)
    assert far[0] == pytest.approx(g[0, 0, 0], rel=1e-6)


def test_map_is_cached_and_open_scenes_are_uniform():
    a = sky.ambient_light_map(scenes.street(length_m=40.0), spacing_m=2.0, samples=256)
    b = sky.ambient_light_map(scenes.street(length_m=40.0), spacing_m=2.0, samples=256)
    assert a.core is b.core
    open_map = sky.ambient_light_map(scenes.empty())
    assert open_map.grid.shape == (1, 1, 1, 5)
    assert open_map.grid[0, 0, 0, 0] == pytest.approx(E, rel=1e-4)


def test_a_map_under_a_new_sky_is_lit_from_the_scenes_horizon():
    # What the boxes hide is found once per geometry (_core.AmbientHorizon); a map under another
    # rain rate, visibility or sky is lit from it: the directly built map bit for bit, and on a
    # canyon's floor the independent scipy integral (canyon_illuminance) under each weather.
    from skyfall import _core

    boxes = sky._occluders(canyon(12.0, 10.0))
    lo, hi = np.array([-4.0, 0.0, -4.0]), np.array([4.0, 2.0, 4.0])
    weathers = [Weather(), Weather(rain_rate_mm_h=30.0), Weather(rain_rate_mm_h=5.0, visibility_m=300.0)]
    for i, w in enumerate(weathers):
        m = sky.cached_core_map(boxes, w, lo, hi, 1.0, 256)
        if i == 0:
            horizon = sky._horizon(boxes, lo, hi, 1.0, 256, "spacing_m")
            assert horizon is not None and horizon.samples == 256 and horizon.nbytes > 0
        direct = w.sky_model().ambient_map(boxes, bounds_min_m=list(lo), bounds_max_m=list(hi), spacing_m=1.0, samples=256)
        assert np.array_equal(m.values, direct.values) and np.array_equal(m.solid, direct.solid)
        ref = canyon_illuminance(0.0, 12.0, 10.0, extinction_per_m=w.extinction_per_m, cloud_base_m=w.cloud_base_height_m)
        assert m.values[4, 0, 4, 0] == pytest.approx(ref, rel=1e-3)
    # a grid past HORIZON_MAX_PAIRS keeps no horizon (MemoryError, at once) and its maps are
    # built directly
    big_lo, big_hi = np.array([0.0, 0.0, 0.0]), np.array([140.0, 14.0, 140.0])
    assert 141 * 15 * 141 * 64 > _core.HORIZON_MAX_PAIRS
    with pytest.raises(MemoryError, match="horizon"):
        _core.ambient_horizon(boxes, bounds_min_m=list(big_lo), bounds_max_m=list(big_hi), spacing_m=1.0, samples=64)
    m = sky.cached_core_map(boxes, weathers[1], big_lo, big_hi, 1.0, 64)
    assert sky._horizon(boxes, big_lo, big_hi, 1.0, 64, "spacing_m") is None
    assert m.dims == [141, 15, 141]


def test_expect_sweeps_lights_the_first_sky_from_the_horizon_with_the_same_bits():
    # After expect_sweeps() a geometry's first map finds its horizon at once (the dataset
    # workers' path); the map equals the one built directly, and False restores the default
    # (a new geometry's first map built directly, no horizon found).
    boxes = sky._occluders(canyon(11.0, 9.0))
    lo, hi = np.array([-3.0, 0.0, -3.0]), np.array([3.0, 2.0, 3.0])
    w = Weather(rain_rate_mm_h=7.0)
    direct = w.sky_model().ambient_map(boxes, bounds_min_m=list(lo), bounds_max_m=list(hi), spacing_m=1.0, samples=128)
    try:
        sky.expect_sweeps()
        m = sky.cached_core_map(boxes, w, lo, hi, 1.0, 128)
        key = (boxes.tobytes(), boxes.shape, tuple(lo), tuple(hi), 1.0, 128)
        assert sky._horizons.get(key) is not None
        assert np.array_equal(m.values, direct.values) and np.array_equal(m.solid, direct.solid)
    finally:
        sky.expect_sweeps(False)
    lo2 = lo - 1.0
    sky.cached_core_map(boxes, w, lo2, hi, 1.0, 128)
    assert (boxes.tobytes(), boxes.shape, tuple(lo2), tuple(hi), 1.0, 128) not in sky._horizons


def test_a_sweep_over_rain_and_visibility_reads_the_street_within_1e_3_of_the_full_tables():
    # Under a sky the same at every azimuth (overcast, in any rain or mist) a node's light is a
    # dot product of weights the street fixes with the sky's integrals at 24 elevations
    # (skyfall_core::sky::profile). Against the sky tabulated along every azimuth at 512
    # elevations (per_azimuth=True, what every map was before), at every open node of the
    # bundled street's frame grid: within 1e-3 of the node's light (its brightest channel), and
    # each channel within 1e-3 of itself where it sees 1 % of E or more.
    from skyfall import _core

    street = scenes.street()
    lo, hi = sky.default_bounds(street, 1.0)
    boxes = sky._occluders(street)
    kw = dict(bounds_min_m=list(lo), bounds_max_m=list(hi), spacing_m=1.0, samples=sky.MAP_SAMPLES)
    horizon = _core.ambient_horizon(boxes, **kw)
    before = horizon.nbytes
    for w in [Weather(), Weather(rain_rate_mm_h=2.0), Weather(rain_rate_mm_h=50.0), Weather(rain_rate_mm_h=5.0, visibility_m=300.0)]:
        model = w.sky_model()
        lit = model.light_map(horizon)
        direct = model.ambient_map(boxes, **kw)
        assert np.array_equal(lit.values, direct.values)  # one definition, however it is reached
        ref = model.ambient_map(boxes, **kw, per_azimuth=True)
        open_ = ~ref.solid.astype(bool)
        a, b = lit.values[open_].astype(np.float64), ref.values[open_].astype(np.float64)
        node = np.abs(a - b).max(axis=1) / np.maximum(np.abs(b).max(axis=1), 1e-6)
        own = np.abs(a - b) / np.maximum(np.abs(b), 1e-2)
        assert node.max() < 1e-3 and own.max() < 1e-3, (w, node.max(), own.max())
        assert not np.array_equal(a, b)  # the reading differs from the reference (within the bound)
        assert lit.values.min() >= 0.0  # light is never negative (the weights' rounding is clamped)
    assert horizon.nbytes > before  # the weights, made at the first such sky and kept
    # A sky with a sun varies with azimuth: read along every azimuth, as built directly.
    sun = Weather(sky=12, sun_elevation_deg=30.0, sun_azimuth_deg=140.0, rain_rate_mm_h=1.0).sky_model()
    assert np.array_equal(sun.light_map(horizon).values, sun.ambient_map(boxes, **kw, per_azimuth=True).values)


# ---- frames ---------------------------------------------------------------------------


W, H = 96, 64


@pytest.fixture(scope="module", params=["cpu", "gpu"])
def renderer(request) -> Renderer:
    return Renderer(W, H, backend=request.param)


def roofed_photo(roof: bool) -> PhotoScene:
    """A black photo (so a streak shows r I_R alone) under a roof over the left half (x < 0)."""
    occ = [{"min": (-30.0, 1.5, -30.0), "max": (0.0, 1.8, 30.0)}] if roof else []
    return PhotoScene(np.zeros((H, W, 3), np.float32), np.full((H, W), np.inf, np.float32), vertical_fov_deg=60.0, occluders=occ, encoding="linear", airlight="sky")


def test_streaks_under_a_roof_are_darker(renderer):
    # Sheltering off, so that rain falls under the roof too: the light model alone.
    w = Weather(rain_rate_mm_h=40.0, rain_near_m=4.0, rain_sheltered=False)
    dry = Weather(rain_rate_mm_h=40.0, rain_near_m=4.0, rain_streaks=False)
    light = {}
    for roof in (False, True):
        f = renderer.render(roofed_photo(roof), w, seed=5)
        bg = renderer.render(roofed_photo(roof), dry).rgb  # the hazed background, uniform
        a = f.layers["rain_alpha"]
        # A streak of coverage a moves C towards I_R by a r (I_R - C), r = 0.5: estimate the
        # coverage-weighted drop light I_R on each side of the image.
        left, right = np.s_[:, : W // 2 - 4], np.s_[:, W // 2 + 4 :]
        light[roof] = [bg[s][..., 0].mean() + (f.rgb[s] - bg[s])[..., 0].sum() / (0.5 * a[s].sum()) for s in (left, right)]
    # Open sky: both sides see I_R = 1 (E/pi units).
    np.testing.assert_allclose(light[False], 1.0, rtol=0.02)
    # Under the roof the left side is much darker, the right side (open, beside it) a little.
    assert light[True][0] < 0.6 * light[False][0]
    assert 0.6 * light[False][1] < light[True][1] < 0.98 * light[False][1]


@pytest.mark.parametrize("wind_x", [0.0, -3.0])
def test_a_roof_keeps_the_rain_off_save_what_the_wind_blows_in(wind_x):
    w = Weather(rain_rate_mm_h=40.0, rain_near_m=4.0, wind_m_s=(wind_x, 0.0, 0.0))
    roofed = roofed_photo(True)
    d = rain.drops((0.0, 0.0, 0.0), w, seed=5, ground=False, scene=roofed)
    every = rain.drops((0.0, 0.0, 0.0), w, seed=5, ground=False)
    under = (d.position_m[:, 0] < 0) & (d.position_m[:, 1] < 1.5)
    # Independently: a drop under the roof is there only if its path back up along its
    # velocity leaves the roof's underside (y = 1.5) beyond the edge x = 0.
    v = d.velocity_m_s
    x_at_roof = d.position_m[:, 0] + (1.5 - d.position_m[:, 1]) * v[:, 0] / v[:, 1]
    assert np.all(x_at_roof[under] >= -1e-4)
    if wind_x == 0.0:
        assert not under.any()
    else:
        assert under.sum() > 10  # blown in under the edge
    assert len(d.diameter_m) < len(every.diameter_m)
    # Frames draw those drops: fewer streaks with the roof than without.
    r = Renderer(W, H, backend="cpu")
    assert r.render(roofed, w, seed=5).stats["rain_drops"] < r.render(roofed_photo(False), w, seed=5).stats["rain_drops"]
    off = Weather(rain_rate_mm_h=40.0, rain_near_m=4.0, wind_m_s=(wind_x, 0.0, 0.0), rain_sheltered=False)
    assert len(rain.drops((0.0, 0.0, 0.0), off, seed=5, ground=False, scene=roofed).diameter_m) == len(every.diameter_m)


def test_cpu_and_gpu_agree_under_a_cie_sky_with_rain():
    w = Weather(rain_rate_mm_h=20.0, sky=10, sun_elevation_deg=30.0, sun_azimuth_deg=200.0)
    cam = Camera((1.5, 1.6, 0.0), pitch_deg=8.0, vertical_fov_deg=55.0)
    frames = [Renderer(W, H, backend=b).render(scenes.street(length_m=40.0), w, camera=cam, seed=2, ambient_spacing_m=2.0) for b in ("cpu", "gpu")]
    c, g = frames
    close = np.abs(c.rgb - g.rgb) <= 1e-3 * np.maximum(np.abs(c.rgb), 1.0)
    assert close.mean() > 0.99
    np.testing.assert_allclose(c.layers["rain_alpha"].mean(), g.layers["rain_alpha"].mean(), rtol=1e-3)


def test_rendered_sky_is_the_cie_luminance_through_colour_science():
    # Sky pixels of an empty scene under CIE type 12: their luminance Y (colour-science,
    # sRGB primaries) times E/pi is skyfall.sky.luminance along the pixel's ray.
    w = Weather(sky=12, sun_elevation_deg=40.0, sun_azimuth_deg=30.0)
    cam = Camera((0.0, 1.6, 0.0), yaw_deg=20.0, pitch_deg=25.0, vertical_fov_deg=60.0).with_resolution(W, H)
    f = Renderer(W, H, backend="cpu").render(scenes.empty(camera=cam), w)
    y = colour.RGB_to_XYZ(f.rgb.astype(np.float64), "sRGB")[..., 1] * w.luminance_scale_cd_m2
    fx, fy, cx, cy = cam.intrinsics()
    xs, ys = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    d = np.stack([(xs - cx) / fx, -(ys - cy) / fy, -np.ones_like(xs)], axis=-1) @ cam.rotation.T
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    el = np.degrees(np.arcsin(d[..., 1]))
    az = np.degrees(np.arctan2(d[..., 0], -d[..., 2]))
    sky_px = ~np.isfinite(f.depth_m)
    want = sky.luminance(el[sky_px], az[sky_px], weather=w)
    np.testing.assert_allclose(y[sky_px], want, rtol=2e-4)


def test_haze_airlight_follows_the_viewpoint_illuminance():
    # Yamamoto & Tadamura: Is = ks E_hv. Under a roof the camera's airlight is dimmer than in the open.
    w = Weather(rain_rate_mm_h=20.0, rain_streaks=False)
    r = Renderer(W, H, backend="cpu")
    # A black photo's sky pixel, hazed up to the cloud base: A (1 - t).
    f = r.render(roofed_photo(False), w)
    open_sky = f.rgb[0, 0, 0] / (1 - f.layers["transmittance"][0, 0])
    occ = [{"min": (-30.0, 0.5, -30.0), "max": (30.0, 0.8, 30.0)}]
    under = PhotoScene(np.zeros((H, W, 3), np.float32), np.full((H, W), np.inf, np.float32), occluders=occ, encoding="linear", airlight="sky")
    g = r.render(under, w)
    roofed = g.rgb[0, 0, 0] / (1 - g.layers["transmittance"][0, 0])
    assert open_sky == pytest.approx(w.airlight_relative, rel=1e-3)
    e_view = sky.horizontal_illuminance([0, 0, 0], under, weather=w, samples=sky.MAP_SAMPLES)[0] / w.sky_illuminance_lux
    assert roofed == pytest.approx(w.airlight_relative * e_view, rel=1e-4)
    assert e_view < 0.2


# ---- hard inputs ----------------------------------------------------------------------

_coord = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(_coord, st.floats(-50, 1e6), _coord), min_size=1, max_size=6), st.sampled_from(["up", "+x", "-x", "+z", "-z"]))
def test_illuminance_never_exceeds_the_open_sky_and_never_crashes(points, normal):
    s = scenes.street(length_m=40.0)
    e = sky.horizontal_illuminance(np.array(points), s, samples=16, normal=normal)
    assert e.shape == (len(points),)
    open_sky = sky.horizontal_illuminance([0, 1e5, 0], samples=16, normal=normal)[0]
    assert np.all((e >= 0) & (e <= open_sky * (1 + 1e-5)))


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.floats(allow_nan=True), st.floats(allow_nan=True), st.floats(allow_nan=True)), min_size=1, max_size=4))
def test_bad_points_raise_value_errors(points):
    arr = np.array(points, dtype=np.float64)
    m = sky.ambient_light_map(scenes.street(length_m=40.0), spacing_m=2.0, samples=16)
    if np.all(np.isfinite(arr)) and np.all(np.abs(arr) <= np.finfo(np.float32).max):
        assert np.all(np.isfinite(m.sample(arr)))
    else:
        with pytest.raises(ValueError, match="points_m"):
            m.sample(arr)


def test_nearby_cameras_share_one_map_extent_and_frames_keep_their_bits(monkeypatch):
    # The cube a frame's map must cover around its camera is widened outwards to
    # CAMERA_BOUNDS_STEP_M steps: a dataset's jittered cameras (+-0.5 m) share one extent, hence
    # one cached horizon and map per sky. The nodes stay on the scene's lattice, so a frame reads
    # the same values as from the camera's own (unwidened) extent: the same bits.
    street = scenes.street()
    eye = np.asarray(street.camera.position_m, dtype=np.float64)
    reach = 6.0
    extents = {tuple(np.concatenate(sky.default_bounds(street, 1.0, around_m=eye + [dx, 0.0, dz], radius_m=reach)))
               for dx in (-0.5, 0.0, 0.5) for dz in (-0.5, 0.0, 0.5)}
    assert len(extents) == 1
    lo, hi = (np.asarray(v) for v in np.split(np.array(next(iter(extents))), 2))
    # the cube is inside (down to the ground, where the street's map starts)
    assert (lo[[0, 2]] <= (eye - reach - 0.5)[[0, 2]]).all() and lo[1] == 0.0 and (hi >= eye + reach + 0.5).all()
    boxes = sky._occluders(street).astype(np.float64)
    np.testing.assert_array_equal(lo, [boxes[:, 0].min(), 0.0, boxes[:, 2].min()])  # the lattice's origin: the scene's
    step = sky.CAMERA_BOUNDS_STEP_M
    assert hi[2] % step == 0 and hi[2] > boxes[:, 5].max()  # widened past the boxes, to a whole step

    def unwidened(scene, spacing_m, around_m=None, radius_m=0.0):
        b = sky._occluders(scene).astype(np.float64)
        c = np.asarray(around_m, dtype=np.float64).reshape(1, 3)
        pts = np.concatenate([b[:, 0:3], b[:, 3:6], c - radius_m, c + radius_m])
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        lo[1] = max(lo[1], 0.0)
        hi[1] = max(hi[1], lo[1]) + spacing_m
        return lo, hi

    camera = Camera(tuple(eye + [0.3, 0.0, -0.2]), yaw_deg=4.0)
    weather = Weather(rain_rate_mm_h=17.0, visibility_m=900.0)
    r = Renderer(96, 54, backend="cpu")
    widened = r.render(street, weather, camera=camera, seed=3)
    monkeypatch.setattr(sky, "default_bounds", unwidened)
    own = r.render(street, weather, camera=camera, seed=3)
    np.testing.assert_array_equal(widened.rgb, own.rgb)
    for name in widened.layers:
        np.testing.assert_array_equal(widened.layers[name], own.layers[name])
