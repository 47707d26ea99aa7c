//! Procedural, seeded clouds: particles scattered in a metaball shape perturbed by noise.
//!
//! A kind is a density field over a box: a sum of Gaussian metaballs (cumulus: a tower of
//! cells above a flat base; broken: a field of small cumulus cells; stratocumulus: a thin
//! layer modulated by a grid of convective cells), multiplied by three octaves of value noise
//! (lattice values from SplitMix64 of the seed and the lattice point). Positions are drawn
//! uniformly in the box from a PCG64 stream seeded by (seed, kind) and kept where the
//! perturbed field exceeds its threshold (rejection), until `n` are kept. The kept share of
//! the draws measures the cloud's volume V, and with it the particles' spacing
//! s = (V/n)^⅓: radii are s·[0.8, 1.2] (uniform), and each particle's optical depth
//! τ_i = β V / (n π r_i²) makes the Gaussians' sum carry the kind's extinction β inside the
//! cloud (a Gaussian of 1/e radius r and central column τ holds τ π r² of β·volume).

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::Cloud;
use super::optics::{self, Droplets};
use crate::error::{Error, Param, Result};
use crate::ranges;
use crate::seed::{derive, splitmix64};

/// Particle radii in spacings (times a uniform [0.8, 1.2]): wide, overlapping particles of
/// small optical depth, so the volume's slices resolve each one's share.
pub const RADIUS_SPACINGS: f64 = 2.0;

/// A kind of generated cloud.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// One cumulus congestus: a tower of cells above a flat base, as tall as it is wide.
    Cumulus,
    /// A stratocumulus deck: a layer a tenth of its side thick, in convective cells.
    Stratocumulus,
    /// A broken field of small fair-weather cumulus covering part of a square.
    Broken,
}

impl Kind {
    /// Every kind's name.
    pub const NAMES: [&'static str; 3] = ["cumulus", "stratocumulus", "broken"];

    /// The kind named `name`.
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "cumulus" => Ok(Kind::Cumulus),
            "stratocumulus" => Ok(Kind::Stratocumulus),
            "broken" => Ok(Kind::Broken),
            _ => Err(Error::Invalid {
                param: Param {
                    name: "kind",
                    index: None,
                },
                message: format!("{name:?} is not one of {:?}", Kind::NAMES),
            }),
        }
    }

    /// The kind's droplets (the Mie table's case for it).
    pub fn droplets(self) -> Droplets {
        match self {
            Kind::Cumulus => optics::CUMULUS,
            Kind::Stratocumulus => optics::STRATOCUMULUS,
            Kind::Broken => optics::BROKEN,
        }
    }
}

/// A metaball: centre and 1/e radius, m.
struct Ball {
    c: DVec3,
    r: f64,
}

/// A kind's shape: the box to draw in, its metaballs (or the layer), the threshold.
struct Shape {
    lo: DVec3,
    hi: DVec3,
    balls: Vec<Ball>,
    layer: Option<(f64, f64, f64)>,
    threshold: f64,
    noise_scale_m: f64,
}

fn lattice(seed: u64, x: i64, y: i64, z: i64) -> f64 {
    let h = derive(seed, &[x as u64, y as u64, z as u64]);
    (h >> 11) as f64 / (1u64 << 53) as f64
}

/// Value noise in [0, 1): trilinear between lattice values, smoothstep weights.
fn value_noise(seed: u64, p: DVec3) -> f64 {
    let f = p.floor();
    let t = p - f;
    let s = t * t * (DVec3::splat(3.0) - 2.0 * t);
    let (x, y, z) = (f.x as i64, f.y as i64, f.z as i64);
    let mut acc = 0.0;
    for dz in 0..2 {
        for dy in 0..2 {
            for dx in 0..2 {
                let w = (if dx == 1 { s.x } else { 1.0 - s.x })
                    * (if dy == 1 { s.y } else { 1.0 - s.y })
                    * (if dz == 1 { s.z } else { 1.0 - s.z });
                acc += w * lattice(seed, x + dx, y + dy, z + dz);
            }
        }
    }
    acc
}

/// Three octaves of value noise, in [0, 1).
fn fractal_noise(seed: u64, p: DVec3) -> f64 {
    let mut acc = 0.0;
    let mut amp = 0.5;
    let mut freq = 1.0;
    let mut norm = 0.0;
    for octave in 0..3u64 {
        acc += amp * value_noise(splitmix64(seed ^ octave), p * freq);
        norm += amp;
        amp *= 0.5;
        freq *= 2.0;
    }
    acc / norm
}

impl Shape {
    fn new(kind: Kind, extent: f64, base: f64, rng: &mut Pcg64Mcg) -> Self {
        let d = extent;
        match kind {
            Kind::Cumulus => {
                let mut balls = vec![Ball {
                    c: DVec3::new(0.0, base + 0.3 * d, 0.0),
                    r: 0.32 * d,
                }];
                for _ in 0..8 {
                    let a = rng.random::<f64>() * std::f64::consts::TAU;
                    let h = rng.random::<f64>();
                    let rho = 0.28 * d * rng.random::<f64>() * (1.0 - 0.6 * h);
                    balls.push(Ball {
                        c: DVec3::new(rho * a.cos(), base + d * (0.25 + 0.5 * h), rho * a.sin()),
                        r: d * (0.12 + 0.1 * rng.random::<f64>()) * (1.0 - 0.4 * h),
                    });
                }
                Shape {
                    lo: DVec3::new(-0.5 * d, base, -0.5 * d),
                    hi: DVec3::new(0.5 * d, base + d, 0.5 * d),
                    balls,
                    layer: None,
                    threshold: 0.55,
                    noise_scale_m: d / 6.0,
                }
            }
            Kind::Broken => {
                let mut balls = Vec::new();
                for _ in 0..14 {
                    let cx = (rng.random::<f64>() - 0.5) * 0.85 * d;
                    let cz = (rng.random::<f64>() - 0.5) * 0.85 * d;
                    let s = d * (0.035 + 0.045 * rng.random::<f64>());
                    for _ in 0..3 {
                        let o = DVec3::new(
                            (rng.random::<f64>() - 0.5) * s,
                            s * (0.5 + 0.6 * rng.random::<f64>()),
                            (rng.random::<f64>() - 0.5) * s,
                        );
                        balls.push(Ball {
                            c: DVec3::new(cx, base, cz) + o,
                            r: s * (0.7 + 0.3 * rng.random::<f64>()),
                        });
                    }
                }
                Shape {
                    lo: DVec3::new(-0.5 * d, base, -0.5 * d),
                    hi: DVec3::new(0.5 * d, base + 0.2 * d, 0.5 * d),
                    balls,
                    layer: None,
                    threshold: 0.55,
                    noise_scale_m: d / 30.0,
                }
            }
            Kind::Stratocumulus => {
                let thick = 0.1 * d;
                let cell = d / 5.0 * (0.8 + 0.4 * rng.random::<f64>());
                Shape {
                    lo: DVec3::new(-0.5 * d, base, -0.5 * d),
                    hi: DVec3::new(0.5 * d, base + thick, 0.5 * d),
                    balls: Vec::new(),
                    layer: Some((base + 0.5 * thick, 0.5 * thick, cell)),
                    threshold: 0.45,
                    noise_scale_m: d / 15.0,
                }
            }
        }
    }

    /// The noise-perturbed density field at `p` (above the threshold: inside the cloud).
    fn field(&self, seed: u64, p: DVec3) -> f64 {
        let noise = fractal_noise(seed, p / self.noise_scale_m);
        let base = match self.layer {
            Some((mid, half, cell)) => {
                let y = (p.y - mid) / half;
                let tau = std::f64::consts::TAU;
                let cells = 0.5 + 0.5 * (tau * p.x / cell).cos() * (tau * p.z / cell).cos();
                (1.0 - y * y) * (0.55 + 0.45 * cells)
            }
            None => self
                .balls
                .iter()
                .map(|b| (-(p - b.c).length_squared() / (b.r * b.r)).exp())
                .sum::<f64>(),
        };
        base * (0.55 + 0.9 * noise)
    }
}

/// A generated cloud of `n` particles, `extent_m` across, its base at `altitude_m`.
pub fn particles(kind: Kind, n: usize, extent_m: f64, altitude_m: f64, seed: u64) -> Result<Cloud> {
    ranges::N_PARTICLES.check(n as f64)?;
    ranges::EXTENT_M.check(extent_m)?;
    ranges::ALTITUDE_M.check(altitude_m)?;
    let kind_key = kind as u64 + 1;
    let mut rng = Pcg64Mcg::seed_from_u64(derive(seed, &[0xC10D, kind_key]));
    let noise_seed = derive(seed, &[0xC10D, kind_key, 1]);
    let shape = Shape::new(kind, extent_m, altitude_m, &mut rng);
    let size = shape.hi - shape.lo;
    let max_draws = (n as u64).saturating_mul(10_000).max(1_000_000);
    let mut positions = Vec::with_capacity(n);
    let mut draws = 0u64;
    while positions.len() < n {
        if draws >= max_draws {
            return Err(Error::Invalid {
                param: Param {
                    name: "kind",
                    index: None,
                },
                message: format!("no cloud found in {draws} draws (seed {seed})"),
            });
        }
        draws += 1;
        let p = shape.lo + size * DVec3::new(rng.random(), rng.random(), rng.random());
        if shape.field(noise_seed, p) > shape.threshold {
            positions.push(p.to_array());
        }
    }
    let volume_m3 = size.x * size.y * size.z * n as f64 / draws as f64;
    let spacing = (volume_m3 / n as f64).cbrt();
    let drops = kind.droplets();
    let beta = drops.extinction_per_m();
    let radii: Vec<f64> = (0..n)
        .map(|_| RADIUS_SPACINGS * spacing * (0.8 + 0.4 * rng.random::<f64>()))
        .collect();
    let depths = radii
        .iter()
        .map(|r| beta * volume_m3 / (n as f64 * std::f64::consts::PI * r * r))
        .collect();
    Cloud::new(positions, radii, depths, vec![drops.albedo; n], drops.g)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeded_and_within_the_box() {
        for kind in [Kind::Cumulus, Kind::Stratocumulus, Kind::Broken] {
            let a = particles(kind, 500, 2000.0, 1200.0, 5).unwrap();
            let b = particles(kind, 500, 2000.0, 1200.0, 5).unwrap();
            let c = particles(kind, 500, 2000.0, 1200.0, 6).unwrap();
            assert_eq!(a, b);
            assert_ne!(a.positions_m, c.positions_m);
            assert!(
                a.positions_m
                    .iter()
                    .all(|p| p[1] >= 1200.0 && p[0].abs() <= 1000.0)
            );
            assert!(a.albedos.iter().all(|&x| x > 0.9999));
        }
        assert!(Kind::parse("cirrus").is_err());
    }

    #[test]
    fn particles_carry_the_kinds_extinction() {
        // The Gaussians' summed extinction, at the particles' own centres, is of the order of
        // the kind's β (edges read less; overlap is uneven).
        let c = particles(Kind::Stratocumulus, 4000, 2000.0, 800.0, 1).unwrap();
        let mean_tau = c.optical_depths.iter().sum::<f64>() / c.len() as f64;
        assert!(mean_tau > 0.0 && mean_tau.is_finite());
        let beta = Kind::Stratocumulus.droplets().extinction_per_m();
        let mut sum = 0.0;
        let p0 = DVec3::from_array(c.positions_m[c.len() / 2]);
        for i in 0..c.len() {
            let r = c.radii_m[i];
            let d2 = (DVec3::from_array(c.positions_m[i]) - p0).length_squared();
            // density at p0: τ/(√π r) exp(−d²/r²)
            sum += c.optical_depths[i] / (std::f64::consts::PI.sqrt() * r) * (-d2 / (r * r)).exp();
        }
        assert!(sum > 0.3 * beta && sum < 3.0 * beta, "{sum} vs {beta}");
    }
}
