//! The cover against what is known independently: the open-ground depth R·t·ρ_w/ρ_snow, the
//! geometry of a box's wind shadow, exact mass bookkeeping.

use super::*;
use crate::scene::boxes::{BoxScene, SceneBox};
use crate::weather::Weather;
use glam::Vec3;

fn weather(rate: f64, wind: [f64; 3]) -> Weather {
    Weather {
        rain_rate_mm_h: 0.0,
        snow_rate_mm_h: rate,
        snow_density_kg_m3: 100.0,
        snow_near_m: 8.0,
        snow_opacity: crate::snow::streaks::SnowOpacity::Extinction,
        visibility_m: f64::INFINITY,
        sky_illuminance_lux: 10_000.0,
        wind_m_s: wind,
        rain_near_m: 5.0,
        rain_far_m: None,
        rain_diameters_mm: vec![1.0],
        rain_streaks: true,
        rain_method: crate::rain::drops::RainMethod::Billboards,
        rain_sheltered: true,
        rain_duration_s: Some(0.0),
        dry_s: 0.0,
        sky: crate::weather::SkySpec::Overcast,
        sun_deg: None,
        cloud_base_m: None,
        sun_illuminance_lux: None,
    }
}

fn params(duration_s: f64, dt_s: f64, roughness: f64) -> CoverParams {
    CoverParams {
        duration_s,
        dt_s,
        roughness,
        seed: 3,
        turbulence: 0.4,
        redistribute: true,
    }
}

fn open_ground(spacing: f64) -> HeightField {
    let scene = BoxScene::new(vec![], true, Vec3::splat(0.2)).unwrap();
    HeightField::from_boxes(
        &scene,
        Grid::covering([-8.0, -8.0], [8.0, 8.0], spacing).unwrap(),
    )
    .unwrap()
}

/// A wall 4 m high across the whole grid (x ∈ [0, 2], every z): the wind along +x.
fn wall_field(spacing: f64) -> HeightField {
    let wall = SceneBox {
        min_m: Vec3::new(0.0, 0.0, -50.0),
        max_m: Vec3::new(2.0, 4.0, 50.0),
        albedo: Vec3::splat(0.5),
    };
    let scene = BoxScene::new(vec![wall], true, Vec3::splat(0.2)).unwrap();
    HeightField::from_boxes(
        &scene,
        Grid::covering([-10.0, -3.0], [30.0, 3.0], spacing).unwrap(),
    )
    .unwrap()
}

#[test]
fn open_flat_ground_in_still_air_gets_rate_times_time_times_density_ratio() {
    // 1 mm/h of water at 100 kg/m³ for an hour: 1.000 cm of snow, every cell.
    let c = accumulate(
        open_ground(0.5),
        &weather(1.0, [0.0; 3]),
        &params(3600.0, 60.0, 0.0),
        None,
    )
    .unwrap();
    assert_eq!(c.steps, 60);
    for &d in &c.depth_m {
        assert!((d / 0.01 - 1.0).abs() < 1e-9, "{d}");
    }
    // With the random factor the cover is rough, its mean still the open depth (within 1 %:
    // exact up to rounding) and every cell within the factor's amplitude.
    let c = accumulate(
        open_ground(0.5),
        &weather(1.0, [0.0; 3]),
        &params(3600.0, 60.0, 0.2),
        None,
    )
    .unwrap();
    let mean = c.depth_m.iter().sum::<f64>() / c.depth_m.len() as f64;
    assert!((mean / 0.01 - 1.0).abs() < 1e-9, "{mean}");
    let spread = c
        .depth_m
        .iter()
        .fold(0.0f64, |m, &d| m.max((d / 0.01 - 1.0).abs()));
    assert!(spread > 1e-3 && spread < 0.2, "{spread}");
    assert!((c.open_depth_m - 0.01).abs() < 1e-15);
    assert!((c.fallen_kg / c.open_sky_kg - 1.0).abs() < 1e-9);
}

/// The flux share of the flakes falling faster than `v_m_s` (in still air), by quadrature of
/// N(D)·m(D)·v(D) over the melted diameters: the reference for the spread of fall paths.
fn flux_share_faster_than(rate: f64, v_m_s: f64) -> f64 {
    use crate::physics::snow::{Snowfall, flake_fall_speed_m_s, flake_mass_mg, flake_size_mm};
    let fall = Snowfall::new(rate);
    let n = 20_000;
    let dmax = fall.melted_max_mm();
    let (mut all, mut faster) = (0.0, 0.0);
    for j in 0..n {
        let d = (j as f64 + 0.5) / n as f64 * dmax;
        let v = flake_fall_speed_m_s(flake_size_mm(d));
        let f = fall.density_per_m3_mm(d) * flake_mass_mg(d) * v;
        all += f;
        if v > v_m_s {
            faster += f;
        }
    }
    faster / all
}

#[test]
fn a_wall_in_slanted_wind_shades_its_lee_as_the_flakes_speeds_and_the_canopy_say() {
    // A 4 m wall across a 40 m x 6 m grid, the wind 2.5 m/s along +x, no gusts: a flake
    // falling at v drifts 2.5/v per metre of lift, and the wall's top (lift G(4 m) under
    // Macdonald's profile) shades the ground out to 2.5 G / v behind it. So the ground x
    // behind the wall gets the flux share of the flakes faster than 2.5 G / x.
    let spacing = 0.25;
    let rate = 2.0;
    let w = weather(rate, [2.5, 0.0, 0.0]);
    let p = CoverParams {
        turbulence: 0.0,
        ..params(3600.0, 120.0, 0.0)
    };
    let c = accumulate(wall_field(spacing), &w, &p, None).unwrap();
    // The canopy: λ_f = 4 m x 6 m of wall / 240 m² of ground, a = 9.6 λ_f, h = 4 m.
    let a = 9.6 * (4.0 * 6.0) / (40.0 * 6.0);
    assert!((c.canopy.attenuation - a).abs() < 1e-12, "{:?}", c.canopy);
    assert!((c.canopy.height_m - 4.0).abs() < 1e-12);
    let lift = 4.0 / a * (1.0 - (-a).exp());
    assert!((c.canopy.lift_m(4.0) - lift).abs() < 1e-12);
    let g = c.field.grid;
    let open = c.open_depth_m;
    let row = g.nz / 2;
    let expect = |x: f64| {
        if x <= 0.0 {
            0.0
        } else {
            flux_share_faster_than(rate, 2.5 * lift / x)
        }
    };
    let mut checked = 0;
    for i in 0..g.nx {
        let xi = g.centre(i, row)[0];
        let d = c.depth_m[row * g.nx + i] / open;
        if xi < -spacing {
            // Upwind: level open ground, every path reaches it.
            assert!((d - 1.0).abs() < 1e-9, "upwind x={xi}: {d}");
        } else if xi > 2.0 + spacing {
            // Behind the wall, within the expectation a cell either side (the smoothing and
            // the cell's width) and the paths' sampling (240 speeds over the run).
            let x = xi - 2.0;
            let (e0, e1) = (expect(x - spacing), expect(x + spacing));
            assert!(
                d >= e0.min(e1) - 0.03 && d <= e0.max(e1) + 0.03,
                "lee x={xi}: {d} vs {e0}..{e1}"
            );
            checked += 1;
        }
    }
    assert!(checked > 100);
    // The lee is bare right behind the wall and covered far from it, with a soft edge between.
    assert_eq!(
        c.depth_m[row * g.nx + g.cell_of(2.0 + 1.5 * spacing, 0.0).unwrap().0],
        0.0
    );
    assert!(c.depth_m[row * g.nx + g.nx - 5] > 0.95 * open);
    let half = (0..g.nx)
        .filter(|&i| {
            let d = c.depth_m[row * g.nx + i] / open;
            g.centre(i, row)[0] > 2.0 && d > 0.1 && d < 0.9
        })
        .count();
    assert!(half >= 4, "a penumbra of {half} cells");
    // Gusts widen the penumbra: the same wall with turbulence 0.4 has more cells part-lit.
    let gusty = accumulate(wall_field(spacing), &w, &params(3600.0, 120.0, 0.0), None).unwrap();
    let half_gusty = (0..g.nx)
        .filter(|&i| {
            let d = gusty.depth_m[row * g.nx + i] / open;
            g.centre(i, row)[0] > 2.0 && d > 0.1 && d < 0.9
        })
        .count();
    assert!(half_gusty > half, "{half_gusty} vs {half}");
    // Still air: no shadow at all.
    let still = accumulate(
        wall_field(spacing),
        &weather(2.0, [0.0; 3]),
        &params(3600.0, 120.0, 0.0),
        None,
    )
    .unwrap();
    assert!(
        still
            .depth_m
            .iter()
            .all(|&d| (d / still.open_depth_m - 1.0).abs() < 1e-9)
    );
}

#[test]
fn snow_fallen_on_the_catchment_is_snow_lying_on_it() {
    let w = weather(5.0, [4.0, 0.0, 1.5]);
    let c = accumulate(wall_field(0.5), &w, &params(7200.0, 300.0, 0.5), None).unwrap();
    let lying: f64 = c.depth_m.iter().sum::<f64>() * c.field.grid.cell_area_m2() * 100.0;
    assert!(
        (lying / c.fallen_kg - 1.0).abs() < 1e-12,
        "{lying} {}",
        c.fallen_kg
    );
    assert!((c.lying_kg / c.fallen_kg - 1.0).abs() < 1e-12);
    // The wall's shadow holds snow back that the open sky let through: less fell.
    assert!(
        c.fallen_kg < 0.95 * c.open_sky_kg,
        "{} {}",
        c.fallen_kg,
        c.open_sky_kg
    );
    assert!(c.depth_m.iter().all(|d| d.is_finite() && *d >= 0.0));
}

#[test]
fn the_cover_is_deterministic_and_seeded() {
    let w = weather(3.0, [3.0, 0.0, -2.0]);
    let a = accumulate(wall_field(0.5), &w, &params(1800.0, 300.0, 0.3), None).unwrap();
    let b = accumulate(wall_field(0.5), &w, &params(1800.0, 300.0, 0.3), None).unwrap();
    let bits = |c: &SnowCover| c.depth_m.iter().map(|d| d.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&a), bits(&b));
    let other = CoverParams {
        seed: 4,
        ..params(1800.0, 300.0, 0.3)
    };
    let c = accumulate(wall_field(0.5), &w, &other, None).unwrap();
    assert_ne!(bits(&a), bits(&c));
}

#[test]
fn hard_cases_give_finite_covers_or_name_the_parameter() {
    // No snow: no cover.
    let c = accumulate(
        wall_field(0.5),
        &weather(0.0, [5.0, 0.0, 0.0]),
        &params(3600.0, 60.0, 0.1),
        None,
    )
    .unwrap();
    assert!(c.steps == 0 && c.depth_m.iter().all(|&d| d == 0.0) && c.fallen_kg == 0.0);
    // 100 mm/h in a 60 m/s gale, one step longer than the run: one step, finite.
    let c = accumulate(
        wall_field(0.5),
        &weather(100.0, [60.0, 0.0, 0.0]),
        &params(3600.0, 7200.0, 0.1),
        None,
    )
    .unwrap();
    assert_eq!(c.steps, 1);
    assert!(c.depth_m.iter().all(|d| d.is_finite() && *d >= 0.0));
    let budget = c.fallen_kg + c.blown_in_kg - c.blown_out_kg;
    assert!(c.blown_out_kg > 0.0 && (c.lying_kg / budget - 1.0).abs() < 1e-9);
    let name = |e: crate::error::Error| e.to_string();
    let w = weather(1.0, [0.0; 3]);
    let bad = |p: CoverParams| name(accumulate(open_ground(1.0), &w, &p, None).unwrap_err());
    assert!(bad(params(3600.0, 0.0, 0.0)).starts_with("dt_s = 0.0 is outside"));
    assert!(bad(params(-1.0, 60.0, 0.0)).starts_with("duration_s = -1.0 is outside"));
    assert!(bad(params(f64::NAN, 60.0, 0.0)).starts_with("duration_s = NaN"));
    assert!(bad(params(3600.0, 60.0, 2.0)).starts_with("roughness = 2.0"));
    let gusts = CoverParams {
        turbulence: 3.0,
        ..params(3600.0, 60.0, 0.0)
    };
    assert!(bad(gusts).starts_with("turbulence = 3.0"));
    assert!(bad(params(1e7, 1e-3, 0.0)).starts_with("dt_s = 0.001 s gives"));
    assert!(
        name(Grid::covering([0.0; 2], [1.0; 2], 0.0).unwrap_err())
            .starts_with("resolution_m = 0.0")
    );
    assert!(
        name(Grid::covering([0.0; 2], [1e5; 2], 0.01).unwrap_err())
            .starts_with("resolution_m = 0.01 m over")
    );
    let up = accumulate(
        open_ground(1.0),
        &weather(1.0, [0.0, 5.0, 0.0]),
        &params(60.0, 60.0, 0.0),
        None,
    );
    assert!(name(up.unwrap_err()).starts_with("wind_m_s[1] = 5.0 m/s lifts the snow"));
}

#[test]
fn the_cover_is_drawn_lifted_above_its_surface() {
    // A 0.5 m drift on a 2 m box top: seen from above at its top, from the side on its face.
    let b = SceneBox {
        min_m: Vec3::new(0.0, 0.0, 0.0),
        max_m: Vec3::new(4.0, 2.0, 4.0),
        albedo: Vec3::splat(0.5),
    };
    let scene = BoxScene::new(vec![b], false, Vec3::ZERO).unwrap();
    let field =
        HeightField::from_boxes(&scene, Grid::covering([0.0; 2], [4.0; 2], 0.5).unwrap()).unwrap();
    let n = field.grid.cells();
    let cover = drawn_cover(field, vec![0.5; n], 0.5);
    let r = SnowRender::boxes(&cover).unwrap();
    let (t, nrm, d) = r
        .trace(
            Vec3::new(2.1, 10.0, 2.1),
            Vec3::new(0.0, -1.0, 0.0),
            f32::INFINITY,
        )
        .unwrap();
    assert!(
        (t - 7.5).abs() < 1e-5 && nrm == Vec3::Y && d == 0.5,
        "{t} {nrm}"
    );
    // From the side, 2.3 m up (within the snow, above the box): the snow's face at x = 0;
    // 2.2 m up, less than half a cell above its base, the face is drawn as the surface's
    // relief (its slope, level here).
    let (t, nrm, _) = r
        .trace(Vec3::new(-3.0, 2.3, 1.1), Vec3::X, f32::INFINITY)
        .unwrap();
    assert!((t - 3.0).abs() < 1e-5 && nrm == -Vec3::X, "{t} {nrm}");
    let (t, nrm, _) = r
        .trace(Vec3::new(-3.0, 2.2, 1.1), Vec3::X, f32::INFINITY)
        .unwrap();
    assert!((t - 3.0).abs() < 1e-5 && nrm == Vec3::Y, "{t} {nrm}");
    // 1.5 m up the box's own wall is not snow; 2.6 m up passes over it.
    assert!(
        r.trace(Vec3::new(-3.0, 1.5, 1.1), Vec3::X, f32::INFINITY)
            .is_none()
    );
    assert!(
        r.trace(Vec3::new(-3.0, 2.6, 1.1), Vec3::X, f32::INFINITY)
            .is_none()
    );
    // Stopped by something nearer.
    assert!(r.trace(Vec3::new(-3.0, 2.2, 1.1), Vec3::X, 2.0).is_none());
}

/// A box 4 m x 4 m x 2 m high on open ground, in a 40 m x 24 m grid.
fn box_field(spacing: f64) -> HeightField {
    let b = SceneBox {
        min_m: Vec3::new(0.0, 0.0, -2.0),
        max_m: Vec3::new(4.0, 2.0, 2.0),
        albedo: Vec3::splat(0.5),
    };
    let scene = BoxScene::new(vec![b], true, Vec3::splat(0.2)).unwrap();
    HeightField::from_boxes(
        &scene,
        Grid::covering([-16.0, -12.0], [24.0, 12.0], spacing).unwrap(),
    )
    .unwrap()
}

#[test]
fn open_ground_in_any_wind_gets_the_open_depth_everywhere() {
    // No obstacle: every path reaches every cell (no canopy), and the saltating flux is the
    // same everywhere (what the upwind edge brings in, the downwind edge lets out).
    for wind in [
        [1.1, 0.0, 0.0],
        [3.0, 0.0, -2.0],
        [8.0, 0.0, 0.0],
        [-6.0, 0.0, 7.0],
    ] {
        let c = accumulate(
            open_ground(0.5),
            &weather(1.0, wind),
            &params(3600.0, 300.0, 0.0),
            None,
        )
        .unwrap();
        assert_eq!(c.canopy.attenuation, 0.0);
        for &d in &c.depth_m {
            assert!((d / 0.01 - 1.0).abs() < 1e-9, "{wind:?}: {d}");
        }
        let moves = super::drift::moves(wind[0].hypot(wind[2]));
        assert_eq!(moves, wind[0].hypot(wind[2]) > 5.0, "{wind:?}");
        assert_eq!(c.blown_in_kg > 0.0, moves);
        assert!((c.blown_in_kg - c.blown_out_kg).abs() <= 1e-9 * c.fallen_kg);
    }
}

#[test]
fn below_the_threshold_the_wind_moves_no_lying_snow() {
    // 4 m/s is under fresh snow's 4.3 m/s: redistribution on or off, the same bits.
    assert!((super::drift::threshold_wind_m_s() - 4.32).abs() < 0.01);
    let w = weather(2.0, [4.0, 0.0, 0.0]);
    let on = accumulate(box_field(0.5), &w, &params(3600.0, 300.0, 0.1), None).unwrap();
    let off = CoverParams {
        redistribute: false,
        ..params(3600.0, 300.0, 0.1)
    };
    let off = accumulate(box_field(0.5), &w, &off, None).unwrap();
    assert_eq!(on, off);
    assert_eq!(on.blown_in_kg, 0.0);
}

#[test]
fn saltation_keeps_mass_and_fills_the_lee_not_the_windward_side() {
    // Pomeroy & Gray's flux at u* = 0.3 m/s against the formula written out.
    let q = super::drift::saltation_flux_kg_m_s(0.3);
    assert!((q - 0.68 * 1.29 * 0.15 * (0.09 - 0.0225) / (0.3 * 9.81)).abs() < 1e-15);
    assert_eq!(super::drift::saltation_flux_kg_m_s(0.15), 0.0);
    let spacing = 0.25;
    let open_depth = 0.02 * 3.0;
    for sign in [1.0, -1.0] {
        let w = weather(2.0, [10.0 * sign, 0.0, 0.0]);
        let c = accumulate(
            box_field(spacing),
            &w,
            &params(3.0 * 3600.0, 600.0, 0.1),
            None,
        )
        .unwrap();
        // Mass: what lies is what fell plus what blew in minus what blew out.
        let budget = c.fallen_kg + c.blown_in_kg - c.blown_out_kg;
        assert!(
            (c.lying_kg / budget - 1.0).abs() < 1e-9,
            "{} {budget}",
            c.lying_kg
        );
        let lying: f64 = c.depth_m.iter().sum::<f64>() * c.field.grid.cell_area_m2() * 100.0;
        assert!((lying / c.lying_kg - 1.0).abs() < 1e-12);
        assert!(c.blown_in_kg > 0.0 && c.blown_out_kg > 0.0);
        // Mean depth over the box's width (|z| < 1.5 m) in a 2 m strip before it and behind it.
        let g = c.field.grid;
        let strip = |x0: f64, x1: f64| {
            let (mut sum, mut n) = (0.0, 0);
            for k in 0..g.nz {
                for i in 0..g.nx {
                    let [x, z] = g.centre(i, k);
                    if x > x0 && x < x1 && z.abs() < 1.5 {
                        sum += c.depth_m[k * g.nx + i];
                        n += 1;
                    }
                }
            }
            sum / n as f64 / open_depth
        };
        let (windward, lee) = if sign > 0.0 {
            (strip(-2.0, 0.0), strip(4.0, 6.0))
        } else {
            (strip(4.0, 6.0), strip(-2.0, 0.0))
        };
        // Windward: the flux passes on as it came, the cover is the open depth's (the
        // factor's ±10 %); lee: the roof's flux and what it carried settle.
        assert!((windward - 1.0).abs() < 0.15, "{sign}: windward {windward}");
        assert!(lee > 2.0, "{sign}: lee {lee}");
    }
}

#[test]
fn the_canopy_slows_the_wind_below_the_roofs_as_macdonald_writes() {
    // Rows of 10 m buildings 10 m deep with 10 m streets between, across the wind (x):
    // λ_f = 10 m of rise per 20 m of plan = 0.5 on the rows' interior, a = 9.6 λ_f.
    let mut boxes = vec![];
    for r in 0..4 {
        let x0 = -40.0 + 20.0 * r as f32;
        boxes.push(SceneBox {
            min_m: Vec3::new(x0, 0.0, -20.0),
            max_m: Vec3::new(x0 + 10.0, 10.0, 20.0),
            albedo: Vec3::splat(0.5),
        });
    }
    let scene = BoxScene::new(boxes, true, Vec3::splat(0.2)).unwrap();
    let field = HeightField::from_boxes(
        &scene,
        Grid::covering([-40.0, -20.0], [40.0, 20.0], 0.5).unwrap(),
    )
    .unwrap();
    let c = super::wind::Canopy::of(&field, [1.0, 0.0]);
    // Four 10 m x 40 m faces over 80 m x 40 m.
    assert!((c.frontal_area_index - 4.0 * 10.0 * 40.0 / (80.0 * 40.0)).abs() < 1e-12);
    assert!((c.attenuation - 9.6 * 0.5).abs() < 1e-12 && (c.height_m - 10.0).abs() < 1e-12);
    // u(z)/u_h = exp(a (z/h - 1)), and G its integral (checked by the trapezoid rule).
    let a = c.attenuation;
    for z in [0.0, 2.5, 5.0, 10.0, 14.0] {
        let u = if z < 10.0 {
            (a * (z / 10.0 - 1.0)).exp()
        } else {
            1.0
        };
        assert!((c.wind_share(z) - u).abs() < 1e-12, "{z}");
        let n = 100_000;
        let trapezoid: f64 = (0..n)
            .map(|j| {
                let (z0, z1) = (z * j as f64 / n as f64, z * (j + 1) as f64 / n as f64);
                0.5 * (c.wind_share(z0) + c.wind_share(z1)) * (z1 - z0)
            })
            .sum();
        assert!(
            (c.lift_m(z) - trapezoid).abs() < 1e-8,
            "{z}: {}",
            c.lift_m(z)
        );
    }
    // Along the rows only the ends face the wind.
    let along = super::wind::Canopy::of(&field, [0.0, 1.0]);
    assert!(along.attenuation < 0.3 * c.attenuation, "{along:?}");
}

#[test]
fn a_photos_specks_and_holes_are_cleaned_and_its_edges_kept() {
    // A floor (depth 5 m, 1 cm of snow) below a wall (depth 5 m too where they meet, then
    // nearer: same surface only within 2 %), with a hole in the floor's snow and specks on the
    // wall: the hole is filled with the floor's depth, the specks go, the edge stays.
    let (w, h) = (240usize, 60usize);
    let mut depth = vec![5.0f32; w * h];
    let mut snow = vec![0.0f32; w * h];
    for y in 0..h {
        for x in 0..w {
            if y >= 30 {
                snow[y * w + x] = 0.01;
            } else {
                depth[y * w + x] = 5.0 - 0.01 * (30 - y) as f32;
            }
        }
    }
    snow[45 * w + 100] = 0.0; // a hole
    snow[10 * w + 50] = 0.01; // a speck
    snow[12 * w + 51] = 0.008; // another
    let out = super::photo::clean_speckles(&snow, &depth, w, h).unwrap();
    assert!((out[45 * w + 100] - 0.01).abs() < 1e-8);
    assert_eq!(out[10 * w + 50], 0.0);
    assert_eq!(out[12 * w + 51], 0.0);
    // The floor's first row and the wall's last row keep what they had: the edge.
    for x in 0..w {
        assert_eq!(out[30 * w + x], 0.01, "{x}");
        assert_eq!(out[29 * w + x], 0.0, "{x}");
    }
    // Nothing else changed.
    let changed = (0..w * h).filter(|&i| out[i] != snow[i]).count();
    assert_eq!(changed, 3);
}

#[test]
fn a_noisy_photo_of_level_ground_is_covered_whole() {
    // A camera 1.6 m over level ground, pitched 20° down; the ground's depth with 0.5 % of
    // seeded noise (a depth map's), which tips single pixels' normals past 60° from up.
    use crate::scene::camera::Camera;
    use glam::Mat3;
    let (w, h) = (240u32, 135u32);
    let f = 200.0;
    let cam = Camera::new(
        w,
        h,
        [f, f, w as f32 / 2.0, h as f32 / 2.0],
        Vec3::new(0.0, 1.6, 0.0),
        Mat3::from_rotation_x(-20f32.to_radians()),
    )
    .unwrap();
    let mut depth = vec![f32::INFINITY; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            let d = cam.ray_direction(x, y);
            if d.y < -0.05 {
                let i = (y * w + x) as u64;
                let u = (crate::seed::splitmix64(i ^ 0x5eed) >> 40) as f32 / (1u64 << 24) as f32;
                depth[(y * w + x) as usize] = 1.6 / -d.y * (1.0 + 0.005 * (2.0 * u - 1.0));
            }
        }
    }
    let field = HeightField::from_depth_map(&cam, &depth, 0.25).unwrap();
    let c = accumulate(
        field,
        &weather(1.0, [0.0; 3]),
        &params(3600.0, 600.0, 0.0),
        None,
    )
    .unwrap();
    let per_pixel = super::photo::photo_depth_m(&c, &cam, &depth).unwrap();
    let ground: Vec<f32> = per_pixel
        .iter()
        .zip(&depth)
        .filter(|(_, d)| d.is_finite())
        .map(|(s, _)| *s)
        .collect();
    let covered = ground.iter().filter(|&&s| s > 0.0).count() as f64 / ground.len() as f64;
    let bare: Vec<(u32, u32)> = (0..w * h)
        .filter(|&i| depth[i as usize].is_finite() && per_pixel[i as usize] <= 0.0)
        .map(|i| (i % w, i / w))
        .take(40)
        .collect();
    assert!(covered > 0.995, "{covered} {bare:?}");
    let mut sorted = ground.clone();
    sorted.sort_by(f32::total_cmp);
    let median = sorted[sorted.len() / 2];
    assert!((median / 0.01 - 1.0).abs() < 1e-3, "{median}");
}

#[test]
fn what_a_pixel_shows_is_interpolated_over_its_own_surface() {
    // Ground (x < 2 m) and a 1 m box (x in [2, 4]) under 0.5 m cells: the ground's cells
    // carry a depth linear in x, 1 cm + 1 cm per m at their centres, but the first one none;
    // the box's 30 cm.
    let b = SceneBox {
        min_m: Vec3::new(2.0, 0.0, -1.0),
        max_m: Vec3::new(4.0, 1.0, 3.0),
        albedo: Vec3::splat(0.5),
    };
    let scene = BoxScene::new(vec![b], true, Vec3::splat(0.2)).unwrap();
    let field = HeightField::from_boxes(&scene, Grid::covering([0.0; 2], [4.0, 2.0], 0.5).unwrap())
        .unwrap();
    let g = field.grid;
    let depth_m: Vec<f64> = (0..g.cells())
        .map(|c| {
            let x = g.origin_m[0] + g.spacing_m * ((c % g.nx) as f64 + 0.5);
            match x {
                x if x > 2.0 => 0.3,
                x if x < 0.5 => 0.0,
                x => 0.01 + 0.01 * x,
            }
        })
        .collect();
    let cover = drawn_cover(field, depth_m, 0.0);
    let r = SnowRender::boxes(&cover).unwrap();
    let at = |x: f32, z: f32, y: f32| {
        let i = ((x - g.origin_m[0] as f32) / g.spacing_m as f32).floor() as usize;
        let k = ((z - g.origin_m[1] as f32) / g.spacing_m as f32).floor() as usize;
        r.surface_at(Vec3::new(x, y, z), i, k, y)
    };
    // Between the ground's snowy centres (x 0.75 .. 1.75): the linear depth, exactly.
    for x in [0.75f32, 0.9, 1.2, 1.5, 1.74] {
        for z in [0.3f32, 0.8, 1.6] {
            let (d, n) = at(x, z, 0.0);
            assert!((d - (0.01 + 0.01 * x)).abs() < 1e-6, "{x} {z} {d}");
            // The snow's top rises 1 cm per m: its normal leans back by that slope.
            let want = Vec3::new(-0.01, 1.0, 0.0).normalize();
            assert!(n.unwrap().abs_diff_eq(want, 1e-6), "{n:?}");
        }
    }
    // Towards the box (x 1.75 .. 2): the box's top is another surface, left out.
    let (d, _) = at(1.9, 1.0, 0.0);
    assert!((d - 0.0275).abs() < 1e-6, "{d}");
    // Towards the bare cell (x 0.25 .. 0.75): the depth thins out to none at its centre;
    // on the bare cell itself the ground takes it too.
    let (d, _) = at(0.5, 1.0, 0.0);
    assert!((d - 0.5 * 0.0175).abs() < 1e-6, "{d}");
    let (d, _) = at(0.25, 1.0, 0.0);
    assert!(d.abs() < 1e-7, "{d}");
    // The box's top: its own 30 cm up to its edge, the ground's cells left out.
    let (d, _) = at(2.1, 1.0, 1.0);
    assert!((d - 0.3).abs() < 1e-6, "{d}");
    // A ray from above onto the ground at x = 1.2 sees the interpolated depth.
    let (_, _, d) = r
        .trace(Vec3::new(1.2, 5.0, 0.8), Vec3::new(0.0, -1.0, 0.0), 5.0)
        .unwrap();
    assert!((d - 0.022).abs() < 1e-6, "{d}");
}

/// A cover of given depths over `field` for drawing (its bookkeeping placeholders: not a run's).
fn drawn_cover(field: HeightField, depth_m: Vec<f64>, open_depth_m: f64) -> SnowCover {
    SnowCover {
        field,
        depth_m,
        fallen_kg: 1.0,
        lying_kg: 1.0,
        blown_in_kg: 0.0,
        blown_out_kg: 0.0,
        canopy: wind::Canopy::none(0.0),
        open_sky_kg: 1.0,
        open_depth_m,
        steps: 1,
        dt_s: 1.0,
        fall_velocity_m_s: [0.0, -1.0, 0.0],
    }
}
