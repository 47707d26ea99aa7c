//! A cloud's shape as a union of billows: spheres grown on spheres, cut flat at the base.
//!
//! Cumulus are made of convective turrets, each of smaller turrets, down to the scale where
//! mixing smooths them: the "cauliflower" of the cloud atlases (WMO International Cloud
//! Atlas, cumulus). A shape is grown from root spheres: each sphere of one level carries
//! children of about half its radius on its upper surface (a turret rises, so none grow
//! downward), for a few levels. The union is cut at the condensation level, which makes the
//! base flat (a stratocumulus deck is cut at its top too: the inversion that caps it), and its surface is perturbed by value noise at the smallest billows' scale.
//! Spheres are binned in a uniform grid so a point is tested against its neighbours only.

use glam::DVec3;
use rand::Rng;
use rand_pcg::Pcg64Mcg;

use crate::seed::{derive, splitmix64};

/// A billow: a sphere, m.
#[derive(Debug, Clone, Copy)]
pub struct Billow {
    /// Centre, m.
    pub c: DVec3,
    /// Radius, m.
    pub r: f64,
}

/// How a level of children grows on its parents.
#[derive(Debug, Clone, Copy)]
pub struct Level {
    /// Children per parent.
    pub children: usize,
    /// A child's radius over its parent's: uniform in this range.
    pub ratio: (f64, f64),
}

/// Grows `levels` of children on `roots` (each child on its parent's upper surface).
pub fn grow(roots: Vec<Billow>, levels: &[Level], rng: &mut Pcg64Mcg) -> Vec<Billow> {
    let mut all = roots.clone();
    let mut parents = roots;
    for level in levels {
        let mut next = Vec::with_capacity(parents.len() * level.children);
        for p in &parents {
            for _ in 0..level.children {
                // A direction on the sphere, folded upward: turrets rise and spread; the
                // flat base is the cut's.
                let z = 2.0 * rng.random::<f64>() - 1.0;
                let a = rng.random::<f64>() * std::f64::consts::TAU;
                let s = (1.0 - z * z).sqrt();
                let d = DVec3::new(s * a.cos(), 0.15 + 0.85 * z.abs(), s * a.sin()).normalize();
                let ratio = level.ratio.0 + (level.ratio.1 - level.ratio.0) * rng.random::<f64>();
                let out = 0.7 + 0.25 * rng.random::<f64>();
                next.push(Billow {
                    c: p.c + d * (p.r * out),
                    r: p.r * ratio,
                });
            }
        }
        all.extend_from_slice(&next);
        parents = next;
    }
    all
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
                let h = derive(seed, &[(x + dx) as u64, (y + dy) as u64, (z + dz) as u64]);
                acc += w * ((h >> 11) as f64 / (1u64 << 53) as f64);
            }
        }
    }
    acc
}

/// Two octaves of value noise, in [0, 1).
fn fractal_noise(seed: u64, p: DVec3) -> f64 {
    (2.0 * value_noise(seed, p) + value_noise(splitmix64(seed ^ 1), 2.0 * p)) / 3.0
}

/// Grid cells per axis, at most.
const GRID: usize = 32;

/// The union of billows above a flat base, with a noise-perturbed surface.
pub struct Field {
    billows: Vec<Billow>,
    /// Lowest corner of the bounding box, m.
    pub lo: DVec3,
    /// Highest corner, m.
    pub hi: DVec3,
    base_m: f64,
    top_m: f64,
    /// The surface moves in and out by up to this share of a billow's radius.
    roughness: f64,
    noise_seed: u64,
    noise_scale_m: f64,
    dims: [usize; 3],
    cell: DVec3,
    cells: Vec<Vec<u32>>,
}

impl Field {
    /// The field of `billows` cut at `base_m` and `top_m` (∞: none), its surface perturbed by
    /// `roughness` of each billow's radius at the noise scale `noise_scale_m`.
    pub fn new(
        billows: Vec<Billow>,
        base_m: f64,
        top_m: f64,
        roughness: f64,
        noise_seed: u64,
        noise_scale_m: f64,
    ) -> Self {
        let reach = 1.0 + roughness;
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for b in &billows {
            lo = lo.min(b.c - DVec3::splat(b.r * reach));
            hi = hi.max(b.c + DVec3::splat(b.r * reach));
        }
        lo.y = lo.y.max(base_m);
        hi.y = hi.y.min(top_m);
        hi.y = hi.y.max(lo.y + 1e-6);
        let size = hi - lo;
        let longest = size.max_element();
        let dims = [
            ((GRID as f64 * size.x / longest).ceil() as usize).clamp(1, GRID),
            ((GRID as f64 * size.y / longest).ceil() as usize).clamp(1, GRID),
            ((GRID as f64 * size.z / longest).ceil() as usize).clamp(1, GRID),
        ];
        let cell = size / DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64);
        let mut cells = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
        for (i, b) in billows.iter().enumerate() {
            let a = Self::index_of(lo, cell, dims, b.c - DVec3::splat(b.r * reach));
            let z = Self::index_of(lo, cell, dims, b.c + DVec3::splat(b.r * reach));
            for k in a[2]..=z[2] {
                for j in a[1]..=z[1] {
                    for n in a[0]..=z[0] {
                        cells[(k * dims[1] + j) * dims[0] + n].push(i as u32);
                    }
                }
            }
        }
        Self {
            billows,
            lo,
            hi,
            base_m,
            top_m,
            roughness,
            noise_seed,
            noise_scale_m,
            dims,
            cell,
            cells,
        }
    }

    fn index_of(lo: DVec3, cell: DVec3, dims: [usize; 3], p: DVec3) -> [usize; 3] {
        let t = (p - lo) / cell;
        let clamp = |v: f64, n: usize| (v.floor().max(0.0) as usize).min(n - 1);
        [
            clamp(t.x, dims[0]),
            clamp(t.y, dims[1]),
            clamp(t.z, dims[2]),
        ]
    }

    /// `None` outside the cloud; inside, the depth below its surface, m (the deepest any
    /// billow or the base puts `p`, before the noise: a lower bound on the distance out).
    pub fn depth(&self, p: DVec3) -> Option<f64> {
        if p.y < self.base_m || p.y > self.top_m {
            return None;
        }
        let ix = Self::index_of(self.lo, self.cell, self.dims, p);
        let list = &self.cells[(ix[2] * self.dims[1] + ix[1]) * self.dims[0] + ix[0]];
        // The smallest normalised distance |p − c|/r decides inside; the noise only moves
        // points within `roughness` of a surface, so it is evaluated only there.
        let mut nearest = f64::INFINITY;
        let mut depth = f64::NEG_INFINITY;
        for &i in list {
            let b = self.billows[i as usize];
            let d = (p - b.c).length();
            nearest = nearest.min(d / b.r);
            depth = depth.max(b.r - d);
        }
        if nearest >= 1.0 + self.roughness {
            return None;
        }
        if nearest > 1.0 - self.roughness {
            let n = fractal_noise(self.noise_seed, p / self.noise_scale_m);
            if nearest >= 1.0 + self.roughness * (2.0 * n - 1.0) {
                return None;
            }
        }
        Some(depth.min(p.y - self.base_m).min(self.top_m - p.y).max(0.0))
    }
}
