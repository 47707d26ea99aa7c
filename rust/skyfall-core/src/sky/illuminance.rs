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
/// Codes per elevation step: a point's visible elevations are kept as u16 codes, the position on
/// the tables' steps in 1/128 of a step (2.4e-5 rad): a quarter of f64 edges' memory, which a
/// map under a sky with a sun streams (about 7.5 M edges on the bundled street), and the table read at
/// a code is an integer split and one interpolation. Rounding an edge moves it by at most
/// 1.2e-5 rad; the light's error from it is measured in `tests::coded_edges_cost_under_1e_4`.
pub const CODES_PER_STEP: u32 = 128;

/// The code of elevation `g` (radians, in [0, π/2]): [`CODES_PER_STEP`] per table step, rounded
/// (π/2 itself is 65 536, kept as 65 535: 1/128 of a step below the zenith).
#[inline]
pub fn elevation_code(g: f64) -> u16 {
    let x =
        (g / FRAC_PI_2 * (STEPS as u32 * CODES_PER_STEP) as f64).clamp(0.0, f64::from(u16::MAX));
    // rounded half up by truncation (x ≥ 0): `f64::round` is a library call on baseline x86-64,
    // which made building a map 3-4 % slower
    (x + 0.5) as u16
}

/// 4-point Gauss–Legendre nodes and weights on [0, 1].
const GL4: [(f64, f64); 4] = [
    (0.069_431_844_202_973_71, 0.173_927_422_568_726_93),
    (0.330_009_478_207_571_9, 0.326_072_577_431_273_07),
    (0.669_990_521_792_428_1, 0.326_072_577_431_273_07),
    (0.930_568_155_797_026_3, 0.173_927_422_568_726_93),
];

/// An elevation the tables integrate at.
#[derive(Debug, Clone, Copy)]
struct Sample {
    /// sin γ.
    sin: f64,
    /// cos γ.
    cos: f64,
}

/// The elevations the tables integrate at, step after step: [`GL4`]'s four in each of the
/// 512 steps (the same along every azimuth, so worked out once).
fn samples() -> &'static [Sample] {
    static TABLE: std::sync::OnceLock<Vec<Sample>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let h = FRAC_PI_2 / STEPS as f64;
        (0..STEPS)
            .flat_map(|j| {
                GL4.map(|(x, _)| {
                    let (sin, cos) = ((j as f64 + x) * h).sin_cos();
                    Sample { sin, cos }
                })
            })
            .collect()
    })
}

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

/// One azimuth's STEPS + 1 cumulative pairs (up, side).
type Row = [[f64; 2]; STEPS + 1];

/// A [`SkyTable`]'s cumulative integrals.
#[derive(Debug, Clone, PartialEq)]
enum Columns {
    /// A sky that varies with azimuth (a general type with a sun).
    Azimuths {
        /// Per azimuth, STEPS + 1 pairs (∫₀^γ L τ sin γ cos γ dγ, ∫₀^γ L τ cos² γ dγ) / π · Δφ:
        /// the horizontal and the vertical surfaces' cumulative integrals, side by side (a
        /// node's edge reads both).
        cum: Vec<Row>,
        /// Each azimuth's `up` and `side` at the zenith, the end of every node's highest
        /// visible interval.
        top: Vec<(f64, f64)>,
        /// Each azimuth's n·ω / cos γ for the vertical normals +X, −X, +Z, −Z (0 where it
        /// faces away): what its `side` integral gives each of them.
        facing: Vec<[f64; 4]>,
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
            Self::of_sky(sky, azimuths, cancel)
        }
    }

    /// A sky along every azimuth: [`Self::from_radiance`] of [`Sky::received`], its
    /// elevations' part ([`Sky::at_elevation`]) worked out once for all azimuths.
    fn of_sky(sky: &Sky, azimuths: usize, cancel: &AtomicBool) -> Result<Self> {
        let at: Vec<_> = samples()
            .iter()
            .map(|s| sky.at_elevation(f64::from(s.sin as f32)))
            .collect();
        Self::from_samples(|dir, i| sky.received_at(dir, &at[i]), azimuths, cancel)
    }

    /// A sky the same at every azimuth, tabulated along one and read at a few elevations.
    fn symmetric(sky: &Sky, azimuths: usize) -> Result<Self> {
        AZIMUTHS.check("samples", None, azimuths as f64)?;
        let dphi = TAU / azimuths as f64;
        let dirs = azimuth_dirs(azimuths);
        let mut cum = vec![[0.0; 2]; STEPS + 1];
        Self::cumulative(&|dir, _| sky.received(dir), dirs[0], dphi, &mut cum);
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
        Self::from_samples(|dir, _| radiance(dir), azimuths, cancel)
    }

    /// [`Self::from_radiance`] of `radiance(dir, i)`, `i` the index of `dir`'s elevation in
    /// [`samples`].
    fn from_samples(
        radiance: impl Fn(Vec3, usize) -> f64 + Sync,
        azimuths: usize,
        cancel: &AtomicBool,
    ) -> Result<Self> {
        AZIMUTHS.check("samples", None, azimuths as f64)?;
        let dphi = TAU / azimuths as f64;
        let dirs = azimuth_dirs(azimuths);
        // 2 x 269 MB at 65536 azimuths: refused as OutOfMemory, not an abort.
        let mut cum =
            crate::error::try_filled("the sky table", azimuths, [[0.0f64; 2]; STEPS + 1])?;
        cum.par_iter_mut().zip(&dirs).for_each(|(row, &dir)| {
            if !cancel.load(Ordering::Relaxed) {
                Self::cumulative(&radiance, dir, dphi, row);
            }
        });
        check_cancel(cancel, "the sky table")?;
        let top = cum
            .iter()
            .map(|row| (row[STEPS][0], row[STEPS][1]))
            .collect();
        let facing = dirs
            .iter()
            .map(|&(dx, dz)| [dx, -dx, dz, -dz].map(|w| w.max(0.0)))
            .collect();
        Ok(SkyTable {
            dirs,
            columns: Columns::Azimuths { cum, top, facing },
        })
    }

    /// [`SkyTable::new`] along every azimuth at 512 elevation steps even for a symmetric sky:
    /// the reference its reading at a few elevations ([`super::profile`]) is measured against.
    pub fn per_azimuth(sky: &Sky, azimuths: usize, cancel: &AtomicBool) -> Result<Self> {
        Self::from_radiance(|dir| sky.received(dir), azimuths, cancel)
    }

    /// One azimuth's STEPS + 1 cumulative pairs (up, side) along horizontal direction
    /// (sx, sz), each times Δφ/π, into `cum`; `radiance(dir, i)` for the `i`th of [`samples`].
    fn cumulative(
        radiance: &impl Fn(Vec3, usize) -> f64,
        (sx, sz): (f64, f64),
        dphi: f64,
        cum: &mut [[f64; 2]],
    ) {
        let h = FRAC_PI_2 / STEPS as f64;
        let (mut a, mut b) = (0.0, 0.0);
        cum[0] = [0.0, 0.0];
        for (j, step) in samples().chunks_exact(GL4.len()).enumerate() {
            for (i, (s, (_, w))) in step.iter().zip(GL4).enumerate() {
                let (sg, cg) = (s.sin, s.cos);
                let dir = Vec3::new((cg * sx) as f32, sg as f32, (cg * sz) as f32);
                let l = radiance(dir, j * GL4.len() + i) * w * h * dphi / PI;
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

    /// One azimuth's `row` read at elevation code `q` ([`elevation_code`]; linear between
    /// steps).
    #[inline(always)]
    fn read(row: &Row, q: u16) -> (f64, f64) {
        let j = usize::from(q) / CODES_PER_STEP as usize; // at most 511
        let f = f64::from(u32::from(q) % CODES_PER_STEP) / f64::from(CODES_PER_STEP);
        let ([u0, s0], [u1, s1]) = (row[j], row[j + 1]);
        (u0 + f * (u1 - u0), s0 + f * (s1 - s0))
    }
}

/// One azimuth of a [`SkyTable`] along every azimuth.
#[derive(Debug, Clone, Copy)]
struct AzimuthRow<'a> {
    /// The cumulative pairs (up, side), times Δφ/π.
    row: &'a Row,
    /// The pair at the zenith.
    top: (f64, f64),
    /// n·ω / cos γ for the vertical normals +X, −X, +Z, −Z (0 where it faces away).
    facing: [f64; 4],
}

impl AzimuthRow<'_> {
    /// Adds to `acc` (the five normals) the light of the visible elevations `edges` along
    /// this azimuth ([`VisibleSky`]'s codes: pairs, and an odd last one open to the zenith).
    #[inline(always)]
    fn add(&self, acc: &mut [f64; CHANNELS], edges: &[u16]) {
        let (ut, st) = self.top;
        let (up, side) = match edges {
            [] => return, // the azimuth's sky all hidden
            &[a] => {
                // the commonest: open from one elevation to the zenith
                let (ua, sa) = SkyTable::read(self.row, a);
                (ut - ua, st - sa)
            }
            _ => {
                let (mut up, mut side) = (0.0, 0.0);
                let (pairs, last) = edges.as_chunks::<2>();
                for &[a, b] in pairs {
                    let ((ua, sa), (ub, sb)) =
                        (SkyTable::read(self.row, a), SkyTable::read(self.row, b));
                    up += ub - ua;
                    side += sb - sa;
                }
                if let &[a] = last {
                    let (ua, sa) = SkyTable::read(self.row, a);
                    up += ut - ua;
                    side += st - sa;
                }
                (up, side)
            }
        };
        acc[0] += up;
        for (a, &f) in acc[1..].iter_mut().zip(&self.facing) {
            *a += side * f;
        }
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
/// elevations are `edges[..]` read as a₀ b₀ a₁ b₁ … (the intervals [a, b] in increasing order,
/// as [`elevation_code`]s) and, when their count (`counts[k]`) is odd, a last a whose interval
/// ends at π/2. [`VisibleSky::light`] turns it into illuminance under a sky.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VisibleSky {
    /// Edges per azimuth.
    pub counts: Vec<u16>,
    /// The edges' codes ([`elevation_code`]), azimuth after azimuth.
    pub edges: Vec<u16>,
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
                    self.edges
                        .extend([elevation_code(from), elevation_code(lo)]);
                }
                from = f64::max(from, hi);
            }
            if from < FRAC_PI_2 {
                self.edges.push(elevation_code(from));
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
    pub fn light_parts(table: &SkyTable, counts: &[u16], edges: &[u16]) -> [f32; CHANNELS] {
        let (cum, top, facing) = match &table.columns {
            Columns::Symmetric(c) => {
                return profile::light(&profile::weights(&table.dirs, counts, edges), c);
            }
            Columns::Azimuths { cum, top, facing } => (cum, top, facing),
        };
        let mut acc = [0.0f64; CHANNELS];
        let mut at_edge = 0;
        for (((row, &top), &facing), &n) in cum.iter().zip(top).zip(facing).zip(counts) {
            let n = usize::from(n);
            AzimuthRow { row, top, facing }.add(&mut acc, &edges[at_edge..at_edge + n]);
            at_edge += n;
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

    /// A point's light read at its exact edges (f64 elevations, not codes), as a reference for
    /// the codes' rounding: the visible intervals found as [`VisibleSky::find`] finds them, each
    /// table read by linear interpolation at the exact elevation.
    fn light_at_exact_edges(boxes: &[SceneBox], t: &SkyTable, p: Vec3) -> [f64; CHANNELS] {
        let Columns::Azimuths { cum, .. } = &t.columns else {
            return [f64::NAN; CHANNELS]; // (the test's sky has a sun: a table along every azimuth)
        };
        let read = |row: &[[f64; 2]], g: f64| {
            let x = (g / FRAC_PI_2 * STEPS as f64).clamp(0.0, STEPS as f64);
            let j = (x as usize).min(STEPS - 1);
            let f = x - j as f64;
            [0, 1].map(|c| row[j][c] + f * (row[j + 1][c] - row[j][c]))
        };
        let mut acc = [0.0; CHANNELS];
        for (&(dx, dz), row) in t.dirs.iter().zip(cum) {
            let mut spans: Vec<(f64, f64)> =
                boxes.iter().filter_map(|b| hidden(b, p, dx, dz)).collect();
            spans.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut visible = Vec::new();
            let mut from = 0.0;
            for (lo, hi) in spans {
                if lo > from {
                    visible.push((from, lo));
                }
                from = f64::max(from, hi);
            }
            if from < FRAC_PI_2 {
                visible.push((from, FRAC_PI_2));
            }
            let (mut up, mut side) = (0.0, 0.0);
            for (a, b) in visible {
                let (ra, rb) = (read(row, a), read(row, b));
                up += rb[0] - ra[0];
                side += rb[1] - ra[1];
            }
            acc[0] += up;
            for (c, w) in [dx, -dx, dz, -dz].into_iter().enumerate() {
                acc[c + 1] += side * w.max(0.0);
            }
        }
        acc
    }

    #[test]
    fn coded_edges_cost_under_1e_4() {
        // A canyon with an awning and a kiosk under a clear sky with a low sun (the sky that
        // varies most along an edge), at every point of a 1 m grid through it: the light from
        // the coded edges against the exact ones, relative to the point's brightest channel.
        let wall = |x0: f32, x1: f32, h: f32| SceneBox {
            min_m: Vec3::new(x0, 0.0, -30.0),
            max_m: Vec3::new(x1, h, 30.0),
            albedo: Vec3::ONE,
        };
        let boxes = [
            wall(-8.0, -6.0, 20.0),
            wall(6.0, 8.0, 12.0),
            SceneBox {
                min_m: Vec3::new(4.0, 3.0, -5.0),
                max_m: Vec3::new(6.0, 3.2, 5.0),
                albedo: Vec3::ONE,
            },
            SceneBox {
                min_m: Vec3::new(-2.0, 0.0, 3.0),
                max_m: Vec3::new(0.5, 2.5, 4.5),
                albedo: Vec3::ONE,
            },
        ];
        let sun = crate::sky::sun_direction(8.0, 100.0);
        let sky = Sky::new(SkyKind::general(12, Some(sun)).unwrap(), 2e-4, 1200.0).unwrap();
        let t = SkyTable::new(&sky, 64).unwrap();
        let mut worst = 0.0f64;
        for x in -5..=5 {
            for y in 0..=14 {
                for z in -8..=8 {
                    let p = Vec3::new(x as f32 + 0.3, y as f32, z as f32 + 0.2);
                    let above = boxes_above_slice(&boxes, p.y);
                    let coded = irradiance(&above, &t, p);
                    let exact = light_at_exact_edges(&above, &t, p);
                    let scale = exact.iter().fold(0.0f64, |m, &v| m.max(v));
                    if scale < 1e-9 {
                        continue; // inside a box
                    }
                    for c in 0..CHANNELS {
                        let e = (f64::from(coded[c]) - exact[c]).abs() / scale;
                        assert!(e < 1e-4, "{p} channel {c}: {} vs {}", coded[c], exact[c]);
                        worst = worst.max(e);
                    }
                }
            }
        }
        // measured: 3.0e-5
        eprintln!("coded edges: worst {worst:.2e} of the point's light");
    }

    fn boxes_above_slice(boxes: &[SceneBox], y: f32) -> Vec<SceneBox> {
        boxes.iter().filter(|b| b.max_m.y > y).copied().collect()
    }
}
