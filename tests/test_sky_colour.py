"""The colour of skies with a sun, and of the sun (``skyfall.sky.luminance_rgb``, ``colours``).

References: colour-science for every chromaticity (sRGB primaries to CIE xy) and, for the sun,
its own CIE 1931 table, black body and Rayleigh optical depth (Bodhaine et al. 1999: another
formula than the core's Hansen & Travis fit); the CIE luminance of ``sky.luminance`` for the
luminance a colour must keep. The issue's targets: a blue zenith at midday (x in 0.20-0.29),
an orange horizon towards a low sun, overcast skies neutral.
"""

from __future__ import annotations

import math

import colour
import numpy as np
import pytest

from skyfall import Camera, Renderer, Weather, scenes, sky

LUMA = np.array([0.2126, 0.7152, 0.0722])


def xy(rgb: np.ndarray) -> np.ndarray:
    """CIE 1931 xy of linear sRGB through colour-science."""
    return colour.XYZ_to_xy(colour.sRGB_to_XYZ(np.asarray(rgb, dtype=np.float64), apply_cctf_decoding=False))


@pytest.mark.parametrize(("sky_type", "sun_el"), [(11, 60.0), (12, 60.0), (12, 45.0), (13, 50.0), (14, 55.0)])
def test_a_clear_midday_zenith_is_blue(sky_type: int, sun_el: float) -> None:
    rgb = sky.luminance_rgb(90.0, 0.0, sky=sky_type, sun_elevation_deg=sun_el, sun_azimuth_deg=180.0)
    x, y = xy(rgb)
    assert 0.20 <= x <= 0.29, (x, y)
    assert rgb[2] > rgb[1] > rgb[0]


def test_a_low_suns_horizon_is_orange_towards_it_and_paler_away() -> None:
    kw = {"sky": 12, "sun_elevation_deg": 2.0, "sun_azimuth_deg": 90.0}
    toward = sky.luminance_rgb(2.0, 90.0, **kw)
    away = sky.luminance_rgb(2.0, 270.0, **kw)
    (xt, yt), (xa, _) = xy(toward), xy(away)
    # Orange: x above 0.40, its hue between red and yellow; away from the sun much paler.
    assert xt > 0.40 and yt > 0.37, (xt, yt)
    assert toward[0] > toward[1] > toward[2]
    assert xa < xt - 0.05
    cct = colour.xy_to_CCT(np.array([xt, yt]), method="Hernandez 1999")
    assert cct < 3000.0, cct


def test_the_colour_keeps_the_cie_luminance_over_the_whole_sky() -> None:
    el, az = np.meshgrid(np.linspace(0.0, 90.0, 19), np.linspace(0.0, 350.0, 36), indexing="ij")
    for w in (
        Weather(sky=12, sun_elevation_deg=35.0, sun_azimuth_deg=120.0),
        Weather(sky=8, sun_elevation_deg=20.0, sun_azimuth_deg=300.0, rain_rate_mm_h=5.0),
        Weather(sky=15, sun_elevation_deg=5.0, sun_azimuth_deg=10.0, visibility_m=3000.0),
    ):
        rgb = sky.luminance_rgb(el, az, weather=w)
        assert rgb.shape == (*el.shape, 3)
        np.testing.assert_allclose(rgb @ LUMA, sky.luminance(el, az, weather=w), rtol=2e-5)
        # Centre, edges, top and bottom rows: every direction has a colour, none negative.
        assert rgb.min() >= 0.0


@pytest.mark.parametrize("weather", [Weather(), Weather(sky=3), Weather(sky=5), Weather(rain_rate_mm_h=20.0)])
def test_overcast_skies_stay_neutral(weather: Weather) -> None:
    el, az = np.meshgrid(np.linspace(0.0, 90.0, 7), np.linspace(0.0, 300.0, 6), indexing="ij")
    rgb = sky.luminance_rgb(el, az, weather=weather)
    np.testing.assert_array_equal(rgb[..., 0], rgb[..., 1])
    np.testing.assert_array_equal(rgb[..., 1], rgb[..., 2])
    c = sky.colours(weather=weather)
    assert c.horizon == c.sky_light == c.sun == (1.0, 1.0, 1.0)


def _spectral_sun_xy(elevation_deg: float, turbidity: float) -> np.ndarray:
    """The sun's chromaticity through colour-science: a 5778 K black body, Bodhaine et al.'s
    Rayleigh optical depth, Angstrom's aerosols (beta from the turbidity as Preetham et al.
    give it, exponent 1.3), Kasten & Young's air mass, the CIE 1931 table."""
    shape = colour.SpectralShape(360, 780, 1)  # colour-science's default shape
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape)
    sd = colour.sd_blackbody(5778, shape)
    lam_um = sd.wavelengths / 1000.0
    h = elevation_deg
    m = 1.0 / (math.sin(math.radians(h)) + 0.50572 * (h + 6.07995) ** -1.6364)
    tau = colour.phenomena.rayleigh_optical_depth(lam_um * 1e-4) + max(0.04608 * turbidity - 0.04586, 0.0) * lam_um**-1.3
    sd = colour.SpectralDistribution(sd.values * np.exp(-m * tau), sd.wavelengths)
    with colour.utilities.suppress_warnings(colour_runtime_warnings=True):  # the default illuminant's alignment
        return colour.XYZ_to_xy(colour.sd_to_XYZ(sd, cmfs=cmfs))


@pytest.mark.parametrize(("sky_type", "turbidity"), [(12, 3.0), (15, 7.0)])
@pytest.mark.parametrize("sun_el", [3.0, 10.0, 30.0, 70.0])
def test_the_suns_colour_is_the_spectral_sum_through_colour_science(sky_type: int, turbidity: float, sun_el: float) -> None:
    got = np.array(sky.colours(sky=sky_type, sun_elevation_deg=sun_el, sun_azimuth_deg=0.0).sun)
    assert got @ LUMA == pytest.approx(1.0, rel=1e-5)
    want = _spectral_sun_xy(sun_el, turbidity)
    # A frame's colours are linear Rec. 709: a sun outside its gamut (below about 5 deg) is
    # clipped at 0 there, as the reference is here.
    inside = colour.XYZ_to_sRGB(colour.xyY_to_XYZ(np.array([*want, 1.0])), apply_cctf_encoding=False)
    want = xy(np.clip(inside, 0.0, None))
    # The core sums the CIE table every 10 nm over 380-780 nm with Hansen & Travis's Rayleigh
    # depth; the reference every 1 nm over 360-780 nm with Bodhaine's.
    np.testing.assert_allclose(xy(got), want, atol=3e-3)


def test_sky_light_is_blue_in_clear_air_and_shadows_under_it_are_bluer_than_sunlit_ground() -> None:
    c = sky.colours(sky=12, sun_elevation_deg=45.0, sun_azimuth_deg=0.0)
    x, y = xy(c.sky_light)
    assert x < 0.29 and y < 0.31, (x, y)
    assert xy(c.sun)[0] > 0.33
    # A frame: open grey ground in the sun and in the shade of a box (the sun behind it, its
    # shadow towards the camera); the shade is bluer.
    w = Weather(sky=12, sun_elevation_deg=45.0, sun_azimuth_deg=0.0)
    box = scenes.boxes(
        [{"min": (-2.0, 0.0, -14.0), "max": (2.0, 6.0, -10.0), "albedo": 0.3}],
        ground_albedo=0.3,
        camera=Camera((0.0, 1.6, 0.0), pitch_deg=-20.0),
    )
    f = Renderer(64, 40, backend="cpu").render(box, w)
    sun = f.layers["sun_transmittance"]
    ground = np.isfinite(f.depth_m) & (f.depth_m < 9.5)
    lit, shade = f.rgb[ground & (sun > 0.99)], f.rgb[ground & (sun < 0.01)]
    assert len(lit) > 20 and len(shade) > 20
    blueness = lambda px: float(np.mean(px[:, 2] / px[:, 0]))  # noqa: E731
    assert blueness(shade) > 1.2 * blueness(lit)


def test_a_rendered_sky_pixel_has_the_models_colour_on_both_backends() -> None:
    # The frame's sky pixels (an empty scene looking up, little haze) have the chromaticity of
    # sky.luminance_rgb along their rays; the GPU's WGSL mirror gives the same.
    w = Weather(sky=12, sun_elevation_deg=30.0, sun_azimuth_deg=200.0, visibility_m=100_000.0)
    cam = Camera((0.0, 1.6, 0.0), yaw_deg=10.0, pitch_deg=60.0, vertical_fov_deg=50.0).with_resolution(32, 24)
    frames = [Renderer(32, 24, backend=b).render(scenes.empty(camera=cam), w) for b in ("cpu", "gpu")]
    d = cam.ray_directions()
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    el = np.degrees(np.arcsin(d[..., 1]))
    az = np.degrees(np.arctan2(d[..., 0], -d[..., 2]))
    want = xy(sky.luminance_rgb(el, az, weather=w))
    for f in frames:
        assert not np.isfinite(f.depth_m).any()
        np.testing.assert_allclose(xy(f.rgb), want, atol=2e-3)
    np.testing.assert_allclose(frames[1].rgb, frames[0].rgb, rtol=2e-3)


def test_falling_rain_takes_the_sky_lights_colour() -> None:
    # The drops' light from the sky has the colour of the sky's light (sky.colours' sky_light);
    # under the overcast sky it stays grey. In front of a black wall (albedo 0, black ground)
    # each rain pixel is C = (1 - alpha) B + alpha L: L, the drops' light, solved per pixel
    # from the layer rain_alpha and the frame's own rain-free background B.
    cam = Camera((0.0, 1.6, 0.0), pitch_deg=0.0, vertical_fov_deg=40.0)
    wall = {"min": (-50.0, 0.0, -12.0), "max": (50.0, 30.0, -11.0), "albedo": 0.0}
    for kw in ({"sky": 12, "sun_elevation_deg": 50.0, "sun_azimuth_deg": 185.0}, {}):
        w = Weather(rain_rate_mm_h=20.0, visibility_m=100_000.0, **kw)
        f = Renderer(192, 108, backend="cpu").render(scenes.boxes([wall], ground_albedo=0.0, camera=cam), w, seed=1)
        a, c = f.layers["rain_alpha"][:54], f.rgb[:54].astype(np.float64)
        background = c[a < 1e-6].mean(axis=0)
        m = a > 0.004
        assert m.sum() > 500
        light = ((c[m] - background * (1.0 - a[m, None])) / a[m, None]).sum(axis=0)
        want = np.array(sky.colours(weather=w).sky_light)
        np.testing.assert_allclose(light / light[1], want / want[1], atol=0.02 if kw else 1e-4)
        if kw:
            assert light[0] / light[1] < 0.9  # bluer than grey, measurably


def _air_extinction_per_m(visibility_m: float, nm: float) -> float:
    """Clear air's extinction at ``nm``: Koschmieder's 3.912/V at 550 nm, of it Rayleigh's
    1.16e-2 /km at sea level (Bucholtz 1995) as lambda^-4.08, the rest aerosol as lambda^-1.3
    (Angstrom)."""
    sigma = 3.912 / visibility_m
    rayleigh = min(1.16e-5, sigma)
    x = nm / 550.0
    return rayleigh * x**-4.08 + (sigma - rayleigh) * x**-1.3


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_clear_air_turns_distance_blue_grey_at_each_channels_wavelength(backend: str) -> None:
    # A black ground in clear air (V = 2 km) under a sky with a sun: each ground pixel is the
    # airlight alone, A_c (1 - t_c). The transmittance layer is the green's (550 nm); the red
    # and blue channels see the air's extinction at the sRGB primaries' dominant wavelengths
    # (colour-science), so A_c = pixel_c / (1 - t_c) is one colour at every distance with the
    # right t_c, and not with the green's.
    cs = colour.RGB_COLOURSPACES["sRGB"]
    nm = [float(colour.dominant_wavelength(p, cs.whitepoint)[0]) for p in cs.primaries]
    visibility = 2000.0
    sigma = np.array([_air_extinction_per_m(visibility, nm[0]), 3.912 / visibility, _air_extinction_per_m(visibility, nm[2])])
    assert sigma[2] / sigma[1] > 1.2 and sigma[0] / sigma[1] < 0.9
    cam = Camera((0.0, 1.6, 0.0), pitch_deg=-4.0, vertical_fov_deg=12.0, width=48, height=40)
    ground = scenes.boxes([], ground_albedo=(0.0, 0.0, 0.0), camera=cam)
    w = Weather(sky=12, sun_elevation_deg=40.0, sun_azimuth_deg=150.0, visibility_m=visibility)
    f = Renderer(48, 40, backend=backend).render(ground, w, layers=("transmittance",))
    t_green = f.layers["transmittance"]
    seen = np.isfinite(f.depth_m) & (t_green > 0.05) & (t_green < 0.97)
    assert seen.sum() > 300 and np.ptp(t_green[seen]) > 0.4  # from about 15 m to 400 m
    path = -np.log(t_green[seen].astype(np.float64)) / sigma[1]
    t = np.exp(-path[:, None] * sigma[None, :])
    airlight = f.rgb[seen] / (1.0 - t)
    spread = np.ptp(airlight, axis=0) / airlight.mean(axis=0)
    assert spread.max() < 2e-3, spread
    grey = f.rgb[seen][:, 2] / (1.0 - t_green[seen])
    assert np.ptp(grey) / grey.mean() > 0.05  # the green's transmittance would not do for blue
    # The airlight is the horizon's colour (x near 0.30 at midday); distance on the way to it is
    # bluer: at a few hundred metres the haze's own chromaticity lies below the airlight's in x.
    near = np.argmin(np.abs(path - 300.0))
    x_air, x_near = xy(airlight.mean(axis=0))[0], xy(f.rgb[seen][near])[0]
    assert x_near < x_air - 0.005, (x_near, x_air)
    # An overcast sky's haze stays grey: one transmittance for every channel.
    o = Renderer(48, 40, backend=backend).render(ground, Weather(visibility_m=visibility), layers=("transmittance",))
    ratio = o.rgb[seen] / (1.0 - o.layers["transmittance"][seen])[:, None]
    assert np.ptp(ratio) / ratio.mean() < 1e-4
