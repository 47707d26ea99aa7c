//! The multiplicative attenuation volume of Shimada, Shinya, Shiraishi & Harada: Γ, the share
//! of sunlight left at each voxel of a light-aligned box, Γ = exp(Σ log G_i) over the
//! particles nearer the sun.
//!
//! Built order-independently, as the paper proposes, but as splat + prefix sum rather than
//! the paper's shadow polygons: each particle adds its footprint log G_i(ρ) = −(1 − a_i f)
//! τ_i exp(−ρ²/r_i²) at its own depth (shared linearly by two slices, [`DEPTH_OFFSET_SLICES`]
//! slices behind its centre), then a prefix sum along the light carries it to every voxel
//! behind; Γ is the exponential of the sum. The cost is particles × footprint + voxels, not
//! particles × column length.
//!
//! Determinism: the sums are fixed point (2⁻²⁸ in log Γ, i64), so a voxel's sum is exact
//! whatever the order its particles arrive in: shuffling the particles gives the same bits.
//! The work is split by rows across the light (each row a v × w plane, one thread's), with the
//! particles binned to the rows their footprints touch.
//!
//! Layout: `gamma[(iu * R + iv) * R + iw]`, axis 2 (w) along the light's travel; voxel centres
//! at (i + ½)/R of the box. Samples outside the box clamp to its faces: across the light the
//! faces lie a cut-off beyond every particle (Γ ≈ 1 there), along it the far face holds the
//! whole cloud's shadow, which continues below the cloud.

use glam::DVec3;
use rayon::prelude::*;

use super::light::{LightFrame, LightParticles};
use super::{CUTOFF_RADII, Cloud, exp_fast, sun_direction};
use crate::error::{Error, Param, Result, try_filled_par};
use crate::ranges;

/// Slices exponentiated together before their transposed write.
const TILE: usize = 16;

/// Fixed-point steps per unit of log Γ.
const SCALE: f64 = (1u64 << 28) as f64;

/// How far behind its centre a particle's log G lands, in slices. Harris' recurrence is a
/// sharp step at each centre (a particle reads none of its own G, all of a neighbour's just
/// before it); sampled slices blur it over one slice. Half a slice behind balances the two:
/// measured on generated cumuli (0, 0.5, 0.75, 1, 1.5, 2 tried), it gives the least median
/// error against Harris and a mean log ratio within ±0.03.
pub const DEPTH_OFFSET_SLICES: f64 = 0.5;

/// The attenuation volume and its light-aligned box.
#[derive(Debug, Clone)]
pub struct AttenuationVolume {
    /// Voxels per side R.
    pub resolution: usize,
    /// Γ per voxel, R³ values (layout in the module's notes).
    pub gamma: Vec<f32>,
    /// Γ at the far face (the last voxel of each column along the light), R² values: where
    /// the light leaves the box. The same values as `gamma`'s, kept together so that a frame,
    /// which reads them per fragment, finds them in cache.
    pub exit: Vec<f32>,
    /// The box: world position of its corner and its three edges.
    pub grid: VolumeBox,
}

/// A light-aligned box: t ∈ [0, 1]³ maps to `origin + t.x·edges[0] + t.y·edges[1] + t.z·edges[2]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumeBox {
    /// World position of the corner t = 0, m.
    pub origin: DVec3,
    /// The box's edges (u, v, w directions times their lengths), m; orthogonal.
    pub edges: [DVec3; 3],
}

impl VolumeBox {
    /// From a 4 × 4 `world_from_volume` matrix (row-major; columns 0–2 the edges, column 3
    /// the origin), checked: finite, edges non-zero and orthogonal.
    pub fn from_matrix(m: &[f64]) -> Result<Self> {
        let bad = |message: String| Error::Invalid {
            param: Param {
                name: "world_from_volume",
                index: None,
            },
            message,
        };
        if m.len() != 16 {
            return Err(bad(format!(
                "must be a 4 x 4 matrix, got {} values",
                m.len()
            )));
        }
        if m.iter().any(|x| !x.is_finite()) {
            return Err(bad("must be finite".into()));
        }
        let col = |j: usize| DVec3::new(m[j], m[4 + j], m[8 + j]);
        let edges = [col(0), col(1), col(2)];
        for (i, e) in edges.iter().enumerate() {
            if e.length() < 1e-9 {
                return Err(bad(format!("edge {i} has zero length")));
            }
        }
        for (a, b) in [(0, 1), (0, 2), (1, 2)] {
            let c = edges[a].dot(edges[b]) / (edges[a].length() * edges[b].length());
            if c.abs() > 1e-6 {
                return Err(bad(format!("edges {a} and {b} are not orthogonal")));
            }
        }
        Ok(VolumeBox {
            origin: col(3),
            edges,
        })
    }

    /// The row-major 4 × 4 `world_from_volume` matrix.
    pub fn matrix(&self) -> [f64; 16] {
        let [a, b, c] = self.edges;
        let o = self.origin;
        [
            a.x, b.x, c.x, o.x, a.y, b.y, c.y, o.y, a.z, b.z, c.z, o.z, 0.0, 0.0, 0.0, 1.0,
        ]
    }

    /// The box coordinates t of a world point.
    #[inline]
    pub fn to_box(&self, p: DVec3) -> DVec3 {
        let d = p - self.origin;
        DVec3::new(
            d.dot(self.edges[0]) / self.edges[0].length_squared(),
            d.dot(self.edges[1]) / self.edges[1].length_squared(),
            d.dot(self.edges[2]) / self.edges[2].length_squared(),
        )
    }
}

/// Trilinear Γ at a world point, from a volume's values and box (clamped to the faces).
pub fn sample(gamma: &[f32], resolution: usize, grid: &VolumeBox, p: DVec3) -> f32 {
    let n = resolution;
    let t = grid.to_box(p);
    let top = (n - 1) as f64;
    let at = |x: f64| {
        let x = (x * n as f64 - 0.5).clamp(0.0, top);
        let i = (x.floor() as usize).min(n.saturating_sub(2));
        (i, (x - i as f64) as f32)
    };
    if n == 1 {
        return gamma[0];
    }
    trilinear(gamma, n, at(t.x), at(t.y), at(t.z))
}

/// The trilinear blend of an n³ grid (`gamma`, x slowest) in the cell at (i, j, k) with
/// fractions (fu, fv, fw): what [`sample`] and the frame's
/// [`super::frame::VolumeView::sample`] share once each has found its cell.
#[inline(always)]
pub(crate) fn trilinear(
    gamma: &[f32],
    n: usize,
    (i, fu): (usize, f32),
    (j, fv): (usize, f32),
    (k, fw): (usize, f32),
) -> f32 {
    let g = |a: usize, b: usize, c: usize| gamma[((i + a) * n + j + b) * n + k + c];
    let lerp = |a: f32, b: f32, f: f32| a + (b - a) * f;
    let plane = |a: usize| {
        lerp(
            lerp(g(a, 0, 0), g(a, 0, 1), fw),
            lerp(g(a, 1, 0), g(a, 1, 1), fw),
            fv,
        )
    };
    lerp(plane(0), plane(1), fu)
}

impl AttenuationVolume {
    /// Builds Γ for `cloud` lit from `sun` (towards the sun) at `resolution`³ voxels.
    pub fn build(cloud: &Cloud, sun: [f64; 3], resolution: usize) -> Result<Self> {
        let n = ranges::RESOLUTION.check(resolution as f64)? as usize;
        let mut gamma = try_filled_par("the attenuation volume", n * n * n, 0.0f32)?;
        let grid = Self::build_into(cloud, sun, n, &mut gamma)?;
        let mut exit = crate::error::try_with_capacity("the attenuation volume", n * n)?;
        exit.extend(gamma.chunks_exact(n).map(|column| column[n - 1]));
        Ok(AttenuationVolume {
            resolution: n,
            gamma,
            exit,
            grid,
        })
    }

    /// [`AttenuationVolume::build`] into the caller's `gamma` (`resolution`³ values, any
    /// contents), returning the box: a binding writes straight into its own array.
    pub fn build_into(
        cloud: &Cloud,
        sun: [f64; 3],
        resolution: usize,
        gamma: &mut [f32],
    ) -> Result<VolumeBox> {
        let sun = sun_direction(sun)?;
        ranges::RESOLUTION.check(resolution as f64)?;
        let n = resolution;
        if gamma.len() != n * n * n {
            return Err(Error::Length {
                param: Param {
                    name: "gamma",
                    index: None,
                },
                len: gamma.len(),
                expected: n * n * n,
            });
        }
        let frame = LightFrame::new(sun);
        let lp = LightParticles::new(cloud, &frame);
        let size = lp.hi - lp.lo;
        let step = size / n as f64;
        let grid = VolumeBox {
            origin: frame.to_world(lp.lo),
            edges: [frame.u * size.x, frame.v * size.y, frame.w * size.z],
        };
        // Prepared in order across u, so a row's particles are one run of `preps` (its loop
        // streams through memory); the sums are integers, so the order changes no bit.
        let mut order: Vec<usize> = (0..cloud.len()).collect();
        order.sort_by(|&a, &b| lp.centres[a].x.total_cmp(&lp.centres[b].x).then(a.cmp(&b)));
        let (preps, v_factors) = prepare(cloud, &lp, n, step, &order);

        // Particles binned (in index order) to the u-rows their footprints reach.
        let mut counts = vec![0usize; n + 1];
        for p in &preps {
            for r in p.u_lo..=p.u_hi {
                counts[r as usize + 1] += 1;
            }
        }
        for r in 0..n {
            counts[r + 1] += counts[r];
        }
        let mut fill = counts.clone();
        let mut members = vec![0u32; counts[n]];
        for (j, p) in preps.iter().enumerate() {
            for r in p.u_lo..=p.u_hi {
                let r = r as usize;
                members[fill[r]] = j as u32;
                fill[r] += 1;
            }
        }

        gamma.par_chunks_mut(n * n).enumerate().for_each_init(
            || (vec![0i64; n * n], vec![0.0f32; TILE * n]),
            |(plane, tile), (iu, out)| {
                // plane[k * n + iv]: depth-major, so a footprint's chord is contiguous.
                let uc = (iu as f64 + 0.5) * step.x;
                for &j in &members[counts[iu]..counts[iu + 1]] {
                    let p = &preps[j as usize];
                    deposit(
                        plane,
                        n,
                        step.y,
                        uc,
                        p,
                        &v_factors[p.v_off..p.v_off + p.v_len],
                    );
                }
                // The prefix sum along k, exponentiated TILE slices at a time and written
                // out transposed (out[iv * n + k]) a cache line per column.
                for k0 in (0..n).step_by(TILE) {
                    let rows = TILE.min(n - k0);
                    for t in 0..rows {
                        let k = k0 + t;
                        let (done, rest) = plane.split_at_mut(k * n);
                        let cur = &mut rest[..n];
                        if k > 0 {
                            for (c, p) in cur.iter_mut().zip(&done[(k - 1) * n..]) {
                                *c += *p;
                            }
                        }
                        for (o, &c) in tile[t * n..(t + 1) * n].iter_mut().zip(cur.iter()) {
                            *o = exp_fixed(c);
                        }
                    }
                    for (iv, col) in out.chunks_exact_mut(n).enumerate() {
                        for (t, o) in col[k0..k0 + rows].iter_mut().enumerate() {
                            *o = tile[t * n + iv];
                        }
                    }
                }
                plane.fill(0);
            },
        );
        Ok(grid)
    }

    /// Trilinear Γ at a world point.
    pub fn sample(&self, p: DVec3) -> f32 {
        sample(&self.gamma, self.resolution, &self.grid, p)
    }
}

/// A particle as the deposit needs it (box coordinates, m).
struct Prep {
    cu: f64,
    cv: f64,
    inv_r2: f64,
    cut2: f64,
    amp: f64,
    k0: usize,
    k1: usize,
    w0: f64,
    w1: f64,
    u_lo: i64,
    u_hi: i64,
    v_lo: usize,
    v_off: usize,
    v_len: usize,
}

/// Each particle's placement, and its footprint's factors exp(−Δv²/r²) across v (one pool).
fn prepare(
    cloud: &Cloud,
    lp: &LightParticles,
    n: usize,
    step: DVec3,
    order: &[usize],
) -> (Vec<Prep>, Vec<f64>) {
    let top = (n - 1) as f64;
    let span = |c: f64, cut: f64, h: f64| {
        let lo = ((c - cut) / h - 0.5).ceil().max(0.0);
        let hi = ((c + cut) / h - 0.5).floor().min(top);
        (lo as usize, hi as i64)
    };
    let mut pool = Vec::new();
    let preps = order
        .iter()
        .map(|&j| {
            let c = lp.centres[j] - lp.lo;
            let r = cloud.radii_m[j];
            let cut = CUTOFF_RADII * r;
            let inv_r2 = 1.0 / (r * r);
            // Depth: the two slices around DEPTH_OFFSET_SLICES behind the centre.
            let q = (c.z / step.z - 0.5 + DEPTH_OFFSET_SLICES).clamp(0.0, top);
            let k0 = (q.floor() as usize).min(n - 1);
            let f = q - k0 as f64;
            let (u_lo, u_hi) = span(c.x, cut, step.x);
            let (v_lo, v_hi) = span(c.y, cut, step.y);
            let v_off = pool.len();
            for iv in v_lo as i64..=v_hi {
                let dv = (iv as f64 + 0.5) * step.y - c.y;
                pool.push((-dv * dv * inv_r2).exp());
            }
            Prep {
                cu: c.x,
                cv: c.y,
                inv_r2,
                cut2: cut * cut,
                amp: -cloud.attenuation_per_depth(j) * cloud.optical_depths[j] * SCALE,
                k0,
                k1: (k0 + 1).min(n - 1),
                w0: 1.0 - f,
                w1: f,
                u_lo: u_lo as i64,
                u_hi,
                v_lo,
                v_off,
                v_len: pool.len() - v_off,
            }
        })
        .collect();
    (preps, pool)
}

/// Adds a particle's footprint on the row at u = `uc` to `plane` (fixed point).
#[inline]
fn deposit(plane: &mut [i64], n: usize, hv: f64, uc: f64, p: &Prep, ev: &[f64]) {
    let du = uc - p.cu;
    let rest2 = p.cut2 - du * du;
    if rest2 < 0.0 || ev.is_empty() {
        return;
    }
    let a = p.amp * (-du * du * p.inv_r2).exp();
    let (a0, a1) = (a * p.w0, a * p.w1);
    // The footprint's chord on this row.
    let half = rest2.sqrt();
    let lo = (((p.cv - half) / hv - 0.5).ceil().max(p.v_lo as f64)) as usize;
    let hi = (((p.cv + half) / hv - 0.5).floor() as i64).min((p.v_lo + ev.len()) as i64 - 1);
    if hi < lo as i64 {
        return;
    }
    let hi = hi as usize;
    let ev = &ev[lo - p.v_lo..=hi - p.v_lo];
    let (r0, r1) = (p.k0 * n, p.k1 * n);
    for (d, &e) in plane[r0 + lo..=r0 + hi].iter_mut().zip(ev) {
        *d += to_fixed(a0 * e);
    }
    for (d, &e) in plane[r1 + lo..=r1 + hi].iter_mut().zip(ev) {
        *d += to_fixed(a1 * e);
    }
}

/// The nearest integer to `x` (|x| < 2⁵¹: a particle's log G in fixed point is at most
/// 1e4 · 2²⁸ ≈ 2.7e12), by the 1.5 · 2⁵² shift: add, reinterpret, subtract. Plain arithmetic
/// that vectorises, where `as i64` checks for NaN and saturates element by element.
#[inline]
fn to_fixed(x: f64) -> i64 {
    const SHIFT: f64 = 6_755_399_441_055_744.0; // 1.5 · 2^52
    (x + SHIFT).to_bits() as i64 - SHIFT.to_bits() as i64
}

/// exp(s / SCALE) for a fixed-point log s ≤ 0, as f32 ([`exp_fast`]).
#[inline]
fn exp_fixed(s: i64) -> f32 {
    exp_fast(s as f64 * (1.0 / SCALE)) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_point_exp_is_exp() {
        for x in [
            0.0, -1e-6, -0.3, -1.0, -7.7, -40.0, -87.0, -103.0, -150.0, -1e4,
        ] {
            let s = (x * SCALE) as i64;
            let want = (s as f64 / SCALE).exp() as f32;
            let got = exp_fixed(s);
            assert!(
                (got - want).abs() <= want * 3e-7 + 1e-44,
                "{x}: {got} vs {want}"
            );
        }
    }
    use crate::cloud::generate::{Kind, particles};
    use crate::cloud::harris::harris_illumination;

    fn errors(cloud: &Cloud, sun: [f64; 3], res: usize) -> (f64, f64) {
        let v = AttenuationVolume::build(cloud, sun, res).unwrap();
        let h = harris_illumination(cloud, sun, 1.0).unwrap();
        let mut e: Vec<f64> = cloud
            .positions_m
            .iter()
            .zip(&h)
            .map(|(p, &hk)| ((v.sample(DVec3::from_array(*p)) as f64 - hk) / hk).abs())
            .collect();
        e.sort_by(f64::total_cmp);
        (e[e.len() / 2], e[e.len() * 95 / 100])
    }

    #[test]
    fn to_fixed_rounds_to_the_nearest_integer() {
        for x in [0.0, -0.4, -0.6, -1.5e9, -2.7e12, 3.2, -123_456.7] {
            assert_eq!(to_fixed(x), x.round_ties_even() as i64, "{x}");
        }
    }

    #[test]
    fn one_particle_gives_its_analytic_transmittance() {
        let cloud = Cloud::new(
            vec![[10.0, 500.0, -3.0]],
            vec![20.0],
            vec![2.0],
            vec![1.0],
            0.86,
        )
        .unwrap();
        let v = AttenuationVolume::build(&cloud, [0.0, 1.0, 0.0], 64).unwrap();
        let k = cloud.attenuation_per_depth(0) * 2.0;
        // Far below the particle, on its axis and 15 m off it (the grid's nodes are 1.9 m
        // apart across the light: trilinear within 1 %).
        for (dx, tol) in [(0.0, 1e-2), (15.0, 1e-2)] {
            let got = v.sample(DVec3::new(10.0 + dx, 0.0, -3.0)) as f64;
            let want = (-k * (-(dx * dx) / 400.0f64).exp()).exp();
            assert!((got - want).abs() < tol * want, "{dx}: {got} vs {want}");
        }
        // Above it, nothing.
        assert_eq!(v.sample(DVec3::new(10.0, 1000.0, -3.0)), 1.0);
    }

    #[test]
    fn shuffling_particles_gives_the_same_bits() {
        let c = particles(Kind::Cumulus, 3000, 1000.0, 1500.0, 7).unwrap();
        let mut idx: Vec<usize> = (0..c.len()).collect();
        idx.reverse();
        idx.rotate_left(123);
        let s = Cloud::new(
            idx.iter().map(|&i| c.positions_m[i]).collect(),
            idx.iter().map(|&i| c.radii_m[i]).collect(),
            idx.iter().map(|&i| c.optical_depths[i]).collect(),
            idx.iter().map(|&i| c.albedos[i]).collect(),
            c.asymmetry_g,
        )
        .unwrap();
        let sun = [0.3, 0.8, 0.2];
        let a = AttenuationVolume::build(&c, sun, 48).unwrap();
        let b = AttenuationVolume::build(&s, sun, 48).unwrap();
        assert!(
            a.gamma
                .iter()
                .zip(&b.gamma)
                .all(|(x, y)| x.to_bits() == y.to_bits())
        );
    }

    #[test]
    fn dense_cloud_stays_finite_and_darkens_monotonically() {
        let mut c = particles(Kind::Cumulus, 2000, 1000.0, 1500.0, 3).unwrap();
        for t in &mut c.optical_depths {
            *t = 5000.0;
        }
        let n = 32;
        let v = AttenuationVolume::build(&c, [0.0, 1.0, 0.0], n).unwrap();
        assert!(
            v.gamma
                .iter()
                .all(|g| g.is_finite() && (0.0..=1.0).contains(g))
        );
        for col in v.gamma.chunks(n) {
            assert!(col.windows(2).all(|w| w[1] <= w[0]));
        }
        assert!(v.gamma.contains(&0.0));
    }

    #[test]
    fn volume_agrees_with_harris_at_the_particles() {
        let c = particles(Kind::Cumulus, 4000, 1000.0, 1500.0, 1).unwrap();
        let (median, p95) = errors(&c, [0.4, 0.8, -0.3], 128);
        eprintln!("median {median} p95 {p95}");
        // Measured: median 0.042, p95 0.109 (60 134 particles at 128³: 0.038, 0.160).
        assert!(median < 0.06 && p95 < 0.15, "median {median} p95 {p95}");
    }

    #[test]
    fn matrix_round_trips_and_is_checked() {
        let c = particles(Kind::Broken, 500, 2000.0, 1000.0, 2).unwrap();
        let v = AttenuationVolume::build(&c, [0.2, 0.9, 0.1], 16).unwrap();
        let b = VolumeBox::from_matrix(&v.grid.matrix()).unwrap();
        assert_eq!(b, v.grid);
        let mut m = v.grid.matrix();
        m[1] = m[0];
        m[5] = m[4];
        m[9] = m[8];
        assert!(VolumeBox::from_matrix(&m).is_err());
        assert!(AttenuationVolume::build(&c, [0.0; 3], 16).is_err());
        assert!(AttenuationVolume::build(&c, [0.0, 1.0, 0.0], 1).is_err());
        assert!(AttenuationVolume::build(&c, [0.0, 1.0, 0.0], 513).is_err());
    }
}
