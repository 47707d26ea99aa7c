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

#[test]
fn a_wall_in_slanted_wind_casts_a_bare_shadow_of_its_height_times_the_fall_slope() {
    let spacing = 0.25;
    let w = weather(2.0, [2.5, 0.0, 0.0]);
    let v = fall_velocity_m_s(&CoverWeather::try_from(&w).unwrap());
    let tan_fall = v[0] / -v[1];
    let length = 4.0 * tan_fall;
    assert!(length > 6.0 && length < 20.0, "{length}");
    let c = accumulate(wall_field(spacing), &w, &params(3600.0, 120.0, 0.1), None).unwrap();
    let g = c.field.grid;
    let open = c.open_depth_m;
    let row = g.nz / 2;
    let at = |i: usize| c.depth_m[row * g.nx + i];
    let x = |i: usize| g.centre(i, row)[0];
    let mut first_covered = None;
    for i in 0..g.nx {
        let xi = x(i);
        if xi < -2.0 * spacing {
            // upwind: full cover (the factor's ±10 % and one cell of smoothing)
            assert!(
                (at(i) / open - 1.0).abs() < 0.15,
                "upwind x={xi}: {}",
                at(i)
            );
        } else if (spacing..2.0 - spacing).contains(&xi) {
            assert!((at(i) / open - 1.0).abs() < 0.15, "top x={xi}: {}", at(i));
        } else if xi > 2.0 + 2.0 * spacing && xi < 2.0 + length - 2.0 * spacing {
            assert_eq!(at(i), 0.0, "shadow x={xi}");
        }
        if xi > 2.0 && first_covered.is_none() && at(i) > 0.5 * open {
            first_covered = Some(xi);
        }
    }
    // The shadow's far end lies h·tan(fall angle) behind the wall, within two cells.
    let end = first_covered.unwrap() - 2.0;
    assert!((end - length).abs() <= 2.0 * spacing, "{end} vs {length}");
    // The lee of the wall is bare, the ground beyond the shadow covered.
    assert_eq!(at(g.cell_of(2.0 + 1.5 * spacing, 0.0).unwrap().0), 0.0);
    assert!(at(g.nx - 5) > 0.8 * open);
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
    assert!((c.lying_kg / c.fallen_kg - 1.0).abs() < 1e-12);
    let name = |e: crate::error::Error| e.to_string();
    let w = weather(1.0, [0.0; 3]);
    let bad = |p: CoverParams| name(accumulate(open_ground(1.0), &w, &p, None).unwrap_err());
    assert!(bad(params(3600.0, 0.0, 0.0)).starts_with("dt_s = 0.0 is outside"));
    assert!(bad(params(-1.0, 60.0, 0.0)).starts_with("duration_s = -1.0 is outside"));
    assert!(bad(params(f64::NAN, 60.0, 0.0)).starts_with("duration_s = NaN"));
    assert!(bad(params(3600.0, 60.0, 2.0)).starts_with("roughness = 2.0"));
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
    let cover = SnowCover {
        field,
        depth_m: vec![0.5; n],
        fallen_kg: 1.0,
        lying_kg: 1.0,
        open_sky_kg: 1.0,
        open_depth_m: 0.5,
        steps: 1,
        dt_s: 1.0,
        fall_velocity_m_s: [0.0, -1.0, 0.0],
    };
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
