//! The cover's time steps (see [`super`] for the method): shadow buffer, flux, random factor,
//! smoothing.

use super::SnowCover;
use super::drift::{Moved, redistribute};
use super::heightfield::HeightField;
use super::shadow::ShadowBuffer;
use super::wind::{Canopy, FallPaths};
use crate::error::{Error, Param, Result, check_cancel, try_filled};
use crate::physics::snow::{Snowfall, WATER_KG_M3, snow_depth_rate_m_s};
use crate::ranges;
use rayon::prelude::*;
use std::sync::atomic::AtomicBool;

/// Most steps a run may take.
pub const MAX_STEPS: usize = 100_000;

/// The key of the random factor's stream.
const ROUGHNESS_KEY: u64 = 0x736e_6f77_636f_7672; // "snowcovr"

/// A run's time and randomness.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoverParams {
    /// How long it snows, s.
    pub duration_s: f64,
    /// The step, s (a run takes ceil(duration / dt) equal steps; dt > duration: one).
    pub dt_s: f64,
    /// Amplitude of the paper's random factor r = 1 + roughness·u, u in [−1, 1].
    pub roughness: f64,
    /// Seeds r.
    pub seed: u64,
    /// The gusts' standard deviation per horizontal component, as a share of the mean wind
    /// ([`super::wind`]; 0: the flakes' sizes alone spread the fall directions).
    pub turbulence: f64,
    /// Whether the wind moves lying snow ([`super::drift`]; only above its threshold).
    pub redistribute: bool,
}

/// What the cover takes of a frame's weather (`weather::Weather` converts itself, validated,
/// so this module need not import the weather that imports the snow).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoverWeather {
    /// Snowfall as liquid water, mm/h.
    pub snow_rate_mm_h: f64,
    /// The wind, m/s (x, y, z).
    pub wind_m_s: [f64; 3],
    /// The cover's bulk density, kg/m³.
    pub snow_density_kg_m3: f64,
}

/// The snow's mean fall velocity under `weather`, m/s: the wind, and the mass-weighted fall
/// speed of its flakes downward ([`Snowfall::mean_fall_speed_m_s`]).
pub fn fall_velocity_m_s(weather: &CoverWeather) -> [f64; 3] {
    let vf = Snowfall::new(weather.snow_rate_mm_h).mean_fall_speed_m_s();
    let w = weather.wind_m_s;
    [w[0], w[1] - vf, w[2]]
}

/// The cover `weather`'s snow lays on `field` over `params.duration_s` (see [`super`]);
/// `cancel` stops it between steps. `weather` is a [`CoverWeather`] or anything that converts
/// to one, checked (a `&weather::Weather`, validated whole).
pub fn accumulate<W: TryInto<CoverWeather, Error = Error>>(
    field: HeightField,
    weather: W,
    params: &CoverParams,
    cancel: Option<&AtomicBool>,
) -> Result<SnowCover> {
    let weather = &weather.try_into()?;
    ranges::DURATION_S.check(params.duration_s)?;
    ranges::DT_S.check(params.dt_s)?;
    ranges::ROUGHNESS.check(params.roughness)?;
    ranges::TURBULENCE.check(params.turbulence)?;
    let grid = field.grid;
    let n = grid.cells();
    if field.base_m.len() != n {
        return Err(Error::Length {
            param: Param {
                name: "base_m",
                index: None,
            },
            len: field.base_m.len(),
            expected: n,
        });
    }
    let rate = weather.snow_rate_mm_h;
    let v = fall_velocity_m_s(weather);
    let steps = if rate > 0.0 && params.duration_s > 0.0 {
        let k = (params.duration_s / params.dt_s).ceil();
        if k > MAX_STEPS as f64 {
            return Err(Error::Unusable {
                param: Param {
                    name: "dt_s",
                    index: None,
                },
                value: params.dt_s,
                message: format!(
                    "s gives {k} steps over duration_s = {} s, more than {MAX_STEPS}: take longer steps",
                    params.duration_s
                ),
            });
        }
        k.max(1.0) as usize
    } else {
        0
    };
    if steps > 0 && v[1] >= 0.0 {
        return Err(Error::Unusable {
            param: Param {
                name: "wind_m_s",
                index: Some(1),
            },
            value: weather.wind_m_s[1],
            message: format!(
                "m/s lifts the snow faster than it falls ({:.3} m/s): none reaches the ground",
                v[1] - weather.wind_m_s[1]
            ),
        });
    }
    let dt = if steps > 0 {
        params.duration_s / steps as f64
    } else {
        params.dt_s
    };
    let mut depth = try_filled("snow cover", n, 0.0f64)?;
    let r = roughness_field(n, params.roughness, params.seed)?;
    let mut a = try_filled("snow cover", n, 0.0f64)?;
    let mut inc = try_filled("snow cover", n, 0.0f64)?;
    let mut top = try_filled("snow cover", n, 0.0f64)?;
    let rho_s = weather.snow_density_kg_m3;
    let flat_m = snow_depth_rate_m_s(rate, rho_s) * dt;
    let paths = FallPaths::new(rate, weather.wind_m_s, params.turbulence);
    let canopy = if paths.windy() {
        Canopy::of(&field, [v[0], v[2]])
    } else {
        Canopy::none(0.0)
    };
    let mut lifted = if paths.windy() {
        try_filled("snow cover", n, 0.0f64)?
    } else {
        Vec::new()
    };
    let (nx, sp) = (grid.nx, grid.spacing_m);
    let base = &field.base_m;
    let linked = |i: usize, j: usize| {
        let (b, c) = (base[i], base[j]);
        !b.is_nan() && !c.is_nan() && (b - c).abs() <= sp
    };
    let mut fallen_m = 0.0f64;
    let mut moved = Moved::default();
    for step in 0..steps {
        if let Some(c) = cancel {
            check_cancel(c, "snow.accumulate")?;
        }
        for (t, (&b, &d)) in top.iter_mut().zip(base.iter().zip(depth.iter())) {
            *t = b + d;
        }
        // 1: which paths reach each cell. In still air every cell is reached, straight down.
        let step_paths = paths.step(step);
        let shadows = if paths.windy() {
            for (g, &t) in lifted.iter_mut().zip(top.iter()) {
                *g = canopy.lift_m(t);
            }
            step_paths
                .par_iter()
                .map(|p| ShadowBuffer::render(&grid, &lifted, p.drift))
                .collect::<Result<Vec<_>>>()?
        } else {
            Vec::new()
        };
        // 2: the lit paths' flux through each cell, per unit of horizontal area, as a depth of
        // snow.
        a.par_chunks_mut(nx).enumerate().for_each(|(k, row)| {
            for (i, out) in row.iter_mut().enumerate() {
                let c = k * nx + i;
                *out = 0.0;
                if base[c].is_nan() {
                    continue;
                }
                if shadows.is_empty() {
                    *out = flat_m;
                    continue;
                }
                let g = |lo: Option<usize>, hi: Option<usize>| {
                    let lo = lo.filter(|&j| linked(c, j));
                    let hi = hi.filter(|&j| linked(c, j));
                    let d = match (lo, hi) {
                        (Some(l), Some(h)) => (top[h] - top[l]) / (2.0 * sp),
                        (None, Some(h)) => (top[h] - top[c]) / sp,
                        (Some(l), None) => (top[c] - top[l]) / sp,
                        (None, None) => 0.0,
                    };
                    d.clamp(-1.0, 1.0)
                };
                let gx = g((i > 0).then(|| c - 1), (i + 1 < nx).then_some(c + 1));
                let gz = g((k > 0).then(|| c - nx), (k + 1 < grid.nz).then_some(c + nx));
                let share = canopy.wind_share(top[c]);
                let centre = grid.centre(i, k);
                let mut flux = 0.0;
                for (p, shadow) in step_paths.iter().zip(shadows.iter()) {
                    if shadow.lit(centre, lifted[c]) {
                        // The path's slope where it meets the cell: its drift times the wind's
                        // share there.
                        let s = [p.drift[0] * share, p.drift[1] * share];
                        let most = 1.0 + (s[0] * s[0] + s[1] * s[1]).sqrt();
                        flux += p.weight * (1.0 + s[0] * gx + s[1] * gz).clamp(0.0, most);
                    }
                }
                *out = flat_m * flux;
            }
        });
        // 3: the random factor, scaled to move snow without making any.
        let (mut sum, mut weighted) = (0.0f64, 0.0f64);
        for (&ai, &ri) in a.iter().zip(r.iter()) {
            sum += ai;
            weighted += ai * ri;
        }
        if sum <= 0.0 {
            continue;
        }
        let scale = sum / weighted;
        for ((x, &ai), &ri) in inc.iter_mut().zip(a.iter()).zip(r.iter()) {
            *x = ai * ri * scale;
        }
        // 4: each cell keeps a fifth of its increment and hands a fifth to each neighbour on
        // its surface (the shares of the others it keeps).
        a.par_chunks_mut(nx).enumerate().for_each(|(k, row)| {
            for (i, out) in row.iter_mut().enumerate() {
                let c = k * nx + i;
                let mut v = inc[c];
                for j in [
                    (i > 0).then(|| c - 1),
                    (i + 1 < nx).then_some(c + 1),
                    (k > 0).then(|| c - nx),
                    (k + 1 < grid.nz).then_some(c + nx),
                ]
                .into_iter()
                .flatten()
                {
                    if linked(c, j) {
                        v += (inc[j] - inc[c]) / 5.0;
                    }
                }
                *out = v;
            }
        });
        for (d, &x) in depth.iter_mut().zip(a.iter()) {
            *d += x;
        }
        fallen_m += sum;
        // 5: the wind moves what lies, where it is strong enough.
        if params.redistribute {
            let m = redistribute(&grid, base, &mut depth, &canopy, [v[0], v[2]], rho_s, dt)?;
            moved.in_kg += m.in_kg;
            moved.out_kg += m.out_kg;
        }
    }
    let area = grid.cell_area_m2();
    let lying_m: f64 = depth.iter().sum();
    let surface = base.iter().filter(|b| !b.is_nan()).count() as f64;
    Ok(SnowCover {
        fallen_kg: fallen_m * area * rho_s,
        blown_in_kg: moved.in_kg,
        blown_out_kg: moved.out_kg,
        canopy,
        lying_kg: lying_m * area * rho_s,
        open_sky_kg: rate * 1e-3 / 3600.0
            * WATER_KG_M3
            * surface
            * area
            * if steps > 0 { params.duration_s } else { 0.0 },
        open_depth_m: if steps > 0 {
            snow_depth_rate_m_s(rate, rho_s) * params.duration_s
        } else {
            0.0
        },
        field,
        depth_m: depth,
        steps,
        dt_s: dt,
        fall_velocity_m_s: v,
    })
}

/// The paper's r per cell: 1 + roughness·u, u uniform in [−1, 1] from the seed and the cell's
/// index alone.
fn roughness_field(n: usize, roughness: f64, seed: u64) -> Result<Vec<f64>> {
    let mut r = try_filled("snow cover", n, 1.0f64)?;
    if roughness > 0.0 {
        let stream = crate::seed::derive(seed, &[ROUGHNESS_KEY]);
        r.par_iter_mut().enumerate().for_each(|(c, x)| {
            let h =
                crate::seed::splitmix64(stream ^ (c as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
            let u = (h >> 11) as f64 / (1u64 << 53) as f64;
            *x = 1.0 + roughness * (2.0 * u - 1.0);
        });
    }
    Ok(r)
}
