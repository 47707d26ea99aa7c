"""The snow cover (skyfall.snow.accumulate) against what is known without it: the depth on
open level ground R * t * rho_water / rho_snow, the geometry of a box's wind shadow
(h * tan of the fall angle), exact mass bookkeeping, and the frames that draw it."""

from __future__ import annotations

import dataclasses
import hashlib
import math
import subprocess
import sys

import numpy as np
import pytest

from skyfall import PhotoScene, Renderer, Weather, io, scenes, snow

HOUR = 3600.0


def wall(height_m: float = 4.0) -> scenes.BoxScene:
    """A wall across the wind (x in [0, 2] m, z in [-50, 50] m) on open ground."""
    return scenes.boxes([{"min": (0.0, 0.0, -50.0), "max": (2.0, height_m, 50.0)}])


def test_open_level_ground_in_still_air_gets_rate_times_time_times_density_ratio() -> None:
    # 1 mm/h of water at 100 kg/m^3 for one hour: 1.000 cm.
    w = Weather(snow_rate_mm_h=1.0, snow_density_kg_m3=100.0)
    smooth = snow.accumulate(scenes.empty(), w, duration_s=HOUR, dt_s=60.0, resolution_m=1.0, roughness=0.0)
    np.testing.assert_allclose(smooth.depth_m, 0.01, rtol=1e-9)
    rough = snow.accumulate(scenes.empty(), w, duration_s=HOUR, dt_s=60.0, resolution_m=1.0, seed=5)
    assert abs(rough.depth_m.mean() / 0.01 - 1.0) < 0.01
    assert 0.0 < rough.depth_m.std() < 0.1 * 0.01
    assert snow.open_depth_m(w, HOUR) == pytest.approx(0.01, rel=1e-12)
    assert rough.open_depth_m == pytest.approx(0.01, rel=1e-12)
    # Denser snow lies thinner: at 250 kg/m^3, 4 mm.
    dense = snow.accumulate(scenes.empty(), Weather(snow_rate_mm_h=1.0, snow_density_kg_m3=250.0), duration_s=HOUR, resolution_m=2.0)
    assert dense.depth_m.mean() == pytest.approx(0.004, rel=1e-9)


def _lift(cover: snow.SnowCover, height_m: float) -> float:
    """Macdonald's canopy lift G(h) = h/a (1 - exp(-a)) of a height at the canopy's top."""
    h, a, _ = cover.canopy
    assert h == pytest.approx(height_m, rel=1e-12)
    return h / a * (1.0 - math.exp(-a))


FASTEST_FLAKE_M_S = 0.8 * 10.0**0.16
"""Locatelli & Hobbs' v = 0.8 S^0.16 m/s at the largest flake drawn, S = 10 mm."""


def test_a_wall_in_slanted_wind_leaves_a_soft_shadow_as_long_as_the_flakes_speeds_say() -> None:
    spacing = 0.25
    w = Weather(snow_rate_mm_h=2.0, wind_m_s=(2.5, 0.0, 0.0))
    cover = snow.accumulate(wall(), w, duration_s=HOUR, dt_s=120.0, resolution_m=spacing, extent_m=(-10, -3, 30, 3), turbulence=0.0, roughness=0.0)
    vx, vy, vz = cover.fall_velocity_m_s
    assert vx == 2.5 and vz == 0.0 and 0.8 < -vy < 1.2  # Locatelli & Hobbs' aggregates fall at ~1 m/s
    # The wall's canopy: 4 m x 6 m of face over 40 m x 6 m, a = 9.6 lambda_f (Macdonald 2000).
    assert cover.canopy[2] == pytest.approx(0.1, rel=1e-12) and cover.canopy[1] == pytest.approx(0.96, rel=1e-12)
    lift = _lift(cover, 4.0)
    x = cover.x_m
    profile = cover.depth_m[cover.shape[0] // 2]
    open_d = cover.open_depth_m
    upwind = x < -2 * spacing
    top = (x > spacing) & (x < 2.0 - spacing)
    np.testing.assert_allclose(profile[upwind], open_d, rtol=1e-9)
    np.testing.assert_allclose(profile[top], open_d, rtol=0.05)
    # Bare where even the fastest flakes are shaded: 2.5 G / v_max behind the wall.
    bare = (x > 2.0 + 2 * spacing) & (x < 2.0 + vx * lift / FASTEST_FLAKE_M_S - 2 * spacing)
    assert bare.sum() > 10 and np.all(profile[bare] == 0.0)
    # Half covered about where the flakes' mean speed's path lands, and soft around it.
    mean_end = 2.0 + vx * lift / -vy
    half = (x > 2.0) & (profile > 0.5 * open_d)
    assert abs(x[half][0] - mean_end) < 1.0, (x[half][0], mean_end)
    soft = (x > 2.0) & (profile > 0.1 * open_d) & (profile < 0.9 * open_d)
    assert soft.sum() >= 4
    assert profile[-5] > 0.95 * open_d


def test_the_street_in_a_breeze_keeps_its_snow_and_a_gale_builds_drifts_in_the_lee() -> None:
    # The case: 3 h of 2 mm/h on the bundled street. A single straight fall line at
    # 1.1 m/s shaded the whole street (0.5 % of pixels under snow against 27.7 % in calm air);
    # slowed below the roofs and spread over the flakes' speeds and the gusts, the snow reaches
    # the street.
    street = scenes.street()
    r = Renderer(192, 108, backend="cpu")

    def covered(wind: tuple[float, float, float]) -> tuple[float, snow.SnowCover]:
        c = snow.accumulate(street, Weather(snow_rate_mm_h=2.0, wind_m_s=wind), duration_s=3 * HOUR, dt_s=600.0)
        f = r.render(street, Weather(wind_m_s=wind, snow_cover=c))
        return float((f.layers["snow_depth_m"] > 0.001).mean()), c

    calm, _ = covered((0.0, 0.0, 0.0))
    breeze, c = covered((1.0, 0.0, 0.5))
    assert calm > 0.2
    assert breeze >= 0.5 * calm, (breeze, calm)
    assert c.blown_in_kg == 0.0 and c.blown_out_kg == 0.0  # 1.1 m/s moves no lying snow
    # 10 m/s across the street: the lying snow moves (mass exact) and piles up in the lee.
    gale = snow.accumulate(street, Weather(snow_rate_mm_h=2.0, wind_m_s=(10.0, 0.0, 0.0)), duration_s=3 * HOUR, dt_s=600.0)
    assert gale.blown_out_kg > 0.0
    assert gale.lying_kg == pytest.approx(gale.fallen_kg + gale.blown_in_kg - gale.blown_out_kg, rel=1e-9)
    assert gale.depth_m.max() > 2.0 * gale.open_depth_m


def test_snow_fallen_on_the_catchment_is_snow_lying_on_it() -> None:
    w = Weather(snow_rate_mm_h=5.0, snow_density_kg_m3=120.0, wind_m_s=(4.0, 0.0, 1.5))
    cover = snow.accumulate(scenes.street(), w, duration_s=2 * HOUR, dt_s=600.0, resolution_m=1.0, roughness=0.5)
    lying = float(cover.depth_m.sum()) * cover.spacing_m**2 * 120.0
    assert lying == pytest.approx(cover.fallen_kg, rel=1e-12)
    assert cover.lying_kg == pytest.approx(cover.fallen_kg, rel=1e-12)
    assert cover.blown_in_kg == cover.blown_out_kg == 0.0  # 4.3 m/s: below fresh snow's threshold
    # The buildings' wind shadows held back snow the open sky let through.
    assert cover.fallen_kg < 0.98 * cover.open_sky_kg
    # In still air over open ground nothing is held back.
    still = snow.accumulate(scenes.empty(), Weather(snow_rate_mm_h=5.0), duration_s=HOUR, resolution_m=2.0)
    assert still.fallen_kg == pytest.approx(still.open_sky_kg, rel=1e-12)


def _digest() -> str:
    w = Weather(snow_rate_mm_h=3.0, wind_m_s=(3.0, 0.0, -2.0))
    c = snow.accumulate(wall(), w, duration_s=1800.0, dt_s=300.0, resolution_m=0.5, seed=11, extent_m=(-10, -3, 30, 3))
    return hashlib.sha256(c.depth_m.tobytes()).hexdigest()


def test_the_cover_is_the_same_bits_in_another_process_and_depends_on_the_seed() -> None:
    code = "import sys; sys.path.insert(0, 'tests'); import test_snow_cover as t; print(t._digest())"
    other = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=None)
    assert other.stdout.strip() == _digest()
    w = Weather(snow_rate_mm_h=3.0, wind_m_s=(3.0, 0.0, -2.0))
    a = snow.accumulate(wall(), w, duration_s=1800.0, dt_s=300.0, resolution_m=0.5, seed=11, extent_m=(-10, -3, 30, 3))
    b = snow.accumulate(wall(), w, duration_s=1800.0, dt_s=300.0, resolution_m=0.5, seed=12, extent_m=(-10, -3, 30, 3))
    assert not np.array_equal(a.depth_m, b.depth_m)


def test_hard_cases_are_finite_or_refused_naming_the_parameter() -> None:
    none = snow.accumulate(wall(), Weather(wind_m_s=(5.0, 0.0, 0.0)), duration_s=HOUR, resolution_m=1.0)
    assert none.steps == 0 and not none.depth_m.any() and none.fallen_kg == 0.0
    gale = snow.accumulate(wall(), Weather(snow_rate_mm_h=100.0, wind_m_s=(60.0, 0.0, 0.0)), duration_s=HOUR, dt_s=2 * HOUR, resolution_m=0.5)
    assert gale.steps == 1 and gale.dt_s == HOUR
    assert np.all(np.isfinite(gale.depth_m)) and gale.depth_m.min() >= 0.0
    assert gale.lying_kg == pytest.approx(gale.fallen_kg + gale.blown_in_kg - gale.blown_out_kg, rel=1e-9)
    assert gale.blown_out_kg > 0.0
    # 100 mm/h of water for an hour: 1 m on open ground; the gale piles it up in the lee.
    assert gale.depth_m.max() < 3.0
    with pytest.raises(ValueError, match=r"^wind_m_s\[1\] = 5.0 m/s lifts the snow"):
        snow.accumulate(scenes.empty(), Weather(snow_rate_mm_h=1.0, wind_m_s=(0.0, 5.0, 0.0)), duration_s=60.0, resolution_m=5.0)
    with pytest.raises(ValueError, match=r"^resolution_m = 0.01 m over .* cells"):
        snow.accumulate(scenes.street(), Weather(snow_rate_mm_h=1.0), duration_s=60.0, resolution_m=0.01)
    with pytest.raises(ValueError, match=r"^dt_s = 0.01 s gives"):
        snow.accumulate(scenes.empty(), Weather(snow_rate_mm_h=1.0), duration_s=HOUR, dt_s=0.01, resolution_m=5.0)
    with pytest.raises(ValueError, match=r"^turbulence = 2.5 is outside the valid range \[0, 2\]"):
        snow.accumulate(scenes.empty(), Weather(snow_rate_mm_h=1.0), duration_s=60.0, turbulence=2.5)
    with pytest.raises(TypeError, match="redistribute must be a bool"):
        snow.accumulate(scenes.empty(), Weather(snow_rate_mm_h=1.0), duration_s=60.0, redistribute="yes")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="extent_m"):
        snow.accumulate(scenes.empty(), Weather(), duration_s=60.0, extent_m=(0, 0, -1, 1))
    with pytest.raises(TypeError, match="weather"):
        snow.accumulate(scenes.empty(), None, duration_s=60.0)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="snow_cover must be a skyfall.snow.SnowCover"):
        Weather(snow_cover="deep")  # type: ignore[arg-type]


def _ground_interp_depth(cover: snow.SnowCover, frame_depth: np.ndarray, renderer: Renderer, cam) -> np.ndarray:
    """The cover's depth at each pixel's ground point (NaN where the pixel is not ground
    over the grid), from the depth map through the camera: bilinear between the centres of
    the four cells around the point that lie on the ground (base within a cell of 0; a
    cell of another surface, or off the grid, left out and the weights renormalised)."""
    p = _points(np.where(np.isfinite(frame_depth), frame_depth, 0.0), cam, renderer)
    s = cover.spacing_m
    nz, nx = cover.shape
    fu = (p[..., 0] - cover.origin_m[0]) / s
    fv = (p[..., 2] - cover.origin_m[1]) / s
    i, k = np.floor(fu).astype(int), np.floor(fv).astype(int)
    inside = np.isfinite(frame_depth) & (i >= 0) & (k >= 0) & (i < nx) & (k < nz) & (np.abs(p[..., 1]) < 0.05)
    # Ground under the awning lies beneath the awning's cell (its snow is on the awning).
    ic, kc = np.clip(i, 0, nx - 1), np.clip(k, 0, nz - 1)
    inside &= np.abs(np.nan_to_num(cover.base_m[kc, ic], nan=1e9)) < 1e-6
    u, v = fu - 0.5, fv - 0.5
    i0, k0 = np.floor(u).astype(int), np.floor(v).astype(int)
    tx, tz = u - i0, v - k0
    w_sum = np.zeros(frame_depth.shape)
    d_sum = np.zeros(frame_depth.shape)
    for di, wx in ((0, 1.0 - tx), (1, tx)):
        for dk, wz in ((0, 1.0 - tz), (1, tz)):
            ii, kk = i0 + di, k0 + dk
            on = (ii >= 0) & (kk >= 0) & (ii < nx) & (kk < nz)
            iic, kkc = np.clip(ii, 0, nx - 1), np.clip(kk, 0, nz - 1)
            base = cover.base_m[kkc, iic]
            on &= np.abs(np.nan_to_num(base, nan=1e9)) <= s
            w = np.where(on, wx * wz, 0.0)
            w_sum += w
            d_sum += w * cover.depth_m[kkc, iic]
    out = np.full(frame_depth.shape, np.nan)
    ok = inside & (w_sum > 0)
    out[ok] = d_sum[ok] / w_sum[ok]
    return out


def _footprint_m(frame_depth: np.ndarray, cam, r: Renderer) -> np.ndarray:
    """A level surface's pixel footprint, m: the pixel's side at its distance, the grazing
    side stretched by 1 / |cos| of the ray to the vertical (the geometric mean of the two)."""
    fx, fy, cx, cy = cam.with_resolution(r.width, r.height).intrinsics()
    y, x = np.mgrid[0 : r.height, 0 : r.width] + 0.5
    rays = np.stack([(x - cx) / fx, -(y - cy) / fy, -np.ones_like(x)], axis=-1) @ np.asarray(cam.rotation).T
    length = np.linalg.norm(rays, axis=-1)
    cos = np.maximum(np.abs(rays[..., 1]) / length, 0.0025)
    return frame_depth * length / fy / np.sqrt(cos)


def test_a_frame_shows_the_cover_white_and_its_depth_layer() -> None:
    r = Renderer(96, 54, backend="cpu")
    w = Weather(snow_rate_mm_h=2.0, wind_m_s=(1.5, 0.0, 0.0))
    street = scenes.street()
    cover = snow.accumulate(street, w, duration_s=HOUR, resolution_m=0.5)
    # drawn once the snow has stopped: no flakes nor their haze over the cover
    after = Weather(wind_m_s=w.wind_m_s)
    bare = r.render(street, after)
    white = r.render(street, dataclasses.replace(after, snow_cover=cover))
    layer = white.layers["snow_depth_m"]
    want = _ground_interp_depth(cover, white.depth_m, r, street.camera)
    ground = np.isfinite(want)
    assert ground.sum() > 500
    # Each ground pixel shows the depth interpolated between the cells' centres (but where a
    # grazing ray meets a column's side, which shows that column's own depth): where the snow
    # is whole (2 cm and more) or a pixel spans many of thin snow's patches, that depth; nearer,
    # on thin snow, the patches' depth d / c(d) where it shows one (the mass kept), 0 between.
    lo, hi = snow.PATCH_BLEND
    fp = _footprint_m(white.depth_m, street.camera, r)
    cov = 1.0 - (1.0 - np.minimum(np.nan_to_num(want) / 0.02, 1.0)) ** 2
    exact = ground & ((cov >= 1.0) | (fp > 1.05 * hi * snow.PATCH_M) | (want == 0.0))
    assert exact.sum() > 400
    agree = np.isclose(layer[exact], want[exact], rtol=1e-4, atol=1e-6)
    assert agree.mean() > 0.97, agree.mean()
    patchy = ground & ~exact
    top = np.where(patchy, want / np.where(cov > 0, cov, 1.0), 0.0)
    assert np.all(layer[patchy] <= top[patchy] * (1 + 1e-4) + 1e-6)
    # Not the cells' own depths: the interpolation is there (most pixels lie off the centres).
    nz, nx = cover.shape
    p = _points(np.where(np.isfinite(white.depth_m), white.depth_m, 0.0), street.camera, r)
    i = np.clip(np.floor((p[..., 0] - cover.origin_m[0]) / cover.spacing_m).astype(int), 0, nx - 1)
    k = np.clip(np.floor((p[..., 2] - cover.origin_m[1]) / cover.spacing_m).astype(int), 0, nz - 1)
    own = cover.depth_m[k, i]
    assert np.mean(np.isclose(layer[ground], own[ground], rtol=1e-6)) < 0.5
    covered = ground & (layer > 0.001)
    assert covered.sum() > 300
    # Far enough that a pixel spans many of thin snow's patches, it shows their mean share:
    # albedo 0.12 + (0.85 - 0.12) * c(d), c(d) = 1 - (1 - d / 2 cm)^2, lit as the bare ground is.
    blended = covered & (fp > 1.05 * hi * snow.PATCH_M)
    assert blended.sum() > 200
    frac = 1.0 - (1.0 - np.minimum(layer[blended] / 0.02, 1.0)) ** 2
    ratio = white.rgb[blended][:, 1] / bare.rgb[blended][:, 1]
    # (The lifted surface is met a little nearer, where the sky light differs slightly, and
    # at edges the bare pixel sees something else.)
    rel = ratio / ((0.12 + (snow.SNOW_ALBEDO - 0.12) * frac) / 0.12) - 1.0
    assert abs(np.median(rel)) < 0.005 and np.mean(np.abs(rel) < 0.02) > 0.9
    # Sky and walls carry no snow; a cover of no snow is no cover, bit for bit.
    assert np.all(layer[np.isinf(white.depth_m)] == 0.0)
    empty = snow.accumulate(street, Weather(), duration_s=HOUR, resolution_m=0.5)
    same = r.render(street, dataclasses.replace(after, snow_cover=empty))
    assert np.array_equal(same.rgb, bare.rgb) and np.array_equal(same.depth_m, bare.depth_m)
    # The 8-bit path draws it too (through the float frame).
    np.testing.assert_array_equal(r.render_srgb8(street, dataclasses.replace(after, snow_cover=cover)), io.to_srgb8(white.rgb))


def _dusted(depth_m: float) -> snow.SnowCover:
    """Open ground under ``depth_m`` of snow, the same everywhere (no roughness): 1 mm/h of
    water at 100 kg/m^3 lays 1 cm/h."""
    w = Weather(snow_rate_mm_h=1.0, snow_density_kg_m3=100.0)
    return snow.accumulate(scenes.empty(), w, duration_s=depth_m / 0.01 * HOUR, resolution_m=1.0, roughness=0.0,
                           extent_m=(-60.0, -60.0, 60.0, 60.0))


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_thin_snow_lies_in_patches_covering_the_share_its_depth_gives(backend: str) -> None:
    # Looking down from 1.5 m at ground under a uniform thin cover: near enough that each
    # pixel is snow or ground (footprint under 1 cm against 10 cm patches). Twelve views 20 m
    # apart hold about 2,500 of the patches' largest cells; over them the share of snow pixels
    # is c(d) = 1 - (1 - d / 2 cm)^2, the analytic coverage, within 0.03 (a view alone: about
    # 0.04 either way), and within 0.05 in each half of the frames (top, bottom, left, right).
    r = Renderer(320, 180, backend=backend)
    views = [_looking_down(20.0 * (j % 4) - 30.0, 20.0 * (j // 4) - 20.0) for j in range(12)]
    for view in views[:1]:
        assert _footprint_m(np.full((180, 320), 1.5), view.camera, r).max() < snow.PATCH_BLEND[0] * snow.PATCH_M
    for c in (0.2, 0.5, 0.8):
        d = 0.02 * (1.0 - math.sqrt(1.0 - c))
        assert snow.coverage(d) == pytest.approx(c, rel=1e-6)
        cover, deep = _dusted(d), _dusted(0.03)
        shares = []
        for scene in views:
            bare = r.render(scene, Weather())
            thin = r.render(scene, Weather(snow_cover=cover))
            full = r.render(scene, Weather(snow_cover=deep))
            assert np.all(full.rgb[..., 1] > 3.0 * bare.rgb[..., 1])  # 2 cm and more hide the ground
            share = (thin.rgb[..., 1] - bare.rgb[..., 1]) / (full.rgb[..., 1] - bare.rgb[..., 1])
            # Sharp: each pixel is snow or ground (the lifted surface's light differs by < 1 %).
            assert np.mean((share < 0.01) | (share > 0.99)) > 0.99, backend
            # The layer is the depth the pixel shows: the patches' d / c (the mass kept) on
            # snow, 0 between them; its expectation is d.
            layer = thin.layers["snow_depth_m"]
            np.testing.assert_allclose(layer[share > 0.99], d / c, rtol=1e-4)
            assert np.all(layer[share < 0.01] == 0.0)
            shares.append(share > 0.5)
        snowy = np.stack(shares)
        assert abs(snowy.mean() - c) < 0.03, (c, snowy.mean())
        for part in (snowy[:, :90], snowy[:, 90:], snowy[:, :, :160], snowy[:, :, 160:]):
            assert abs(part.mean() - c) < 0.05, (c, part.mean())
    # The patches are the same in every frame (no seed) and grow around themselves: what lies
    # at c = 0.2 still lies at c = 0.5.
    bare_g = r.render(views[0], Weather()).rgb[..., 1]
    a = r.render(views[0], Weather(snow_cover=_dusted(0.02 * (1 - math.sqrt(0.8))))).rgb[..., 1] > 2 * bare_g
    b = r.render(views[0], Weather(snow_cover=_dusted(0.02 * (1 - math.sqrt(0.5))))).rgb[..., 1] > 2 * bare_g
    assert a.sum() > 0 and np.mean(b[a]) > 0.995


def _looking_down(x_m: float, z_m: float, height_m: float = 1.5) -> scenes.BoxScene:
    return scenes.empty(camera=scenes.Camera((x_m, height_m, z_m), pitch_deg=-89.0, vertical_fov_deg=40.0))


def test_far_away_a_pixel_shows_the_patches_mean_share_exactly() -> None:
    # From 30 m up a pixel spans about 20 cm of ground, several of the patches' largest cells:
    # every pixel is the blend ground + (snow - ground) * c(d), whole frame, to float precision.
    r = Renderer(96, 54, backend="cpu")
    scene = _looking_down(0.0, 0.0, 30.0)
    d = 0.006
    c = 1.0 - (1.0 - d / 0.02) ** 2
    bare = r.render(scene, Weather()).rgb
    thin = r.render(scene, Weather(snow_cover=_dusted(d))).rgb
    full = r.render(scene, Weather(snow_cover=_dusted(0.03))).rgb
    assert _footprint_m(np.full((54, 96), 30.0), scene.camera, r).min() > 0.5 * snow.PATCH_M
    # (The lifted surfaces are met 6 mm and 3 cm nearer: the sky light there differs by ~1e-4.)
    np.testing.assert_allclose(thin, bare + (full - bare) * c, rtol=2e-4)
    # The depth layer there is the mean depth, d.
    np.testing.assert_allclose(r.render(scene, Weather(snow_cover=_dusted(d))).layers["snow_depth_m"], d, rtol=1e-5)


def test_snow_lies_on_a_photos_upward_surfaces_and_not_in_its_wind_shadow() -> None:
    # The photo: a rendered frame of a wall across the wind, with its depth map.
    r = Renderer(120, 68, backend="cpu")
    scene = scenes.boxes(
        [{"min": (-20.0, 0.0, -14.0), "max": (20.0, 3.0, -12.0)}],
        camera=scenes.Camera((0.0, 6.0, 0.0), pitch_deg=-25.0, vertical_fov_deg=60.0),
    )
    shot = r.render(scene)
    photo = PhotoScene(shot.rgb, shot.depth_m, camera=scene.camera, encoding="linear", airlight="sky")
    still = snow.accumulate(photo, Weather(snow_rate_mm_h=2.0), duration_s=HOUR, resolution_m=0.5, roughness=0.0)
    frame = r.render(photo, Weather(snow_rate_mm_h=2.0, snow_cover=still))
    d = frame.layers["snow_depth_m"]
    normal_up = _photo_ground(shot.depth_m, scene.camera, r)
    # Level ground and the wall's top: the open depth (2 cm); the wall's face: none.
    level = normal_up & (d > 0)
    assert level.sum() > 0.5 * normal_up.sum()
    np.testing.assert_allclose(np.median(d[level]), 0.02, rtol=0.01)
    face = _wall_face(shot.depth_m, scene.camera, r)
    assert face.sum() > 50 and np.all(d[face] == 0.0)
    assert np.all(frame.rgb[level].mean(axis=1) > shot.rgb[level].mean(axis=1))
    # Wind from behind the wall towards the camera (+z): the ground in front of it, in its
    # lee, is bare as far as the fastest flakes' path from its top lands (1.5 G(3 m) / v_max,
    # G the lift under the photo's canopy), covered where only the slowest flakes are shaded.
    windy = Weather(snow_rate_mm_h=2.0, wind_m_s=(0.0, 0.0, 1.5))
    cover = snow.accumulate(photo, windy, duration_s=HOUR, resolution_m=0.5, roughness=0.0, turbulence=0.0)
    h, a, _ = cover.canopy
    assert h == pytest.approx(3.0, abs=0.05) and a < 1e-5  # one wall in a wide field: no canopy to speak of
    lift = h / a * (1.0 - math.exp(-a)) if a > 0 else h
    bare_to = 1.5 * lift / FASTEST_FLAKE_M_S
    z = cover.z_m
    at = int(np.searchsorted(cover.x_m, 0.0))
    col, base = cover.depth_m[:, at], cover.base_m[:, at]
    lee = (z > -12.0 + 1.0) & (z < -12.0 + bare_to - 1.0) & np.isfinite(base)
    assert lee.sum() >= 3 and np.all(col[lee] == 0.0), (bare_to, col[lee])
    beyond = (z > -12.0 + 1.6 * bare_to) & np.isfinite(base)
    assert beyond.sum() >= 3 and np.all(col[beyond] > 0.8 * cover.open_depth_m), col[beyond]


def _points(depth: np.ndarray, cam, r: Renderer) -> np.ndarray:
    fx, fy, cx, cy = cam.with_resolution(r.width, r.height).intrinsics()
    y, x = np.mgrid[0 : r.height, 0 : r.width] + 0.5
    rays = np.stack([(x - cx) / fx, -(y - cy) / fy, -np.ones_like(x)], axis=-1) @ np.asarray(cam.rotation).T
    return np.asarray(cam.position_m) + rays * depth[..., None]


def _photo_ground(depth: np.ndarray, cam, r: Renderer) -> np.ndarray:
    """Pixels on level surfaces (the ground, the wall's top), away from edges."""
    p = _points(depth, cam, r)
    finite = np.isfinite(depth)
    on = finite & ((np.abs(p[..., 1]) < 1e-3) | (np.abs(p[..., 1] - 3.0) < 1e-3))
    inner = on.copy()
    inner[1:-1, 1:-1] &= on[:-2, 1:-1] & on[2:, 1:-1] & on[1:-1, :-2] & on[1:-1, 2:]
    inner[[0, -1], :] = False
    inner[:, [0, -1]] = False
    return inner


def _wall_face(depth: np.ndarray, cam, r: Renderer) -> np.ndarray:
    p = _points(depth, cam, r)
    return np.isfinite(depth) & (np.abs(p[..., 2] + 12.0) < 1e-3) & (p[..., 1] > 0.2) & (p[..., 1] < 2.8)


def test_the_gpu_backend_draws_the_cover_as_the_cpu_does() -> None:
    street = scenes.street()
    w = Weather(snow_rate_mm_h=3.0, wind_m_s=(0.3, 0.0, 1.5))
    cover = snow.accumulate(street, w, duration_s=HOUR, resolution_m=0.5)
    after = Weather(wind_m_s=w.wind_m_s)  # the snow has stopped: the cover alone
    cpu = Renderer(160, 90, backend="cpu").render(street, dataclasses.replace(after, snow_cover=cover))
    gpu = Renderer(160, 90, backend="gpu").render(street, dataclasses.replace(after, snow_cover=cover))
    assert sorted(gpu.layers) == ["snow_depth_m"]
    # while it snows, the flakes and their haze are drawn over it too
    falling = Renderer(160, 90, backend="gpu").render(street, dataclasses.replace(w, snow_cover=cover))
    assert sorted(falling.layers) == ["snow_alpha", "snow_depth_m", "transmittance"]
    # f32 rounding may move a silhouette by a pixel (as tests/test_render.py allows)
    assert np.mean(np.abs(cpu.rgb - gpu.rgb) > 1e-3) <= 0.005
    assert np.mean(cpu.layers["snow_depth_m"] != gpu.layers["snow_depth_m"]) <= 0.005
    assert (cpu.layers["snow_depth_m"] > 0).mean() > 0.2


def test_a_sequence_carries_the_cover_in_every_frame() -> None:
    r = Renderer(48, 27, backend="cpu")
    w = Weather(snow_rate_mm_h=2.0)
    cover = snow.accumulate(scenes.street(), w, duration_s=HOUR, resolution_m=1.0)
    one = r.render(scenes.street(), dataclasses.replace(w, snow_cover=cover), time_s=0.5)
    frames = list(r.render_sequence(scenes.street(), dataclasses.replace(w, snow_cover=cover), n_frames=2, fps=2.0))
    assert np.array_equal(frames[1].rgb, one.rgb) and np.array_equal(frames[1].layers["snow_depth_m"], one.layers["snow_depth_m"])
    codes = list(r.render_sequence_srgb8(scenes.street(), dataclasses.replace(w, snow_cover=cover), n_frames=2, fps=2.0))
    np.testing.assert_array_equal(codes[1], io.to_srgb8(one.rgb))


def test_the_cover_is_a_weather_field_and_the_old_keyword_warns() -> None:
    # Weather(snow_cover=...) is the way; the render calls' snow_cover= keyword still works for
    # one release, with a DeprecationWarning naming the new way at the caller's line.
    r = Renderer(48, 27, backend="cpu")
    street = scenes.street()
    w = Weather(snow_rate_mm_h=2.0)
    cover = snow.accumulate(street, w, duration_s=HOUR, resolution_m=1.0)
    covered = dataclasses.replace(w, snow_cover=cover)
    assert covered.snow_cover is cover and covered == dataclasses.replace(w, snow_cover=cover)
    want = r.render(street, covered)
    assert want.layers["snow_depth_m"].max() > 0.0
    with pytest.warns(DeprecationWarning, match=r"snow_cover= is deprecated: .*Weather\(snow_cover=cover\)") as record:
        got = r.render(street, w, snow_cover=cover)
    assert [x.filename for x in record] == [__file__]
    np.testing.assert_array_equal(got.rgb, want.rgb)
    np.testing.assert_array_equal(got.layers["snow_depth_m"], want.layers["snow_depth_m"])
    with pytest.warns(DeprecationWarning, match="snow_cover= is deprecated"):
        np.testing.assert_array_equal(r.render_srgb8(street, w, snow_cover=cover), r.render_srgb8(street, covered))
    with pytest.warns(DeprecationWarning, match="snow_cover= is deprecated"):
        frames = list(r.render_sequence(street, w, n_frames=1, snow_cover=cover))
    np.testing.assert_array_equal(frames[0].rgb, want.rgb)
    with pytest.warns(DeprecationWarning, match="snow_cover= is deprecated"):
        codes = list(r.render_sequence_srgb8(street, w, n_frames=1, snow_cover=cover))
    np.testing.assert_array_equal(codes[0], io.to_srgb8(want.rgb))
    photo8 = PhotoScene(np.full((27, 48, 3), 120, np.uint8), depth_m=np.full((27, 48), 30.0, np.float32))
    assert r.fuses_srgb8(photo8, w) and not r.fuses_srgb8(photo8, covered)
    with pytest.warns(DeprecationWarning, match="snow_cover= is deprecated"):
        assert not r.fuses_srgb8(photo8, w, cover)
    other = snow.accumulate(street, w, duration_s=HOUR, resolution_m=2.0)
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match="two covers"):
        r.render(street, covered, snow_cover=other)


# The snow's sparkle (skyfall_core::snow::cover::sparkle), its constants written again from
# their sources: ice facets 0.2 mm across tiling the surface, their normals uniform over the
# hemisphere; ice's index 1.311 at 550 nm (Warren & Brandt 2008); the sun's radius 0.2666 deg.
FACET_M, ICE_N, SUN_R = 2.0e-4, 1.311, math.radians(0.2666)


def _fresnel(c: np.ndarray) -> np.ndarray:
    """Unpolarised Fresnel reflectance on ice at incidence cosine ``c``."""
    t = np.sqrt(1.0 - (1.0 - c**2) / ICE_N**2)
    rs = (c - ICE_N * t) / (c + ICE_N * t)
    rp = (t - ICE_N * c) / (t + ICE_N * c)
    return 0.5 * (rs**2 + rp**2)


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_sunlit_snow_sparkles_as_many_facets_as_mirror_the_sun(backend: str) -> None:
    # Level snow 3 cm deep under a sun 35 deg up, seen from 1.6 m at 40 deg down. Two frames
    # whose suns differ in illuminance alone: their difference is the sun's part of the
    # light, 0.85 (n.l) dE per pixel, plus the glints' (the sky's part cancels). A 5 x 5
    # median of it is the Lambertian part (the glints are sparse); what lies above is the
    # glints. A pixel of footprint A holds N = (A / FACET^2) r^2 / 8 glinting facets on
    # average: the number of pixels with a glint is sum(1 - e^(-N)) (4 standard deviations),
    # and their light is sum over pixels of R(h.v)(h.v) / (8 n.v) per unit of the sun's
    # illuminance, within 4 standard deviations of its sampling (a few per cent).
    from scipy import ndimage  # type: ignore[import-untyped]

    r = Renderer(320, 180, backend=backend)
    cam = scenes.Camera((0.0, 1.6, 0.0), pitch_deg=-40.0, vertical_fov_deg=50.0)
    scene = scenes.empty(camera=cam)
    cover = _dusted(0.03)
    sunny = dict(sky=12, sun_elevation_deg=35.0, sun_azimuth_deg=180.0, snow_cover=cover)
    lo = r.render(scene, Weather(sun_illuminance_lux=40000.0, **sunny))
    hi = r.render(scene, Weather(sun_illuminance_lux=80000.0, **sunny))
    d = (hi.rgb - lo.rgb)[..., 1].astype(np.float64)
    base = ndimage.median_filter(d, size=5, mode="nearest")
    ground = np.isfinite(lo.depth_m)
    inner = ground & ndimage.binary_erosion(ground, iterations=3)
    ratio = (d - base) / base
    glints = inner & (ratio > 1e-3)
    # The expectation per pixel, from the geometry written again.
    fx, fy, cx, cy = cam.with_resolution(r.width, r.height).intrinsics()
    yy, xx = np.mgrid[0 : r.height, 0 : r.width] + 0.5
    rays = np.stack([(xx - cx) / fx, -(yy - cy) / fy, -np.ones_like(xx)], axis=-1) @ np.asarray(cam.rotation).T
    v = -rays / np.linalg.norm(rays, axis=-1, keepdims=True)
    el = math.radians(35.0)
    l = np.asarray(Weather(**sunny).sun_direction)  # towards the sun (the core's convention)
    assert l[1] == pytest.approx(math.sin(el), rel=1e-6)
    fp = _footprint_m(np.where(ground, lo.depth_m, 1.0), cam, r)
    count = (fp**2 / FACET_M**2) * SUN_R**2 / 8.0
    p_glint = 1.0 - np.exp(-count)
    want_n = p_glint[inner].sum()
    sd_n = math.sqrt((p_glint * (1.0 - p_glint))[inner].sum())
    assert want_n > 100
    assert abs(glints.sum() - want_n) < 4.0 * sd_n, (glints.sum(), want_n, sd_n)
    # Their light, over the sun's Lambertian light 0.85 sin(el), per pixel: its expectation
    # R(h.v)(h.v) / (8 n.v) / (0.85 sin(el)); each pixel's draw carries N / (1 - e^-N) glints
    # with probability 1 - e^-N, so the sum's variance is sum m^2 (1 - p) / p.
    h = v + l
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    hv = np.clip(np.sum(h * v, axis=-1), 0.0, 1.0)
    m = (_fresnel(hv) * hv / (8.0 * v[..., 1]) / (0.85 * math.sin(el)))[inner]
    want = m.sum()
    sd = math.sqrt((m**2 * (1.0 - p_glint[inner]) / p_glint[inner]).sum())
    got = np.where(glints, ratio, 0.0)[inner].sum()
    assert abs(got - want) < 4.0 * sd, (got, want, sd)
    # Without a sun nothing sparkles: overcast snow is flat, the same bits as before.
    flat = r.render(scene, Weather(snow_cover=cover)).rgb[..., 1]
    assert np.all(np.abs(flat - ndimage.median_filter(flat, size=5, mode="nearest"))[inner] < 1e-3 * flat[inner])
