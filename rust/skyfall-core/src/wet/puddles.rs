//! Where a wet surface holds standing water: puddles in the low points of a ground's relief,
//! and the roughness of the film elsewhere.
//!
//! A level surface (ground, a flat roof: a normal within [`LEVEL_MIN_UP`] of straight up) is
//! not flat at the scale of a road's ruts and dips. Its relief below the crests is
//! h = [`RELIEF_MM`]·u, with u(x, z) a smooth random field over the ground that is uniform on
//! [0, 1] by construction: value noise summed over three octaves ([`relief_noise`], features
//! from [`RELIEF_SCALE_M`] down), passed through its own distribution function, tabulated
//! once from 2¹⁸ samples ([`relief_u`]). The film takes the first [`WET_FILM_MM`] of a
//! surface's water; the rest (up to the depression storage, [`super::film::STORAGE_MM`]) pools
//! in the low points, at the level L where the mean of max(0, L − h) over the surface equals
//! it. For a uniform relief that mean is L²/(2·RELIEF_MM), so the puddles cover the share
//! L/RELIEF_MM = √(2·pool/RELIEF_MM) of the surface ([`puddle_share`]): the points with
//! u < that share.
//!
//! Outside the puddles the film lies on the surface's texture, and its reflection is rough:
//! each point mirrors about a microfacet normal drawn from the film's GGX distribution
//! ([`super::optics::FILM_ROUGHNESS`]; [`film_normal`]), keyed to a 1 cm cell of the surface so
//! that the grain stays on the road as the camera moves. A puddle's still water is a flat
//! mirror. The grain and the relief are the same in every frame and process: no seed.
//!
//! The constants are documented choices:
//! - [`RELIEF_MM`]: 16 mm between a worn road's crests and its dips over metres (road
//!   unevenness surveys report ruts of 5–20 mm on ordinary city streets); a fully wet road
//!   (0.8 mm pooled) then has puddles on √(1.6/16) = 32 % of its area.
//! - [`RELIEF_SCALE_M`]: the relief's largest features, 2 m (a dip between wheel tracks).

use super::film::WET_FILM_MM;
use glam::Vec3;
use std::sync::OnceLock;

/// The depth of a level surface's relief below its crests, mm.
pub const RELIEF_MM: f64 = 16.0;

/// The size of the relief's largest features (its first octave's lattice), m.
pub const RELIEF_SCALE_M: f32 = 2.0;

/// A face holds puddles when its normal's upward component is at least this (within 18° of
/// level).
pub const LEVEL_MIN_UP: f32 = 0.95;

/// The side of the cells the film's microfacet normals are keyed to, m.
pub const GRAIN_CELL_M: f32 = 0.01;

/// Quantiles tabulated of the relief noise's distribution.
pub const RELIEF_QUANTILES: usize = 33;

/// The octaves' weights (each octave halves the lattice).
const OCTAVE_WEIGHTS: [f32; 3] = [1.0, 0.5, 0.25];

/// Chris Wellons' `lowbias32` integer hash (also in `shaders/common.wgsl`).
pub const fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

/// A number in [0, 1) from the top 24 bits of a hash.
pub(crate) fn unit(h: u32) -> f32 {
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// The hash of the cell of side `cell_m` holding the point `p`, salted (the film's grain, the
/// snow's glints: also `cell_hash` in `shaders/common.wgsl`).
pub(crate) fn cell_hash(p: Vec3, cell_m: f32, salt: u32) -> u32 {
    let c = (p / cell_m).floor();
    hash(c.x as i32 as u32 ^ hash(c.y as i32 as u32 ^ hash(c.z as i32 as u32 ^ salt)))
}

/// The hash of a lattice point (i, j) of octave (salt) `salt`.
fn lattice(i: i32, j: i32, salt: u32) -> u32 {
    hash(i as u32 ^ hash(j as u32 ^ hash(salt)))
}

/// One octave of value noise at (x, z) in lattice units: the lattice's values in [0, 1),
/// blended by the smoothstep of the fractions.
fn value_noise(x: f32, z: f32, salt: u32) -> f32 {
    let (fx, fz) = (x.floor(), z.floor());
    let (i, j) = (fx as i32, fz as i32);
    let (tx, tz) = (x - fx, z - fz);
    let (sx, sz) = (tx * tx * (3.0 - 2.0 * tx), tz * tz * (3.0 - 2.0 * tz));
    let v = |di: i32, dj: i32| unit(lattice(i.wrapping_add(di), j.wrapping_add(dj), salt));
    let a = v(0, 0) + (v(1, 0) - v(0, 0)) * sx;
    let b = v(0, 1) + (v(1, 1) - v(0, 1)) * sx;
    a + (b - a) * sz
}

/// The relief's noise at the ground point (x, z), m: three octaves of value noise, the first
/// on a [`RELIEF_SCALE_M`] lattice, weighted 1, 1/2, 1/4 and divided by their sum (0–1, not
/// uniform: see [`relief_u`]).
pub fn relief_noise(x: f32, z: f32) -> f32 {
    let mut sum = 0.0;
    let mut scale = 1.0 / RELIEF_SCALE_M;
    for (o, w) in OCTAVE_WEIGHTS.iter().enumerate() {
        sum += w * value_noise(x * scale, z * scale, o as u32);
        scale *= 2.0;
    }
    sum / OCTAVE_WEIGHTS.iter().sum::<f32>()
}

/// The noise's quantiles at probabilities k/32, k = 0..32, from 2¹⁸ samples on a 512 × 512
/// grid of spacing 0.613 m (incommensurate with the lattices), with the 0 and 1 quantiles set
/// to the noise's bounds. Computed once.
pub fn relief_quantiles() -> &'static [f32; RELIEF_QUANTILES] {
    static TABLE: OnceLock<[f32; RELIEF_QUANTILES]> = OnceLock::new();
    TABLE.get_or_init(|| {
        const SIDE: usize = 512;
        let mut v: Vec<f32> = (0..SIDE * SIDE)
            .map(|k| {
                let (i, j) = ((k % SIDE) as f32, (k / SIDE) as f32);
                relief_noise(0.613 * i - 150.0, 0.613 * j - 150.0)
            })
            .collect();
        v.sort_by(f32::total_cmp);
        let last = (RELIEF_QUANTILES - 1) as f64;
        std::array::from_fn(|k| match k {
            0 => 0.0,
            k if k == RELIEF_QUANTILES - 1 => 1.0,
            k => v[(k as f64 / last * (v.len() - 1) as f64).round() as usize],
        })
    })
}

/// The relief's u at the ground point (x, z), uniform on [0, 1]: the noise through its
/// tabulated distribution function, linear between the quantiles.
pub fn relief_u(x: f32, z: f32) -> f32 {
    let q = relief_quantiles();
    let n = relief_noise(x, z);
    let k = q
        .partition_point(|&v| v <= n)
        .clamp(1, RELIEF_QUANTILES - 1);
    let (lo, hi) = (q[k - 1], q[k]);
    let t = if hi > lo {
        ((n - lo) / (hi - lo)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ((k - 1) as f32 + t) / (RELIEF_QUANTILES - 1) as f32
}

/// The share of a level surface under puddles when it holds `water_mm`: what exceeds the film,
/// up to the storage, pooled in a uniform relief of depth [`RELIEF_MM`]: √(2·pool/RELIEF_MM).
pub fn puddle_share(water_mm: f64) -> f32 {
    let pool = (water_mm - WET_FILM_MM).max(0.0);
    (2.0 * pool / RELIEF_MM).sqrt().min(1.0) as f32
}

/// Whether the point `p` of a face of unit normal `n` holding `water_mm` lies in a puddle.
pub fn in_puddle(p: Vec3, n: Vec3, water_mm: f64) -> bool {
    n.y >= LEVEL_MIN_UP && water_mm > WET_FILM_MM && relief_u(p.x, p.z) < puddle_share(water_mm)
}

/// The film's microfacet normal at `p` on a face of unit normal `n`: GGX (Trowbridge–Reitz)
/// of roughness `alpha`, sampled by the two numbers the point's [`GRAIN_CELL_M`] cell hashes
/// to (tan²θ = α²·u₁/(1 − u₁), φ = 2π·u₂ about `n`).
pub fn film_normal(p: Vec3, n: Vec3, alpha: f32) -> Vec3 {
    let h = cell_hash(p, GRAIN_CELL_M, 0x9e37);
    let (u1, u2) = (unit(h), unit(hash(h)));
    let tan = alpha * (u1 / (1.0 - u1)).sqrt();
    let cos_t = 1.0 / (1.0 + tan * tan).sqrt();
    let sin_t = tan * cos_t;
    let (sin_p, cos_p) = (std::f32::consts::TAU * u2).sin_cos();
    let (t, b) = tangents(n);
    (n * cos_t + (t * cos_p + b * sin_p) * sin_t).normalize()
}

/// Two unit tangents of the unit normal `n` (its frame for [`film_normal`]).
fn tangents(n: Vec3) -> (Vec3, Vec3) {
    let a = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Z };
    let t = n.cross(a).normalize();
    (t, n.cross(t))
}

/// The direction a view ray `d` (unit) leaves a wet face of normal `n` at `p`: mirrored about
/// `n` in a puddle (`still`), else about the film's microfacet normal there, or about `n` when
/// that would send it into the face.
pub fn reflected(d: Vec3, n: Vec3, p: Vec3, still: bool, alpha: f32) -> Vec3 {
    let mirror = d - 2.0 * d.dot(n) * n;
    if still {
        return mirror;
    }
    let m = film_normal(p, n, alpha);
    let r = d - 2.0 * d.dot(m) * m;
    if r.dot(n) > 0.0 { r } else { mirror }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_relief_is_uniform_away_from_the_tables_samples() {
        // 160 000 points on another grid, far from the table's: each tenth of [0, 1] holds
        // a tenth of them within 1.5 % (the base lattice's ~8 000 cells over the grid: a
        // tenth's share varies by about 0.35 %).
        let mut bins = [0u32; 10];
        let side = 400;
        for k in 0..side * side {
            let (i, j) = ((k % side) as f32, (k / side) as f32);
            let u = relief_u(1000.0 + 0.457 * i, -700.0 + 0.457 * j);
            assert!((0.0..=1.0).contains(&u));
            bins[((u * 10.0) as usize).min(9)] += 1;
        }
        for b in bins {
            let share = f64::from(b) / f64::from(side * side);
            assert!((share - 0.1).abs() < 0.015, "{bins:?}");
        }
    }

    #[test]
    fn the_puddles_hold_the_pooled_water() {
        // The mean of max(0, L − RELIEF·u) over a uniform u, numerically, equals the pool at
        // the share the formula gives (L = share·RELIEF).
        for water in [0.25, 0.5, 1.0] {
            let share = f64::from(puddle_share(water));
            let level = share * RELIEF_MM;
            let steps = 100_000;
            let held: f64 = (0..steps)
                .map(|i| (level - RELIEF_MM * (i as f64 + 0.5) / steps as f64).max(0.0))
                .sum::<f64>()
                / steps as f64;
            assert!(
                (held - (water - WET_FILM_MM)).abs() < 1e-6,
                "{water}: {held}"
            );
        }
        assert_eq!(puddle_share(WET_FILM_MM), 0.0);
        assert!((puddle_share(1.0) - 0.316_227_77).abs() < 1e-6);
    }

    #[test]
    fn film_normals_follow_ggx_and_puddles_need_a_level_face() {
        // tan²θ of the sampled normals is α²·u/(1 − u) for u uniform: its median is α².
        let alpha = 0.12;
        let mut t2: Vec<f32> = (0..20_000)
            .map(|k| {
                let p = Vec3::new((k % 200) as f32 * 0.013, 0.0, (k / 200) as f32 * 0.013);
                let m = film_normal(p, Vec3::Y, alpha);
                assert!((m.length() - 1.0).abs() < 1e-5);
                (1.0 - m.y * m.y) / (m.y * m.y)
            })
            .collect();
        t2.sort_by(f32::total_cmp);
        let median = t2[t2.len() / 2];
        assert!((median / (alpha * alpha) - 1.0).abs() < 0.05, "{median}");
        let p = (0..1000)
            .map(|k| Vec3::new(k as f32 * 0.37, 0.0, 1.0))
            .find(|p| relief_u(p.x, p.z) < 0.1)
            .unwrap();
        assert!(in_puddle(p, Vec3::Y, 1.0));
        assert!(!in_puddle(p, Vec3::new(0.0, 0.9, 0.436).normalize(), 1.0));
        assert!(!in_puddle(p, Vec3::Y, WET_FILM_MM));
        // a mirrored ray never enters the face
        for k in 0..1000 {
            let p = Vec3::new(k as f32 * 0.011, 0.0, 3.0);
            let d = Vec3::new(0.0, -0.05, -1.0).normalize();
            assert!(reflected(d, Vec3::Y, p, false, alpha).y > 0.0);
        }
    }
}
