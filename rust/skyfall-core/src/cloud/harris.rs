//! Harris & Lastra's illumination (2001), the accuracy reference and the speed baseline:
//! particles sorted along the light, nearest the sun first; each reads the light left at its
//! centre by those before it, I_k = (∏_{i<k} G_i(ρ_ik)) I₀, then adds its own log G to what
//! the particles after it read, as Harris' light-space frame buffer does. A fair CPU port:
//! one sort, then per particle one read and one insertion. The "buffer" is exact rather than
//! rasterised: particles already passed are kept in a 2D grid of cells across the light (half a
//! cut-off radius wide), and a read sums the footprints exp(−ρ²/r²) of those in the 5 × 5
//! cells around it, so the reference carries no pixel error. In sums of log G, so dense
//! clouds stay finite.

use super::light::{LightFrame, LightParticles};
use super::{CUTOFF_RADII, Cloud, exp_fast, sun_direction};
use crate::error::{Result, try_filled};
use crate::ranges;

/// Cells per side of the grid of passed particles, at most.
pub const MAX_GRID_CELLS: usize = 1024;

/// One passed particle as a read needs it.
#[derive(Clone, Copy)]
struct Passed {
    u: f64,
    v: f64,
    inv_r2: f64,
    cut2: f64,
    /// log G at the centre: −(1 − a f) τ.
    amp: f64,
}

/// Per-particle sunlight I_k by the sorted recurrence, in the unit of `sun_radiance`.
pub fn harris_illumination(cloud: &Cloud, sun: [f64; 3], sun_radiance: f64) -> Result<Vec<f64>> {
    let sun = sun_direction(sun)?;
    ranges::SUN_RADIANCE.check(sun_radiance)?;
    let frame = LightFrame::new(sun);
    let lp = LightParticles::new(cloud, &frame);
    let cut_max = cloud.radii_m.iter().copied().fold(0.0, f64::max) * CUTOFF_RADII;
    let span = lp.hi - lp.lo;
    let cell = (0.5 * cut_max).max(span.x.max(span.y) / MAX_GRID_CELLS as f64);
    let nx = ((span.x / cell).ceil() as usize).clamp(1, MAX_GRID_CELLS);
    let ny = ((span.y / cell).ceil() as usize).clamp(1, MAX_GRID_CELLS);
    let mut grid: Vec<Vec<Passed>> = try_filled("Harris' grid of particles", nx * ny, Vec::new())?;
    let cell_of = |x: f64, n: usize| ((x / cell).floor().max(0.0) as usize).min(n - 1);

    let amp = |k: usize| -cloud.attenuation_per_depth(k) * cloud.optical_depths[k];
    // Nearest the sun first; particles at the same depth in an order of their own values
    // (across the light, radius, attenuation; the index only between identical particles), so
    // the result does not depend on the input's order.
    let mut order: Vec<usize> = (0..cloud.len()).collect();
    order.sort_by(|&a, &b| {
        let (pa, pb) = (lp.centres[a], lp.centres[b]);
        pa.z.total_cmp(&pb.z)
            .then(pa.x.total_cmp(&pb.x))
            .then(pa.y.total_cmp(&pb.y))
            .then(cloud.radii_m[a].total_cmp(&cloud.radii_m[b]))
            .then(amp(a).total_cmp(&amp(b)))
            .then(a.cmp(&b))
    });
    let mut light = vec![0.0; cloud.len()];
    // Particles at exactly the same depth do not shadow each other (neither lies before the
    // other along the light): a group of ties all read before any is added.
    let mut start = 0;
    while start < order.len() {
        let z = lp.centres[order[start]].z;
        let end = start + order[start..].partition_point(|&k| lp.centres[k].z == z);
        for &k in &order[start..end] {
            let c = lp.centres[k] - lp.lo;
            let (cx, cy) = (cell_of(c.x, nx), cell_of(c.y, ny));
            let mut log_light = 0.0;
            for gy in cy.saturating_sub(2)..=(cy + 2).min(ny - 1) {
                for gx in cx.saturating_sub(2)..=(cx + 2).min(nx - 1) {
                    for p in &grid[gy * nx + gx] {
                        let (du, dv) = (c.x - p.u, c.y - p.v);
                        let rho2 = du * du + dv * dv;
                        if rho2 <= p.cut2 {
                            log_light += p.amp * exp_fast(-rho2 * p.inv_r2);
                        }
                    }
                }
            }
            light[k] = sun_radiance * log_light.exp();
        }
        for &k in &order[start..end] {
            let c = lp.centres[k] - lp.lo;
            let (cx, cy) = (cell_of(c.x, nx), cell_of(c.y, ny));
            let r = cloud.radii_m[k];
            grid[cy * nx + cx].push(Passed {
                u: c.x,
                v: c.y,
                inv_r2: 1.0 / (r * r),
                cut2: (CUTOFF_RADII * r).powi(2),
                amp: amp(k),
            });
        }
        start = end;
    }
    Ok(light)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_column_of_particles_multiplies_their_g() {
        // Five particles on the sun's ray: each sees the product of those above it.
        let n = 5;
        let cloud = Cloud::new(
            (0..n)
                .map(|i| [0.0, 100.0 - 10.0 * i as f64, 0.0])
                .collect(),
            vec![5.0; n],
            vec![0.5; n],
            vec![1.0; n],
            0.86,
        )
        .unwrap();
        let light = harris_illumination(&cloud, [0.0, 1.0, 0.0], 2.0).unwrap();
        let k = 0.5 * cloud.attenuation_per_depth(0);
        for (i, l) in light.iter().enumerate() {
            let want = 2.0 * (-k * i as f64).exp();
            assert!((l - want).abs() < 1e-9 * want, "{i}: {l} vs {want}");
        }
    }

    #[test]
    fn ties_in_depth_shadow_neither_way_whatever_the_input_order() {
        // Two particles side by side across the sun's ray at one height, 3 m apart, and one
        // below between them: the two see the full sun (neither lies before the other), the
        // one below their two footprints, G_i = exp(−k_i τ_i e^(−ρ²/r²)), ρ = 1.5 m, r = 5 m.
        let centres = vec![[-1.5, 100.0, 0.0], [1.5, 100.0, 0.0], [0.0, 90.0, 0.0]];
        let taus = vec![0.5, 0.8, 0.3];
        let cloud = Cloud::new(
            centres.clone(),
            vec![5.0; 3],
            taus.clone(),
            vec![1.0; 3],
            0.86,
        )
        .unwrap();
        let light = harris_illumination(&cloud, [0.0, 1.0, 0.0], 2.0).unwrap();
        let k = cloud.attenuation_per_depth(0);
        let foot = (-(1.5f64 * 1.5) / 25.0).exp();
        let below = 2.0 * (-k * (taus[0] + taus[1]) * foot).exp();
        assert!(
            (light[0] - 2.0).abs() < 1e-12 && (light[1] - 2.0).abs() < 1e-12,
            "{light:?}"
        );
        assert!(
            (light[2] - below).abs() < 1e-5 * below,
            "{} vs {below}",
            light[2]
        );
        // Every order of the input gives the same bits, particle by particle.
        for perm in [[1, 0, 2], [2, 1, 0], [0, 2, 1]] {
            let c = Cloud::new(
                perm.iter().map(|&i| centres[i]).collect(),
                vec![5.0; 3],
                perm.iter().map(|&i| taus[i]).collect(),
                vec![1.0; 3],
                0.86,
            )
            .unwrap();
            let l = harris_illumination(&c, [0.0, 1.0, 0.0], 2.0).unwrap();
            for (j, &i) in perm.iter().enumerate() {
                assert_eq!(l[j].to_bits(), light[i].to_bits(), "{perm:?}");
            }
        }
    }
}
