//! Sky illuminance with occlusion (Yamamoto & Tadamura, eq. 8): E_n(P) = ∫ L(ω) τ(ω) H(P, ω) max(0, n·ω) dω.
//!
//! Per azimuth the integral over elevation is done exactly for the scene's geometry: along an
//! azimuth each box hides one interval of elevations (seen from P, the vertical half-plane at
//! that azimuth cuts the box in a rectangle), so the visible elevations are [0, π/2] less a
//! union of intervals, and the sky's contribution over each visible interval is read from
//! cumulative tables of ∫ L τ sin γ cos γ dγ (horizontal surfaces) and ∫ L τ cos² γ dγ
//! (vertical ones) along that azimuth, precomputed once per sky on 512 elevation steps with
//! 4-point Gauss–Legendre each. Only the azimuths are sampled (periodic midpoint rule): the
//! visible elevation varies continuously with azimuth, with kinks at box corners, so the error
//! falls as O(1/azimuths²) (measured in `benches/results/sky.md`). Unlike ray sampling (the
//! seed's grid on the projected disk, or any set of directions), whose error at an occluder's
//! edge falls only as O(1/directions^½), this is exact in elevation.
//!
//! The five normals are up, +X, −X, +Z, −Z: every face of the box scene (and the ground)
//! faces one of them; a face looking down sees no sky.

use super::model::Sky;
use super::profile;
use crate::error::{Range, Result, check_cancel};
use crate::scene::boxes::{BoxScene, SceneBox};
use crate::scene::raycast::T_MIN;
use glam::Vec3;
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::sync::atomic::{AtomicBool, Ordering};

/// Number of normals per point: up, +X, −X, +Z, −Z.
pub const CHANNELS: usize = 5;
/// The normals, in channel order.
pub const NORMALS: [Vec3; CHANNELS] = [Vec3::Y, Vec3::X, Vec3::NEG_X, Vec3::Z, Vec3::NEG_Z];
/// Valid numbers of azimuths.
pub const AZIMUTHS: Range = crate::ranges::SAMPLES.range;
/// Elevation steps of the cumulative tables.
const STEPS: usize = 512;

/// 4-point Gauss–Legendre nodes and weights on [0, 1].
const GL4: [(f64, f64); 4] = [
    (0.069_431_844_202_973_71, 0.173_927_422_568_726_93),
    (0.330_009_478_207_571_9, 0.326_072_577_431_273_07),
    (0.669_990_521_792_428_1, 0.326_072_577_431_273_07),
    (0.930_568_155_797_026_3, 0.173_927_422_568_726_93),
];

/// The midpoints of `azimuths` equal sectors, as unit horizontal directions (sin φ, −cos φ):
/// the azimuths of [`SkyTable`] and [`super::horizon::Horizon`].
pub fn azimuth_dirs(azimuths: usize) -> Vec<(f64, f64)> {
    let dphi = TAU / azimuths as f64;
    (0..azimuths)
        .map(|k| {
            let phi = (k as f64 + 0.5) * dphi;
            (phi.sin(), -phi.cos())
        })
        .collect()
}

/// A sky tabulated for illuminance: per azimuth, cumulative integrals over elevation.
#[derive(Debug, Clone, PartialEq)]
pub struct SkyTable {
    /// Azimuths (midpoints of equal sectors), as unit horizontal directions (sin φ, −cos φ).
    dirs: Vec<(f64, f64)>,
    /// The integrals, per azimuth or (a symmetric sky) at a few elevations.
    columns: Columns,
}

/// A [`SkyTable`]'s cumulative integrals.
#[derive(Debug, Clone, PartialEq)]
enum Columns {
    /// A sky that varies with azimuth (a general type with a sun).
    Azimuths {
        /// Per azimuth, STEPS + 1 pairs (∫₀^γ L τ sin γ cos γ dγ, ∫₀^γ L τ cos² γ dγ) / π · Δφ:
        /// the horizontal and the vertical surfaces' cumulative integrals, side by side (a
        /// node's edge reads both).
        cum: Vec<[f64; 2]>,
        /// Each azimuth's `up` and `side` read at the zenith (as [`SkyTable::read`] reads them),
        /// the end of every node's highest visible interval.
        top: Vec<(f64, f64)>,
    },
    /// A sky the same at every azimuth: one azimuth's integrals at [`profile::AT_STEP`], read
    /// through [`profile::weights`].
    Symmetric(Box<profile::Coarse>),
}

impl SkyTable {
    /// Tabulates `sky` (luminance received at the ground, relative to E/π) on `azimuths` sectors.
    pub fn new(sky: &Sky, azimuths: usize) -> Result<Self> {
        Self::new_cancellable(sky, azimuths, &AtomicBool::new(false))
    }

    /// [`SkyTable::new`], stopping with [`Error::Cancelled`](crate::Error::Cancelled) soon after `cancel` is set
    /// (checked before every azimuth: 2048 sky evaluations, well under a millisecond; azimuths
    /// in parallel). A sky the same
    /// at every azimuth ([`super::cie::SkyKind::symmetric`]) is tabulated along one.
    pub fn new_cancellable(sky: &Sky, azimuths: usize, cancel: &AtomicBool) -> Result<Self> {
        if sky.kind.symmetric() {
            Self::symmetric(sky, azimuths)
        } else {
            Self::from_radiance(|dir| sky.received(dir), azimuths, cancel)
        }
    }

    /// A sky the same at every azimuth, tabulated along one and read at a few elevations.
    fn symmetric(sky: &Sky, azimuths: usize) -> Result<Self> {
        AZIMUTHS.check("samples", None, azimuths as f64)?;
        let dphi = TAU / azimuths as f64;
        let dirs = azimuth_dirs(azimuths);
        let mut cum = vec![[0.0; 2]; STEPS + 1];
        Self::cumulative(&|dir| sky.received(dir), dirs[0], dphi, &mut cum);
        let at = |c: usize| profile::AT_STEP.map(|j| cum[usize::from(j)][c]);
        let coarse = profile::Coarse {
            up: at(0),
            side: at(1),
        };
        Ok(SkyTable {
            dirs,
            columns: Columns::Symmetric(Box::new(coarse)),
        })
    }

    /// The table along every azimuth of any sky's radiance: `radiance(dir)` the luminance
    /// received at the ground from unit direction `dir` (above the horizon), relative to E/π
    /// ([`Sky::received`] for a sky; a sky with clouds in it, `crate::cloud::dome`).
    pub fn from_radiance(
        radiance: impl Fn(Vec3) -> f64 + Sync,
        azimuths: usize,
        cancel: &AtomicBool,
    ) -> Result<Self> {
        AZIMUTHS.check("samples", None, azimuths as f64)?;
        let dphi = TAU / azimuths as f64;
        let dirs = azimuth_dirs(azimuths);
        // 2 x 269 MB at 65536 azimuths: refused as OutOfMemory, not an abort.
        let n = azimuths * (STEPS + 1);
        let mut cum = crate::error::try_filled("the sky table", n, [0.0f64; 2])?;
        cum.par_chunks_mut(STEPS + 1)
            .zip(&dirs)
            .for_each(|(row, &dir)| {
                if !cancel.load(Ordering::Relaxed) {
                    Self::cumulative(&radiance, dir, dphi, row);
                }
            });
        check_cancel(cancel, "the sky table")?;
        let top = cum
            .chunks_exact(STEPS + 1)
            .map(|row| {
                <&[[f64; 2]; STEPS + 1]>::try_from(row)
                    .map_or((0.0, 0.0), |r| Self::read(r, FRAC_PI_2))
            })
            .collect();
        Ok(SkyTable {
            dirs,
            columns: Columns::Azimuths { cum, top },
        })
    }

    /// [`SkyTable::new`] along every azimuth at 512 elevation steps even for a symmetric sky:
    /// the reference its reading at a few elevations ([`super::profile`]) is measured against.
    pub fn per_azimuth(sky: &Sky, azimuths: usize, cancel: &AtomicBool) -> Result<Self> {
        Self::from_radiance(|dir| sky.received(dir), azimuths, cancel)
    }

    /// One azimuth's STEPS + 1 cumulative pairs (up, side) along horizontal direction
    /// (sx, sz), each times Δφ/π, into `cum`.
    fn cumulative(
        radiance: &impl Fn(Vec3) -> f64,
        (sx, sz): (f64, f64),
        dphi: f64,
        cum: &mut [[f64; 2]],
    ) {
        let h = FRAC_PI_2 / STEPS as f64;
        let (mut a, mut b) = (0.0, 0.0);
        cum[0] = [0.0, 0.0];
        for j in 0..STEPS {
            for (x, w) in GL4 {
                let g = (j as f64 + x) * h;
                let (sg, cg) = g.sin_cos();
                let dir = Vec3::new((cg * sx) as f32, sg as f32, (cg * sz) as f32);
                let l = radiance(dir) * w * h * dphi / PI;
                a += l * sg * cg;
                b += l * cg * cg;
            }
            cum[j + 1] = [a, b];
        }
    }

    /// The symmetric sky's integrals at a few elevations, if it is one.
    pub fn coarse(&self) -> Option<&profile::Coarse> {
        match &self.columns {
            Columns::Symmetric(c) => Some(c),
            Columns::Azimuths { .. } => None,
        }
    }

    /// Number of azimuths.
    pub fn azimuths(&self) -> usize {
        self.dirs.len()
    }

    /// The azimuths, as unit horizontal directions (sin φ, −cos φ).
    pub fn dirs(&self) -> &[(f64, f64)] {
        &self.dirs
    }

    /// One azimuth's `row` read at elevation `g` (linear between steps).
    #[inline(always)]
    fn read(row: &[[f64; 2]; STEPS + 1], g: f64) -> (f64, f64) {
        let x = (g / FRAC_PI_2 * STEPS as f64).clamp(0.0, STEPS as f64);
        let j = (x as usize).min(STEPS - 1);
        let f = x - j as f64;
        let ([u0, s0], [u1, s1]) = (row[j], row[j + 1]);
        (u0 + f * (u1 - u0), s0 + f * (s1 - s0))
    }
}

/// The elevations (radians, in [0, π/2]) box `b` hides along horizontal direction (dx, dz)
/// seen from `p`, if any.
#[inline]
fn hidden(b: &SceneBox, p: Vec3, dx: f64, dz: f64) -> Option<(f64, f64)> {
    let y_hi = f64::from(b.max_m.y - p.y);
    if y_hi <= 0.0 {
        return None;
    }
    // Horizontal distances along the azimuth at which the half-plane is inside the footprint.
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    for (o, d, lo, hi) in [
        (p.x, dx, b.min_m.x, b.max_m.x),
        (p.z, dz, b.min_m.z, b.max_m.z),
    ] {
        let (o, lo, hi) = (f64::from(o), f64::from(lo), f64::from(hi));
        if d.abs() < 1e-12 {
            if o < lo || o > hi {
                return None;
            }
        } else {
            let (a, c) = ((lo - o) / d, (hi - o) / d);
            t0 = t0.max(a.min(c));
            t1 = t1.min(a.max(c));
        }
    }
    if t1 <= f64::from(T_MIN) || t0 > t1 {
        return None;
    }
    let d0 = t0.max(0.0);
    let hi = y_hi.atan2(d0);
    let y_lo = f64::from(b.min_m.y - p.y);
    let lo = if y_lo <= 0.0 { 0.0 } else { y_lo.atan2(t1) };
    (hi > lo).then_some((lo, hi))
}

/// The boxes that can hide sky from height `y_m` (those reaching above it).
pub fn boxes_above(scene: &BoxScene, y_m: f32) -> Vec<SceneBox> {
    scene
        .boxes
        .iter()
        .filter(|b| b.max_m.y > y_m)
        .copied()
        .collect()
}

/// Illuminance on the five normals at `p`, relative to E (1 on the open ground).
pub fn irradiance(boxes_above_p: &[SceneBox], table: &SkyTable, p: Vec3) -> [f32; CHANNELS] {
    let mut sky = VisibleSky::default();
    sky.find(boxes_above_p, &table.dirs, p);
    sky.light(table)
}

/// The sky a point sees, per azimuth: what the boxes fix, whatever the sky. Azimuth k's visible
/// elevations are `edges[..]` read as a₀ b₀ a₁ b₁ … (radians, the intervals [a, b] in
/// increasing order) and, when their count (`counts[k]`) is odd, a last a whose interval
/// ends at π/2. [`VisibleSky::light`] turns it into illuminance under a sky.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VisibleSky {
    /// Edges per azimuth.
    pub counts: Vec<u16>,
    /// The edges, azimuth after azimuth.
    pub edges: Vec<f64>,
    /// Scratch: one azimuth's hidden spans.
    spans: Vec<(f64, f64)>,
}

impl VisibleSky {
    /// Appends the visible elevations of `p` along each of `dirs` (unit horizontal
    /// directions), hidden by `boxes_above_p`.
    pub fn find(&mut self, boxes_above_p: &[SceneBox], dirs: &[(f64, f64)], p: Vec3) {
        for &(dx, dz) in dirs {
            self.spans.clear();
            self.spans
                .extend(boxes_above_p.iter().filter_map(|b| hidden(b, p, dx, dz)));
            self.spans.sort_by(|a, b| a.0.total_cmp(&b.0));
            // Visible elevations: [0, π/2] less the union of the hidden spans.
            let start = self.edges.len();
            let mut from = 0.0;
            for &(lo, hi) in &self.spans {
                if lo > from {
                    self.edges.extend([from, lo]);
                }
                from = f64::max(from, hi);
            }
            if from < FRAC_PI_2 {
                self.edges.push(from);
            }
            // At most two edges per box and one more: 8193 for a scene's most boxes
            // (`scene::boxes::MAX_BOXES`, 4096, which every scene is checked against).
            self.counts
                .push(u16::try_from(self.edges.len() - start).unwrap_or(u16::MAX));
        }
    }

    /// Forgets the point (keeps the buffers).
    pub fn clear(&mut self) {
        self.counts.clear();
        self.edges.clear();
    }

    /// The illuminance on the five normals relative to E under `table`'s sky, of the point
    /// whose visible elevations are `counts` and `edges` (one count per azimuth of `table`).
    pub fn light_parts(table: &SkyTable, counts: &[u16], edges: &[f64]) -> [f32; CHANNELS] {
        let (cum, top) = match &table.columns {
            Columns::Symmetric(c) => {
                return profile::light(&profile::weights(&table.dirs, counts, edges), c);
            }
            Columns::Azimuths { cum, top } => (cum, top),
        };
        let mut acc = [0.0f64; CHANNELS];
        let mut at_edge = 0;
        for ((&(dx, dz), &n), (row, &(ut, st))) in table
            .dirs
            .iter()
            .zip(counts)
            .zip(cum.chunks_exact(STEPS + 1).zip(top))
        {
            let e = &edges[at_edge..at_edge + usize::from(n)];
            at_edge += usize::from(n);
            let Ok(row) = <&[[f64; 2]; STEPS + 1]>::try_from(row) else {
                continue; // (every row is STEPS + 1 long)
            };
            let (mut up, mut side) = (0.0, 0.0);
            let (pairs, last) = e.as_chunks::<2>();
            for &[a, b] in pairs {
                let ((ua, sa), (ub, sb)) = (SkyTable::read(row, a), SkyTable::read(row, b));
                up += ub - ua;
                side += sb - sa;
            }
            if let &[a] = last {
                let (ua, sa) = SkyTable::read(row, a);
                up += ut - ua;
                side += st - sa;
            }
            acc[0] += up;
            // n·ω / cos γ for the vertical normals +X, −X, +Z, −Z.
            for (c, w) in [dx, -dx, dz, -dz].into_iter().enumerate() {
                acc[c + 1] += side * w.max(0.0);
            }
        }
        acc.map(|v| v as f32)
    }

    /// [`Self::light_parts`] of this point.
    pub fn light(&self, table: &SkyTable) -> [f32; CHANNELS] {
        Self::light_parts(table, &self.counts, &self.edges)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sky::cie::SkyKind;

    #[test]
    fn an_infinite_wall_hides_its_view_factor_of_a_uniform_sky() {
        // Uniform sky (CIE type 5), a wall of height H at horizontal distance D running along Z:
        // the floor sees (1 + cos γ0)/2 of it, γ0 = atan(H/D) (the 2D view factor).
        let sky = Sky::new(SkyKind::general(5, None).unwrap(), 0.0, 1000.0).unwrap();
        let t = SkyTable::new(&sky, 256).unwrap();
        let wall = SceneBox {
            min_m: Vec3::new(5.0, 0.0, -1e5),
            max_m: Vec3::new(6.0, 10.0, 1e5),
            albedo: Vec3::ONE,
        };
        let e = irradiance(&[wall], &t, Vec3::ZERO);
        let want = (1.0 + 2f64.atan().cos()) / 2.0;
        assert!((f64::from(e[0]) - want).abs() < 2e-4, "{} vs {want}", e[0]);
        // At its foot exactly half the sky; the wall face itself (normal −X) sees all its half.
        let foot = irradiance(&[wall], &t, Vec3::new(5.0, 0.0, 0.0));
        assert!((foot[0] - 0.5).abs() < 1e-4 && foot[1] == 0.0, "{foot:?}");
        assert!((f64::from(foot[2]) - 0.5).abs() < 1e-3, "{foot:?}"); // uniform sky: E_v = E/2
    }

    #[test]
    fn open_overcast_sky_gives_e_and_the_vertical_ratio() {
        let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
        let s = SkyTable::new(&sky, 256).unwrap();
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
        let s = SkyTable::new(&sky, 256).unwrap();
        let b = SceneBox {
            min_m: Vec3::new(-1.0, 2.0, -1.0),
            max_m: Vec3::new(1.0, 3.0, 1.0),
            albedo: Vec3::ONE,
        };
        assert_eq!(irradiance(&[b], &s, Vec3::new(0.0, 2.5, 0.0)), [0.0; 5]);
        // on its roof: the open sky for up
        let top = irradiance(&[b], &s, Vec3::new(0.0, 3.0, 0.0));
        assert!((top[0] - 1.0).abs() < 1e-5);
        // far below its 2 m × 2 m underside at 2 m above: the blocked solid angle is small but not zero
        let under = irradiance(&[b], &s, Vec3::new(0.0, 0.0, 0.0));
        assert!(under[0] < 0.8 && under[0] > 0.3, "{under:?}");
    }
}
