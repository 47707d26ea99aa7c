//! Snow the wind moves after it has landed: saltation from where the wind is strong into where
//! it is sheltered, the lee of walls and boxes.
//!
//! **How much moves.** Over level snow the wind `U` (taken at 10 m, z₀ = [`SNOW_Z0_M`]) has
//! the friction velocity u* = κ U / ln(10 m / z₀) (κ = 0.4); among buildings the wind a cell
//! feels is the canopy's share at its height ([`super::wind::Canopy::wind_share`]). Fresh dry
//! snow starts to move at u*_t = [`THRESHOLD_FRICTION_M_S`] (0.07–0.25 m/s for fresh snow, the
//! range Pomeroy & Gray quote; 0.15 m/s gives 4.3 m/s at 10 m, at the low end of the 4–11 m/s
//! Li & Pomeroy measured for dry snow, *Estimates of threshold wind speeds for snow transport
//! using meteorological data*, J. Appl. Meteor. 36, 1997). Above it the saltating snow carries,
//! per metre across the wind, Pomeroy & Gray's flux (*Saltation of snow*, Water Resources
//! Research 26(7), 1990): Q = 0.68 m/s · ρ_air u*_t (u*² − u*_t²) / (u* g) kg m⁻¹ s⁻¹.
//! A 10 m/s wind carries 5.7 g m⁻¹ s⁻¹, 20 kg per metre across it per hour.
//!
//! **Where it stops.** Behind a crest the wind separates: Werner's cellular dune model
//! (B. T. Werner, *Eolian dunes: computer simulations and attractor interpretation*, Geology 23,
//! 1995) takes a shadow zone below a line descending at [`SHADOW_ANGLE_DEG`] downwind of every
//! point of the surface, where nothing is eroded and what arrives is laid down. Here the zone is
//! the cover's own shadow buffer rendered along that line ([`super::shadow::ShadowBuffer`]):
//! a cell in it feels no wind.
//!
//! **The step.** The flux is carried cell to cell along the wind, in a first-order upwind
//! finite-volume sweep (each cell after its upwind neighbours): a cell receives what crosses its
//! upwind sides, and sends on across its downwind sides the flux relaxed toward its own
//! capacity over [`SALTATION_LENGTH_M`], q_out = C + (q_in − C)·e^(−ℓ/L) (ℓ the wind's mean path
//! across the cell), eroding at most the snow it holds; the difference stays in the cell. The
//! flux passes over walls (the wind lifts the snow over them) and into the lee, where the
//! capacity is zero and it settles. Across the grid's upwind edge a cell receives its own
//! capacity if it holds snow (the same snowfield continues upwind); across the downwind edge
//! the flux leaves. Mass is exact: what lies changes by what came in minus what left
//! ([`Moved`]), to rounding.

use super::heightfield::Grid;
use super::shadow::ShadowBuffer;
use super::wind::Canopy;
use crate::error::{Result, try_filled};

/// Threshold friction velocity of fresh dry snow, m/s.
pub const THRESHOLD_FRICTION_M_S: f64 = 0.15;
/// Aerodynamic roughness of a snow surface, m (Pomeroy & Gray: 1e-4 to 1e-3).
pub const SNOW_Z0_M: f64 = 1e-4;
/// The height the wind is given at, m.
pub const REFERENCE_HEIGHT_M: f64 = 10.0;
/// The distance over which the saltating flux adapts to the wind it meets, m (a few of snow's
/// saltation hops, which are 0.1–1 m long).
pub const SALTATION_LENGTH_M: f64 = 1.0;
/// The slope below which a crest's lee is sheltered, degrees (Werner 1995).
pub const SHADOW_ANGLE_DEG: f64 = 15.0;
/// Von Kármán's constant.
const KARMAN: f64 = 0.4;
/// Density of air, kg/m³ (sea level, 0 °C: 1.29; the snow's temperatures lie near it).
const AIR_KG_M3: f64 = 1.29;
/// Gravity, m/s².
const GRAVITY_M_S2: f64 = 9.81;
/// Pomeroy & Gray's coefficient, m/s.
const POMEROY_GRAY_M_S: f64 = 0.68;

/// The friction velocity of a wind `wind_m_s` (at 10 m) over snow, m/s.
pub fn friction_velocity_m_s(wind_m_s: f64) -> f64 {
    KARMAN * wind_m_s / (REFERENCE_HEIGHT_M / SNOW_Z0_M).ln()
}

/// The wind at 10 m at which fresh snow starts to move, m/s.
pub fn threshold_wind_m_s() -> f64 {
    THRESHOLD_FRICTION_M_S * (REFERENCE_HEIGHT_M / SNOW_Z0_M).ln() / KARMAN
}

/// Pomeroy & Gray's saltation flux at friction velocity `u_star_m_s`, kg per metre across the
/// wind per second (0 below the threshold).
pub fn saltation_flux_kg_m_s(u_star_m_s: f64) -> f64 {
    let ut = THRESHOLD_FRICTION_M_S;
    if u_star_m_s.is_nan() || u_star_m_s <= ut {
        return 0.0;
    }
    POMEROY_GRAY_M_S * AIR_KG_M3 * ut * (u_star_m_s * u_star_m_s - ut * ut)
        / (u_star_m_s * GRAVITY_M_S2)
}

/// What one step moved across the grid's edges, kg.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Moved {
    /// Blown in across the upwind edge.
    pub in_kg: f64,
    /// Blown out across the downwind edge.
    pub out_kg: f64,
}

/// Whether a wind of horizontal speed `speed_m_s` above the roofs moves any snow.
pub fn moves(speed_m_s: f64) -> bool {
    saltation_flux_kg_m_s(friction_velocity_m_s(speed_m_s)) > 0.0
}

/// One step of `dt_s` of saltation in the horizontal wind `wind_m_s` (x, z) over the cover
/// `depth_m` on `base_m` (snow of `density_kg_m3`), in place.
#[allow(clippy::too_many_arguments)]
pub fn redistribute(
    grid: &Grid,
    base_m: &[f64],
    depth_m: &mut [f64],
    canopy: &Canopy,
    wind_m_s: [f64; 2],
    density_kg_m3: f64,
    dt_s: f64,
) -> Result<Moved> {
    let speed = wind_m_s[0].hypot(wind_m_s[1]);
    let mut moved = Moved::default();
    if !moves(speed) {
        return Ok(moved);
    }
    let e = [wind_m_s[0] / speed, wind_m_s[1] / speed];
    let (ax, az) = (e[0].abs(), e[1].abs());
    let (nx, nz, sp) = (grid.nx, grid.nz, grid.spacing_m);
    let n = grid.cells();
    let mut top = try_filled("snow drift", n, 0.0f64)?;
    for ((t, &b), &d) in top.iter_mut().zip(base_m).zip(depth_m.iter()) {
        *t = b + d;
    }
    let run = 1.0 / SHADOW_ANGLE_DEG.to_radians().tan();
    let shelter = ShadowBuffer::render(grid, &top, [e[0] * run, e[1] * run])?;
    // Capacity per cell, kg per metre across the wind per second.
    let mut cap = try_filled("snow drift", n, 0.0f64)?;
    for k in 0..nz {
        for i in 0..nx {
            let c = k * nx + i;
            if base_m[c].is_nan() || !shelter.lit(grid.centre(i, k), top[c]) {
                continue;
            }
            let u = speed * canopy.wind_share(top[c]);
            cap[c] = saltation_flux_kg_m_s(friction_velocity_m_s(u));
        }
    }
    let cell_kg = density_kg_m3 * sp * sp;
    let width = sp * (ax + az);
    let keep = (-sp / ((ax + az) * SALTATION_LENGTH_M)).exp();
    let share_x = ax / (ax + az);
    // Flux out across each cell's downwind x and z sides, kg/s.
    let mut fx = try_filled("snow drift", n, 0.0f64)?;
    let mut fz = try_filled("snow drift", n, 0.0f64)?;
    let (east, south) = (e[0] >= 0.0, e[1] >= 0.0);
    // Upwind cells first: the j-th row (column) of the sweep counted from the upwind side.
    let upwind_first = |j: usize, m: usize, forward: bool| if forward { j } else { m - 1 - j };
    for kk in 0..nz {
        let k = upwind_first(kk, nz, south);
        for ii in 0..nx {
            let i = upwind_first(ii, nx, east);
            let c = k * nx + i;
            if base_m[c].is_nan() {
                continue;
            }
            let up_x = if east {
                i.checked_sub(1)
            } else {
                (i + 1 < nx).then_some(i + 1)
            };
            let up_z = if south {
                k.checked_sub(1)
            } else {
                (k + 1 < nz).then_some(k + 1)
            };
            let held = depth_m[c] * cell_kg;
            let edge = |share: f64| {
                if held > 0.0 {
                    cap[c] * width * share
                } else {
                    0.0
                }
            };
            let from_x = match up_x {
                Some(j) => fx[k * nx + j],
                None => {
                    let f = edge(share_x);
                    moved.in_kg += f * dt_s;
                    f
                }
            };
            let from_z = match up_z {
                Some(j) => fz[j * nx + i],
                None => {
                    let f = edge(1.0 - share_x);
                    moved.in_kg += f * dt_s;
                    f
                }
            };
            let q_in = from_x + from_z;
            let c_out = cap[c] * width;
            let mut q_out = c_out + (q_in - c_out) * keep;
            if q_out > q_in {
                q_out = q_in + ((q_out - q_in) * dt_s).min(held) / dt_s;
            }
            let mut changed = q_in != q_out;
            let mut kg = held + (q_in - q_out) * dt_s;
            let (mut ox, mut oz) = (q_out * share_x, q_out * (1.0 - share_x));
            let down_x = if east {
                (i + 1 < nx).then_some(c + 1)
            } else {
                c.checked_sub(1).filter(|_| i > 0)
            };
            let down_z = if south {
                (k + 1 < nz).then_some(c + nx)
            } else {
                (k > 0).then(|| c - nx)
            };
            for (down, out) in [(down_x, &mut ox), (down_z, &mut oz)] {
                match down {
                    None => moved.out_kg += *out * dt_s,
                    Some(j) if base_m[j].is_nan() => {
                        // Nothing there to carry it: it settles here.
                        kg += *out * dt_s;
                        changed |= *out != 0.0;
                        *out = 0.0;
                    }
                    Some(_) => {}
                }
            }
            fx[c] = ox;
            fz[c] = oz;
            if changed {
                depth_m[c] = (kg / cell_kg).max(0.0);
            }
        }
    }
    Ok(moved)
}
