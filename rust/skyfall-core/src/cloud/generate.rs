//! Procedural, seeded clouds: particles filling a union of billows above a flat base.
//!
//! A kind is a shape grown by [`super::billows`]: root spheres per convective cell (cumulus:
//! one tower of stacked turrets with shoulders; broken: fourteen small cells scattered over a
//! square; stratocumulus: a deck of flat cells on a jittered grid whose cover thins out
//! towards the deck's edge, so it ends in scattered cells instead of a line), children of
//! about half their parent's radius on each sphere's upper surface for two or three levels
//! (the cauliflower), the union cut flat at the base and its surface perturbed by value
//! noise at the smallest billows' scale. Lattice values come from SplitMix64 of the seed and
//! the lattice point; the spheres and the draws from a PCG64 stream seeded by (seed, kind).
//!
//! Particles are small at the surface and large inside, where no one sees them: a point at
//! depth D below the surface has the relative spacing g = min(1 + D/L, 4), L the smallest
//! billows' mean radius. Points are drawn uniformly in the box and kept inside the shape with
//! probability g⁻³, until `n` are kept, so the particles' number density is ∝ g⁻³ and each
//! stands for the volume v_i ∝ g_i³. The share of draws inside measures the cloud's volume V,
//! and the v_i are scaled to sum to it. Radii are [`RADIUS_SPACINGS`] · v_i^⅓ · [0.8, 1.2]
//! (uniform), and each particle's optical depth τ_i = β v_i / (π r_i²) makes the Gaussians'
//! sum carry the kind's extinction β everywhere inside (a Gaussian of 1/e radius r and
//! central column τ holds τ π r² of β·volume).

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::Cloud;
use super::billows::{Billow, Field, Level, grow};
use super::optics::{self, Droplets};
use crate::error::{Error, Param, Result};
use crate::ranges;
use crate::seed::derive;

/// Particle radii in spacings (times a uniform [0.8, 1.2]): wide, overlapping particles of
/// small optical depth, so the volume's slices resolve each one's share.
pub const RADIUS_SPACINGS: f64 = 2.0;

/// The largest relative spacing, deep inside a cloud (the surface's is 1).
pub const MAX_SPACING_RATIO: f64 = 4.0;

/// The surface moves in and out by up to this share of a billow's radius (noise).
const ROUGHNESS: f64 = 0.35;

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

/// Levels of (children per parent, a child's radius ratio from, to).
fn levels(spec: &[(usize, f64, f64)]) -> Vec<Level> {
    spec.iter()
        .map(|&(children, lo, hi)| Level {
            children,
            ratio: (lo, hi),
        })
        .collect()
}

fn uniform(rng: &mut Pcg64Mcg, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

/// A kind's root spheres, the levels grown on them and the box particles are drawn in.
fn roots(
    kind: Kind,
    d: f64,
    base: f64,
    rng: &mut Pcg64Mcg,
) -> (Vec<Billow>, Vec<Level>, DVec3, DVec3) {
    let half = 0.5 * d;
    match kind {
        Kind::Cumulus => {
            // A tower of four turrets, each narrower than the one below, leaning at random,
            // on three shoulders at the base.
            let mut roots = Vec::new();
            let mut c = DVec3::new(0.0, base + 0.16 * d, 0.0);
            let mut r = 0.23 * d;
            for _ in 0..4 {
                roots.push(Billow { c, r });
                c += DVec3::new(
                    uniform(rng, -0.05, 0.05) * d,
                    0.16 * d,
                    uniform(rng, -0.05, 0.05) * d,
                );
                r *= 0.82;
            }
            let a0 = rng.random::<f64>() * std::f64::consts::TAU;
            for k in 0..3 {
                let a = a0 + k as f64 * std::f64::consts::TAU / 3.0 + uniform(rng, -0.4, 0.4);
                let rho = uniform(rng, 0.18, 0.24) * d;
                roots.push(Billow {
                    c: DVec3::new(rho * a.cos(), base + 0.08 * d, rho * a.sin()),
                    r: uniform(rng, 0.14, 0.19) * d,
                });
            }
            let levels = levels(&[(6, 0.38, 0.55), (5, 0.38, 0.55), (4, 0.4, 0.55)]);
            (
                roots,
                levels,
                DVec3::new(-half, base, -half),
                DVec3::new(half, base + 1.5 * d, half),
            )
        }
        Kind::Broken => {
            // Fourteen fair-weather cumulus: two or three turrets each, sitting on the base.
            let mut roots = Vec::new();
            for _ in 0..14 {
                let cx = uniform(rng, -0.42, 0.42) * d;
                let cz = uniform(rng, -0.42, 0.42) * d;
                let s = uniform(rng, 0.035, 0.08) * d;
                let k = 2 + (rng.random::<f64>() < 0.5) as usize;
                for _ in 0..k {
                    let r = s * uniform(rng, 0.6, 0.9);
                    roots.push(Billow {
                        c: DVec3::new(
                            cx + uniform(rng, -0.5, 0.5) * s,
                            base + 0.45 * r,
                            cz + uniform(rng, -0.5, 0.5) * s,
                        ),
                        r,
                    });
                }
            }
            let levels = levels(&[(5, 0.4, 0.6), (4, 0.4, 0.6)]);
            (
                roots,
                levels,
                DVec3::new(-half, base, -half),
                DVec3::new(half, base + 0.5 * d, half),
            )
        }
        Kind::Stratocumulus => {
            // Cells on a jittered grid, three times as wide as the deck is thick (a twentieth
            // of its side, at most 400 m: real decks are 200-500 m thick whatever their
            // extent), cut flat at the top (the inversion caps the deck) as at the base. A
            // cell is there with probability 0.9 inside 65 % of the deck's radius, falling to
            // 0 at its edge, so the deck ends in scattered cells, not in a line.
            let thick = (0.05 * d).min(400.0);
            let n = ((d / (3.0 * thick)).round() as usize).clamp(1, 48);
            let cell = d / n as f64;
            let mut roots = Vec::new();
            for i in 0..n {
                for j in 0..n {
                    let cx = (i as f64 + 0.5 + uniform(rng, -0.2, 0.2)) * cell - half;
                    let cz = (j as f64 + 0.5 + uniform(rng, -0.2, 0.2)) * cell - half;
                    let rho = (cx * cx + cz * cz).sqrt() / half;
                    let present = 0.9 * ((1.0 - rho) / 0.35).clamp(0.0, 1.0);
                    let draw = rng.random::<f64>();
                    let k = 4 + (rng.random::<f64>() * 3.0) as usize;
                    for _ in 0..k {
                        let r = thick * uniform(rng, 0.5, 0.7);
                        let c = DVec3::new(
                            cx + uniform(rng, -0.25, 0.25) * cell,
                            base + 0.45 * thick,
                            cz + uniform(rng, -0.25, 0.25) * cell,
                        );
                        if draw < present {
                            roots.push(Billow { c, r });
                        }
                    }
                }
            }
            if roots.is_empty() {
                roots.push(Billow {
                    c: DVec3::new(0.0, base + 0.3 * thick, 0.0),
                    r: 0.6 * thick,
                });
            }
            let levels = levels(&[(4, 0.35, 0.55), (3, 0.4, 0.55)]);
            (
                roots,
                levels,
                DVec3::new(-half, base, -half),
                DVec3::new(half, base + thick, half),
            )
        }
    }
}

/// A kind's shape: its field and the box to draw in.
fn shape(
    kind: Kind,
    d: f64,
    base: f64,
    seed: u64,
    rng: &mut Pcg64Mcg,
) -> (Field, f64, DVec3, DVec3) {
    let (roots, levels, lo, hi) = roots(kind, d, base, rng);
    let n_roots = roots.len();
    let billows = grow(roots, &levels, rng);
    let last: usize = n_roots * levels.iter().map(|l| l.children).product::<usize>();
    let finest = &billows[billows.len() - last.min(billows.len())..];
    let smallest_m = finest.iter().map(|b| b.r).sum::<f64>() / finest.len().max(1) as f64;
    let field = Field::new(billows, base, hi.y, ROUGHNESS, seed, smallest_m);
    let lo = lo.max(field.lo);
    let hi = hi.min(field.hi).max(lo + DVec3::splat(1e-6));
    (field, smallest_m, lo, hi)
}

/// A generated cloud of `n` particles, `extent_m` across, its base at `altitude_m`.
pub fn particles(kind: Kind, n: usize, extent_m: f64, altitude_m: f64, seed: u64) -> Result<Cloud> {
    ranges::N_PARTICLES.check(n as f64)?;
    ranges::EXTENT_M.check(extent_m)?;
    ranges::ALTITUDE_M.check(altitude_m)?;
    let kind_key = kind as u64 + 1;
    let mut rng = Pcg64Mcg::seed_from_u64(derive(seed, &[0xC10D, kind_key]));
    let noise_seed = derive(seed, &[0xC10D, kind_key, 1]);
    let (field, smallest_m, lo, hi) = shape(kind, extent_m, altitude_m, noise_seed, &mut rng);
    let size = hi - lo;
    let max_draws = (n as u64).saturating_mul(10_000).max(1_000_000);
    let mut positions = Vec::with_capacity(n);
    let mut ratios = Vec::with_capacity(n);
    let (mut draws, mut inside) = (0u64, 0u64);
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
        let p = lo + size * DVec3::new(rng.random(), rng.random(), rng.random());
        if let Some(depth) = field.depth(p) {
            inside += 1;
            let g = (1.0 + depth / smallest_m).min(MAX_SPACING_RATIO);
            if rng.random::<f64>() * g * g * g < 1.0 {
                positions.push(p.to_array());
                ratios.push(g);
            }
        }
    }
    let volume_m3 = size.x * size.y * size.z * inside as f64 / draws as f64;
    let cubes: f64 = ratios.iter().map(|g| g * g * g).sum();
    let drops = kind.droplets();
    let beta = drops.extinction_per_m();
    let mut radii = Vec::with_capacity(n);
    let mut depths = Vec::with_capacity(n);
    for g in &ratios {
        let v = volume_m3 * g * g * g / cubes;
        let r = RADIUS_SPACINGS * v.cbrt() * (0.8 + 0.4 * rng.random::<f64>());
        radii.push(r);
        depths.push(beta * v / (std::f64::consts::PI * r * r));
    }
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

    /// The particles' summed extinction at `p`, /m: a Gaussian of 1/e radius r and central
    /// column τ has the density τ/(√π r)·exp(−d²/r²).
    fn extinction_at(c: &Cloud, p: DVec3) -> f64 {
        (0..c.len())
            .map(|i| {
                let r = c.radii_m[i];
                let d2 = (DVec3::from_array(c.positions_m[i]) - p).length_squared();
                c.optical_depths[i] / (std::f64::consts::PI.sqrt() * r) * (-d2 / (r * r)).exp()
            })
            .sum()
    }

    #[test]
    fn particles_carry_the_kinds_extinction_everywhere_inside() {
        // Small particles at the surface, large ones inside: at points deep enough that every
        // particle's Gaussian around them lies inside, the sum is the kind's β, whatever the
        // sizes there (measured at seed 3: mean 0.97 β, every point within 0.64-1.15 β).
        let (d, base) = (1500.0, 1200.0);
        let c = particles(Kind::Cumulus, 20_000, d, base, 3).unwrap();
        let beta = Kind::Cumulus.droplets().extinction_per_m();
        let mut rng = Pcg64Mcg::seed_from_u64(derive(3, &[0xC10D, 1]));
        let (field, _, lo, hi) =
            shape(Kind::Cumulus, d, base, derive(3, &[0xC10D, 1, 1]), &mut rng);
        let r_max = c.radii_m.iter().cloned().fold(0.0, f64::max);
        let mut draw = Pcg64Mcg::seed_from_u64(7);
        let mut ratios = Vec::new();
        while ratios.len() < 200 {
            let p = lo + (hi - lo) * DVec3::new(draw.random(), draw.random(), draw.random());
            if field.depth(p).is_some_and(|depth| depth > 1.5 * r_max) {
                ratios.push(extinction_at(&c, p) / beta);
            }
        }
        let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
        let (lo_r, hi_r) = ratios
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
        assert!((mean - 1.0).abs() < 0.1, "mean {mean}");
        assert!(lo_r > 0.55 && hi_r < 1.35, "{lo_r} .. {hi_r}");
    }

    /// Each column's (lowest, highest) particle over a `cells` × `cells` grid of the box, for
    /// columns with at least 8 particles.
    fn columns(c: &Cloud, half: f64, cells: usize) -> Vec<(f64, f64)> {
        let mut col = vec![(f64::MAX, f64::MIN, 0usize); cells * cells];
        for p in &c.positions_m {
            let i = (((p[0] + half) / (2.0 * half) * cells as f64) as usize).min(cells - 1);
            let j = (((p[2] + half) / (2.0 * half) * cells as f64) as usize).min(cells - 1);
            let e = &mut col[j * cells + i];
            *e = (e.0.min(p[1]), e.1.max(p[1]), e.2 + 1);
        }
        col.into_iter()
            .filter(|e| e.2 >= 8)
            .map(|e| (e.0, e.1))
            .collect()
    }

    fn spread(x: &[f64]) -> f64 {
        let m = x.iter().sum::<f64>() / x.len() as f64;
        (x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / x.len() as f64).sqrt()
    }

    #[test]
    fn a_cumulus_has_a_flat_base_under_a_towering_billowed_top() {
        // Over the cloud's columns the lowest particle sits on the base (within 4 % of the
        // width) in most of them, while the tops vary by a fifth of the width: turrets.
        let (d, base) = (1500.0, 1200.0);
        let c = particles(Kind::Cumulus, 20_000, d, base, 0).unwrap();
        let cols = columns(&c, 0.5 * d, 24);
        let lows: Vec<f64> = cols.iter().map(|e| e.0).collect();
        let highs: Vec<f64> = cols.iter().map(|e| e.1).collect();
        let on_base =
            lows.iter().filter(|&&y| y - base < 0.04 * d).count() as f64 / lows.len() as f64;
        assert!(on_base > 0.7, "{on_base}");
        assert!(spread(&highs) > 0.15 * d, "{}", spread(&highs));
        let top = highs.iter().cloned().fold(0.0, f64::max);
        assert!(
            top - base > 0.7 * d && top - base < 1.2 * d,
            "as tall as wide: {}",
            top - base
        );
        // Small particles at the surface, large inside: radii span the ratio of spacings.
        let (r_lo, r_hi) = c
            .radii_m
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), &r| (a.min(r), b.max(r)));
        assert!(
            r_hi / r_lo > 0.6 * MAX_SPACING_RATIO * 1.2 / 0.8,
            "{r_lo} .. {r_hi}"
        );
    }

    #[test]
    fn a_stratocumulus_deck_is_broken_and_thins_out_at_its_edge() {
        // Seen from below (columns of d/60): cells with lanes between them in the middle of the
        // deck, scattered cells at its edge, no line where it stops.
        let d = 24_000.0;
        let c = particles(Kind::Stratocumulus, 60_000, d, 1000.0, 0).unwrap();
        let cells = 60;
        let mut hit = vec![false; cells * cells];
        for p in &c.positions_m {
            let i = (((p[0] + 0.5 * d) / d * cells as f64) as usize).min(cells - 1);
            let j = (((p[2] + 0.5 * d) / d * cells as f64) as usize).min(cells - 1);
            hit[j * cells + i] = true;
        }
        let cover = |r0: f64, r1: f64| {
            let (mut n, mut k) = (0, 0);
            for j in 0..cells {
                for i in 0..cells {
                    let x = (i as f64 + 0.5) / cells as f64 - 0.5;
                    let z = (j as f64 + 0.5) / cells as f64 - 0.5;
                    let rho = 2.0 * (x * x + z * z).sqrt();
                    if rho >= r0 && rho < r1 {
                        n += 1;
                        k += hit[j * cells + i] as usize;
                    }
                }
            }
            k as f64 / n as f64
        };
        let (inner, ring, edge) = (cover(0.0, 0.5), cover(0.7, 0.85), cover(0.9, 1.0));
        assert!(inner > 0.55 && inner < 0.95, "inner {inner}");
        assert!(
            ring < 0.85 * inner && edge < 0.5 * ring,
            "{inner} {ring} {edge}"
        );
        // Flat at the base and at the top (the inversion): 400 m thick.
        let top = c.positions_m.iter().map(|p| p[1]).fold(0.0, f64::max);
        assert!(top <= 1400.0 + 1e-9 && top > 1350.0, "{top}");
    }
}
