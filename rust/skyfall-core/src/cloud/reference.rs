//! A brute-force Monte Carlo path tracer of a particle cloud lit by the sun: the reference the
//! frames' cloud lighting is measured against (every order of scattering, no approximation
//! but the sampling).
//!
//! The medium is the cloud's own density: particle i contributes extinction
//! β_i exp(−|x − c_i|²/r_i²) inside its support (2.5 r_i), β_i = τ_i/(r_i √π) so that the column
//! through its centre is τ_i; its single-scattering albedo a_i weighs its share; the phase
//! function is Henyey–Greenstein with the cloud's g. Along a ray the optical depth is analytic
//! (a sum of error functions over the particles the ray passes), so free flights are sampled
//! exactly by inverting it (bisection), and next-event estimation towards the sun uses the
//! exact transmittance. Paths start at the eye along each direction (the adjoint of the light's
//! path), each vertex adds the sun's light scattered towards the eye, W a p(cos θ) T_sun E_sun,
//! and the path goes on in a direction drawn from the phase function, W ← W a, up to
//! `max_orders` vertices. Results are in the frames' relative units (π L / E with E_sun/E =
//! `sun_relative`), the sky's light left out (a black sky).
//!
//! Deterministic: direction k's paths draw from a PCG64 stream seeded by (seed, k).

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;

use super::{CUTOFF_RADII, Cloud};
use crate::error::{Error, Param, Result};
use crate::seed::derive;

/// What [`path_trace`] returns per direction, relative units.
#[derive(Debug, Clone, PartialEq)]
pub struct PathTraced {
    /// Radiance of every order of scattering.
    pub radiance: Vec<f64>,
    /// Radiance of single scattering alone (each path's first vertex).
    pub single: Vec<f64>,
    /// One standard error of `radiance`.
    pub std_err: Vec<f64>,
}

/// erf(x), Abramowitz & Stegun 7.1.26 (|error| < 1.5e-7).
fn erf(x: f64) -> f64 {
    let t = 1.0 / (1.0 + 0.327_591_1 * x.abs());
    let p = t
        * (0.254_829_592
            + t * (-0.284_496_736
                + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    let y = 1.0 - p * (-x * x).exp();
    if x >= 0.0 { y } else { -y }
}

/// A particle's share of a ray: its extinction integrates to
/// `scale · (erf((t − s0)/r) − erf((lo − s0)/r))` for t in [lo, hi].
#[derive(Debug, Clone, Copy)]
struct Chord {
    s0: f64,
    r: f64,
    lo: f64,
    hi: f64,
    scale: f64,
    base: f64,
}

impl Chord {
    #[inline]
    fn depth_to(&self, t: f64) -> f64 {
        let t = t.clamp(self.lo, self.hi);
        self.scale * (erf((t - self.s0) / self.r) - self.base)
    }
}

/// The medium: the particles with their extinction scales.
struct Medium<'a> {
    cloud: &'a Cloud,
    beta: Vec<f64>,
}

impl Medium<'_> {
    /// The chords of the ray from `o` along unit `d` (t ≥ 0).
    fn chords(&self, o: DVec3, d: DVec3, out: &mut Vec<Chord>) {
        out.clear();
        for (i, c) in self.cloud.positions_m.iter().enumerate() {
            let r = self.cloud.radii_m[i];
            let support = CUTOFF_RADII * r;
            let rel = DVec3::from_array(*c) - o;
            let s0 = rel.dot(d);
            let rho2 = (rel - d * s0).length_squared();
            if rho2 >= support * support {
                continue;
            }
            let h = (support * support - rho2).sqrt();
            if s0 + h <= 0.0 {
                continue;
            }
            let lo = (s0 - h).max(0.0);
            let scale =
                self.beta[i] * r * std::f64::consts::PI.sqrt() / 2.0 * (-rho2 / (r * r)).exp();
            out.push(Chord {
                s0,
                r,
                lo,
                hi: s0 + h,
                scale,
                base: erf((lo - s0) / r),
            });
        }
    }

    /// The single-scattering albedo at `p`: the particles' albedos weighed by their extinction.
    fn albedo_at(&self, p: DVec3) -> f64 {
        let (mut num, mut den) = (0.0, 0.0);
        for (i, c) in self.cloud.positions_m.iter().enumerate() {
            let r = self.cloud.radii_m[i];
            let d2 = (DVec3::from_array(*c) - p).length_squared();
            if d2 >= (CUTOFF_RADII * r).powi(2) {
                continue;
            }
            let s = self.beta[i] * (-d2 / (r * r)).exp();
            num += s * self.cloud.albedos[i];
            den += s;
        }
        if den > 0.0 { num / den } else { 1.0 }
    }
}

fn total(chords: &[Chord]) -> f64 {
    chords.iter().map(|c| c.depth_to(c.hi)).sum()
}

/// The distance along the chords' ray where the optical depth reaches `target` (< total).
fn invert(chords: &[Chord], target: f64) -> f64 {
    let mut hi = chords.iter().fold(0.0f64, |m, c| m.max(c.hi));
    let mut lo = 0.0;
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        let tau: f64 = chords.iter().map(|c| c.depth_to(mid)).sum();
        if tau < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// A direction drawn from the Henyey–Greenstein phase about unit `w`.
fn sample_hg(rng: &mut Pcg64Mcg, w: DVec3, g: f64) -> DVec3 {
    let xi: f64 = rng.random();
    let cos = if g.abs() < 1e-6 {
        1.0 - 2.0 * xi
    } else {
        let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * xi);
        ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
    };
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = std::f64::consts::TAU * rng.random::<f64>();
    let a = if w.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let u = w.cross(a).normalize();
    let v = w.cross(u);
    (w * cos + (u * phi.cos() + v * phi.sin()) * sin).normalize()
}

/// Radiance towards `eye` from each of `directions` (unit, world), in relative units, by
/// `paths` paths of up to `max_orders` scattering vertices each (see the module's notes).
#[allow(clippy::too_many_arguments)]
pub fn path_trace(
    cloud: &Cloud,
    sun: [f64; 3],
    sun_relative: f64,
    eye: DVec3,
    directions: &[DVec3],
    paths: usize,
    max_orders: usize,
    seed: u64,
) -> Result<PathTraced> {
    let s = super::sun_direction(sun)?;
    if paths == 0 || max_orders == 0 {
        return Err(Error::Invalid {
            param: Param {
                name: "paths",
                index: None,
            },
            message: "paths and max_orders must be at least 1".into(),
        });
    }
    let medium = Medium {
        cloud,
        beta: (0..cloud.len())
            .map(|i| cloud.optical_depths[i] / (cloud.radii_m[i] * std::f64::consts::PI.sqrt()))
            .collect(),
    };
    let g = cloud.asymmetry_g;
    let hg = |c: f64| super::optics::henyey_greenstein(c, g);
    let scale = std::f64::consts::PI * sun_relative;
    let per_dir: Vec<(f64, f64, f64)> = directions
        .par_iter()
        .enumerate()
        .map_init(Vec::new, |chords, (k, &d0)| {
            let mut rng = Pcg64Mcg::seed_from_u64(derive(seed, &[0x5A7, k as u64]));
            let d0 = d0.normalize();
            let (mut sum, mut sum2, mut single) = (0.0, 0.0, 0.0);
            for _ in 0..paths {
                let (mut o, mut w, mut weight, mut value) = (eye, d0, 1.0, 0.0);
                for order in 0..max_orders {
                    medium.chords(o, w, chords);
                    let tau_all = total(chords);
                    let target = -(1.0 - rng.random::<f64>()).ln();
                    if target >= tau_all {
                        break; // the path leaves the cloud
                    }
                    let x = o + w * invert(chords, target);
                    let a = medium.albedo_at(x);
                    weight *= a;
                    medium.chords(x, s, chords);
                    let t_sun = (-total(chords)).exp();
                    let c = weight * hg(w.dot(s)) * t_sun * scale;
                    value += c;
                    if order == 0 {
                        single += c;
                    }
                    o = x;
                    w = sample_hg(&mut rng, w, g);
                }
                sum += value;
                sum2 += value * value;
            }
            let n = paths as f64;
            let mean = sum / n;
            let var = (sum2 / n - mean * mean).max(0.0);
            (mean, single / n, (var / n).sqrt())
        })
        .collect();
    Ok(PathTraced {
        radiance: per_dir.iter().map(|v| v.0).collect(),
        single: per_dir.iter().map(|v| v.1).collect(),
        std_err: per_dir.iter().map(|v| v.2).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erf_matches_known_values() {
        for (x, want) in [
            (0.0, 0.0),
            (0.5, 0.520_499_877_8),
            (1.0, 0.842_700_792_9),
            (2.0, 0.995_322_265),
            (-1.0, -0.842_700_792_9),
        ] {
            assert!((erf(x) - want).abs() < 2e-7, "{x}");
        }
    }

    #[test]
    fn a_chord_through_the_centre_carries_the_particles_optical_depth() {
        let cloud = Cloud::new(
            vec![[0.0, 0.0, 0.0]],
            vec![10.0],
            vec![3.0],
            vec![1.0],
            0.86,
        )
        .unwrap();
        let m = Medium {
            cloud: &cloud,
            beta: vec![3.0 / (10.0 * std::f64::consts::PI.sqrt())],
        };
        let mut ch = Vec::new();
        m.chords(DVec3::new(0.0, 0.0, -100.0), DVec3::Z, &mut ch);
        // τ times the share of the Gaussian within ±2.5 r: erf(2.5).
        let want = 3.0 * erf(2.5);
        assert!((total(&ch) - want).abs() < 1e-6, "{}", total(&ch));
        let t = invert(&ch, want / 2.0);
        assert!((t - 100.0).abs() < 1e-6, "{t}");
    }

    #[test]
    fn a_thin_particle_scatters_its_single_scattering() {
        // τ = 0.01 seen through its centre with the sun at 90°: L ≈ π rel τ_eff p(0) (the
        // support holds erf(2.5) of τ), multiple scattering negligible.
        let tau = 0.01;
        let cloud = Cloud::new(
            vec![[0.0, 0.0, -100.0]],
            vec![5.0],
            vec![tau],
            vec![1.0],
            0.86,
        )
        .unwrap();
        let r = path_trace(
            &cloud,
            [1.0, 0.0, 0.0],
            2.0,
            DVec3::ZERO,
            &[DVec3::new(0.0, 0.0, -1.0)],
            20_000,
            4,
            1,
        )
        .unwrap();
        let p = crate::cloud::optics::henyey_greenstein(0.0, 0.86);
        let want = std::f64::consts::PI * 2.0 * tau * erf(2.5) * p;
        assert!(
            (r.radiance[0] - want).abs() < 4.0 * r.std_err[0] + 0.02 * want,
            "{} vs {want} ± {}",
            r.radiance[0],
            r.std_err[0]
        );
        // Higher orders add about τ of it.
        assert!((r.single[0] - r.radiance[0]).abs() < 0.05 * want);
    }

    #[test]
    fn paths_are_seeded() {
        let cloud = Cloud::new(
            vec![[0.0, 0.0, -50.0]],
            vec![10.0],
            vec![5.0],
            vec![1.0],
            0.86,
        )
        .unwrap();
        let d = [DVec3::new(0.0, 0.0, -1.0), DVec3::new(0.05, 0.0, -1.0)];
        let a = path_trace(&cloud, [0.0, 1.0, 0.0], 1.0, DVec3::ZERO, &d, 200, 32, 7).unwrap();
        let b = path_trace(&cloud, [0.0, 1.0, 0.0], 1.0, DVec3::ZERO, &d, 200, 32, 7).unwrap();
        assert_eq!(a, b);
        assert!(a.radiance[0] > a.single[0]); // a thick particle scatters more than once
    }
}
