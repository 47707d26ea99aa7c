//! Sky illuminance with occlusion (seed 002, eq. 8): E_n(P) = ∫ L(ω) τ(ω) H(P, ω) max(0, n·ω) dω.
//!
//! Directions: a product rule over the hemisphere, Gauss–Legendre in μ = sin γ (dω = dμ dφ)
//! times the periodic midpoint rule in azimuth with 4 azimuths per ring. It is exact for the
//! open overcast sky with two rings and converges spectrally for every smooth sky; with
//! occluders H is a step in each direction, the error falls as O(1/rings) (measured in
//! `benches/results/sky.md`). Unlike the seed's uniform grid on the projected disk, which
//! carries cos θ for the horizontal only, explicit weights also give the vertical normals.
//!
//! The five normals are up, +X, −X, +Z, −Z: every face of the box scene (and the ground)
//! faces one of them; a face facing down sees no sky.

use super::model::Sky;
use crate::error::{Range, Result};
use crate::scene::boxes::{BoxScene, SceneBox, T_MIN};
use glam::Vec3;
use std::f64::consts::{PI, TAU};

/// Number of normals per point: up, +X, −X, +Z, −Z.
pub const CHANNELS: usize = 5;
/// The normals, in channel order.
pub const NORMALS: [Vec3; CHANNELS] = [Vec3::Y, Vec3::X, Vec3::NEG_X, Vec3::Z, Vec3::NEG_Z];
/// Valid numbers of sample directions.
pub const SAMPLES: Range = Range::closed(4.0, 1_048_576.0, "directions");

/// Gauss–Legendre nodes and weights on [0, 1].
pub fn gauss_legendre_01(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = Vec::with_capacity(n);
    let mut weights = Vec::with_capacity(n);
    for i in 0..n {
        // Newton on P_n from Tricomi's initial guess.
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 0 { 1.0 } else if n == 1 { x } else { p1 };
            let pm = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (x * pn - pm) / (x * x - 1.0);
            let dx = pn / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        nodes.push(0.5 * (1.0 - x));
        weights.push(1.0 / ((1.0 - x * x) * dp * dp));
    }
    (nodes, weights)
}

/// Sample directions over the upper hemisphere with each one's contribution to the five
/// normals' illuminance (relative to E) when the sky is visible along it.
#[derive(Debug, Clone, PartialEq)]
pub struct SkySamples {
    /// Unit directions.
    pub dirs: Vec<Vec3>,
    /// L τ max(0, n·ω) dω / π per direction and normal.
    pub weights: Vec<[f32; CHANNELS]>,
}

impl SkySamples {
    /// About `samples` directions: `rings` = round(√(samples/4)) Gauss–Legendre rings of
    /// 4·rings azimuths (4·rings² in all).
    pub fn new(sky: &Sky, samples: usize) -> Result<Self> {
        SAMPLES.check("samples", None, samples as f64)?;
        let rings = ((samples as f64 / 4.0).sqrt().round() as usize).max(1);
        let az_n = 4 * rings;
        let (mus, ws) = gauss_legendre_01(rings);
        let mut dirs = Vec::with_capacity(rings * az_n);
        let mut weights = Vec::with_capacity(rings * az_n);
        for (&mu, &wm) in mus.iter().zip(&ws) {
            let c = (1.0 - mu * mu).sqrt();
            for k in 0..az_n {
                let az = (k as f64 + 0.5) * TAU / az_n as f64;
                let dir = Vec3::new((c * az.sin()) as f32, mu as f32, (-c * az.cos()) as f32);
                let l = sky.received(dir) * wm * TAU / az_n as f64 / PI;
                weights.push(NORMALS.map(|n| (l * f64::from(n.dot(dir).max(0.0))) as f32));
                dirs.push(dir);
            }
        }
        Ok(SkySamples { dirs, weights })
    }

    /// Number of directions.
    pub fn len(&self) -> usize {
        self.dirs.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.dirs.is_empty()
    }
}

/// Whether the ray from `p` along `dir` meets a box (a box containing `p` counts; one `p` sits
/// on while the ray leaves it does not).
#[inline]
pub fn occluded(boxes: &[SceneBox], p: Vec3, dir: Vec3) -> bool {
    let safe = |d: f32| if d.abs() < 1e-20 { if d < 0.0 { -1e-20 } else { 1e-20 } } else { d };
    let inv = Vec3::new(1.0 / safe(dir.x), 1.0 / safe(dir.y), 1.0 / safe(dir.z));
    boxes.iter().any(|b| {
        let t1 = (b.min_m - p) * inv;
        let t2 = (b.max_m - p) * inv;
        let lo = t1.min(t2);
        let hi = t1.max(t2);
        let t_near = lo.max_element();
        let t_far = hi.min_element();
        t_far > T_MIN && t_near <= t_far
    })
}

/// The boxes an upward ray from height `y_m` can meet (those reaching above it).
pub fn boxes_above(scene: &BoxScene, y_m: f32) -> Vec<SceneBox> {
    scene.boxes.iter().filter(|b| b.max_m.y > y_m).copied().collect()
}

/// Illuminance on the five normals at `p`, relative to E (1 on the open ground).
pub fn irradiance(boxes_above_p: &[SceneBox], samples: &SkySamples, p: Vec3) -> [f32; CHANNELS] {
    let mut acc = [0.0f32; CHANNELS];
    for (dir, w) in samples.dirs.iter().zip(&samples.weights) {
        if !occluded(boxes_above_p, p, *dir) {
            for (a, wk) in acc.iter_mut().zip(w) {
                *a += wk;
            }
        }
    }
    acc
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sky::cie::SkyKind;

    #[test]
    fn gauss_legendre_integrates_polynomials() {
        let (x, w) = gauss_legendre_01(5);
        let s: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(9)).sum();
        assert!((s - 0.1).abs() < 1e-13, "{s}");
        let (x1, w1) = gauss_legendre_01(1);
        assert!((x1[0] - 0.5).abs() < 1e-15 && (w1[0] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn open_overcast_sky_gives_e_and_the_vertical_ratio() {
        let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
        let s = SkySamples::new(&sky, 1024).unwrap();
        let e = irradiance(&[], &s, Vec3::ZERO);
        assert!((e[0] - 1.0).abs() < 1e-5, "{e:?}");
        // Vertical/horizontal illuminance of the CIE overcast sky: 3/14 + 4/(7π) = 0.3962.
        let ratio = 3.0 / 14.0 + 4.0 / (7.0 * PI);
        for (k, v) in e.iter().enumerate().skip(1) {
            assert!((f64::from(*v) - ratio).abs() < 2e-3, "{k} {v} vs {ratio}");
        }
    }

    #[test]
    fn a_point_inside_or_under_a_box_sees_no_sky() {
        let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
        let s = SkySamples::new(&sky, 256).unwrap();
        let b = SceneBox { min_m: Vec3::new(-1.0, 2.0, -1.0), max_m: Vec3::new(1.0, 3.0, 1.0), albedo: Vec3::ONE };
        assert_eq!(irradiance(&[b], &s, Vec3::new(0.0, 2.5, 0.0)), [0.0; 5]);
        // on its roof: the open sky for up
        let top = irradiance(&[b], &s, Vec3::new(0.0, 3.0, 0.0));
        assert!((top[0] - 1.0).abs() < 1e-5);
        // far below its 2 m × 2 m underside at 2 m above: the blocked solid angle is small but not zero
        let under = irradiance(&[b], &s, Vec3::new(0.0, 0.0, 0.0));
        assert!(under[0] < 0.8 && under[0] > 0.3, "{under:?}");
    }
}
