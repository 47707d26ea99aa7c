//! Clouds in a frame: the cloud pass and the sun's light through the clouds.
//!
//! [`CloudField`] is a cloud made ready for frames under one sky: its attenuation volume Γ for
//! the sun (when the sky has one) and a second for the zenith, which stands for the sky's light
//! from above. Each frame, [`CloudSplats::prepare`] turns the particles into camera-facing
//! Gaussian splats, sorted far to near and binned to tiles; [`CloudSplats::apply_row`]
//! composites them over a row, back to front, E_k = S_k + T_k·E_{k−1} (Harris' rendering
//! recurrence, with T_k = e^(−τ_k(ρ)) for the column τ_k(ρ) = τ_k e^(−ρ²/r_k²) the ray passes
//! through at distance ρ from particle k's centre), with
//!
//!   S_k = α_k a_k ((E_sun/E) (π Γ_sun(x) p_HG(cos θ) + F_sun(x)) + L_sky F_sky(x)),
//!   α_k = 1 − T_k,
//!
//! in the frame's relative units (a white surface under the open sky is 1): x the point of the
//! ray nearest the centre, read trilinearly from the volumes per fragment, θ the scattering
//! angle (cos θ = view direction · sun direction), p_HG the Henyey–Greenstein phase with the
//! droplets' g, L_sky the open sky's light (1 in relative units, times a photo's units). The
//! first term is the sun's single scattering (the paper's), its Γ_sun the full extinction
//! towards the sun ([`unscattered`]: the volume keeps the δ-M share, which with the full phase
//! would scatter the forward peak twice); F ([`diffuse_light`]) the diffuse light at x: the
//! two-stream field's two streams along the light, the flux coming through the column above x
//! (the two-stream transmission D: the sun's less its direct beam; the sky's whole) and the
//! flux coming back up out of the column below (D times its two-stream reflection), each
//! weighted by the share a Henyey–Greenstein particle scatters towards the viewer
//! ([`stream_weights`]: a view from below the cloud sees mostly the stream coming through, a
//! view of its lit face the one coming back), with three weights and the columns' depth scale
//! ([`STREAM_DEPTH`]) fitted to a Monte Carlo path
//! tracer (`benches/clouds_fit.py`, `benches/results/clouds_fit.md`). Both columns are read
//! from the volume: Γ at x, and at the far face, where the light leaves the cloud. Without the
//! diffuse part a cloud more than a few optical depths thick renders black, and its sunlit
//! face, which real clouds make their brightest, would be as dark as its base.
//!
//! Everything per fragment is f32 relative to the camera, in the order the GPU pass
//! (`skyfall-gpu`'s `cloud.wgsl`) computes it.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::optics::henyey_greenstein;
use super::volume::{AttenuationVolume, VolumeBox};
use super::{CUTOFF_RADII, Cloud};
use crate::error::{Error, Result, try_filled, try_with_capacity};
use crate::haze::{exp_neg, ln_normal};
use crate::scene::camera::Camera;

/// Side of the square tiles the splats are binned to, px.
pub const TILE_PX: u32 = 16;

/// A pixel's splats are composited near to far until less than this share of the light from
/// behind gets through: what lies behind then changes the pixel by at most this share of its
/// radiance (and `cloud_alpha` by at most this much).
pub const MIN_TRANSMITTANCE: f32 = 1.0 / 1024.0;

/// Pixels composited together ([`CloudSplats::apply_row`]): a tile's row is walked this many
/// pixels at a time.
const LANES: usize = 16;

/// Splats in one frame at most (binned entries): 64 M, 256 MB of indices.
const MAX_ENTRIES: usize = 1 << 26;

/// A cloud ready for frames under one sky.
#[derive(Debug, Clone)]
pub struct CloudField {
    /// The particles.
    pub cloud: Cloud,
    /// Towards the sun (unit) and Γ for it, when the sky has a sun.
    pub sun: Option<(DVec3, AttenuationVolume)>,
    /// Γ for light from the zenith: the share of the sky's light from above.
    pub zenith: AttenuationVolume,
    /// Whether fragments get the diffuse light ([`diffuse_light`]) besides the sun's single
    /// scattering (true in frames; false measures single scattering alone).
    pub diffuse: bool,
}

impl CloudField {
    /// `cloud` under a sky with the sun towards `sun` (None: no sun), its volumes at
    /// `resolution`³.
    pub fn new(cloud: Cloud, sun: Option<[f64; 3]>, resolution: usize) -> Result<Self> {
        let sun = match sun {
            Some(s) => {
                let d = super::sun_direction(s)?;
                let v = AttenuationVolume::build(&cloud, d.to_array(), resolution)?;
                Some((d, v))
            }
            None => None,
        };
        let zenith = AttenuationVolume::build(&cloud, [0.0, 1.0, 0.0], resolution)?;
        Ok(CloudField {
            cloud,
            sun,
            zenith,
            diffuse: true,
        })
    }
}

/// A volume as a frame samples it: its values and its box relative to the camera, f32.
#[derive(Debug, Clone, Copy)]
pub struct VolumeView<'a> {
    /// Γ, R³ ([`AttenuationVolume`]'s layout).
    pub gamma: &'a [f32],
    /// Γ at the far face, R² ([`AttenuationVolume::exit`]).
    pub exit: &'a [f32],
    /// R.
    pub resolution: usize,
    /// The box's corner relative to the camera, m.
    pub origin_rel: Vec3,
    /// Each edge over its squared length, 1/m: t_k = (p − origin)·axes[k].
    pub axes: [Vec3; 3],
}

impl<'a> VolumeView<'a> {
    /// `v` seen from a camera at `eye_m`.
    pub fn new(v: &'a AttenuationVolume, eye_m: DVec3) -> Self {
        let VolumeBox { origin, edges } = v.grid;
        VolumeView {
            gamma: &v.gamma,
            exit: &v.exit,
            resolution: v.resolution,
            origin_rel: (origin - eye_m).as_vec3(),
            axes: edges.map(|e| (e / e.length_squared()).as_vec3()),
        }
    }

    /// Trilinear Γ at `p` (relative to the camera), clamped to the box's faces (as
    /// [`super::volume::sample`]).
    #[inline]
    pub fn sample(&self, p: Vec3) -> f32 {
        self.sample_with_exit(p).0
    }

    /// Γ at `p` and where the light leaves the box along its ray through `p` (the far face:
    /// the whole column's share), both as [`VolumeView::sample`] reads them.
    #[inline(always)]
    pub fn sample_with_exit(&self, p: Vec3) -> (f32, f32) {
        let n = self.resolution;
        if n == 1 {
            return (self.gamma[0], self.gamma[0]);
        }
        let d = p - self.origin_rel;
        let top = (n - 1) as f32;
        let at = |t: f32| {
            let x = (t * n as f32 - 0.5).clamp(0.0, top);
            // x ≥ 0: truncation is the floor (an instruction; `floor` is a libm call on
            // baseline x86-64).
            let i = (x as usize).min(n - 2);
            (i, x - i as f32)
        };
        let (i, fu) = at(d.dot(self.axes[0]));
        let (j, fv) = at(d.dot(self.axes[1]));
        let (k, fw) = at(d.dot(self.axes[2]));
        let lerp = |a: f32, b: f32, f: f32| a + (b - a) * f;
        let last = |a: usize, b: usize| self.exit[(i + a) * n + j + b];
        let exit = lerp(
            lerp(last(0, 0), last(0, 1), fv),
            lerp(last(1, 0), last(1, 1), fv),
            fu,
        );
        let inside = super::volume::trilinear(self.gamma, n, (i, fu), (j, fv), (k, fw));
        (inside, exit)
    }
}

/// How a frame lights its clouds, relative units (a white surface under the open sky is 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CloudLight {
    /// The sun's normal illuminance over E, per channel (a photo's units included); zero
    /// without a sun.
    pub sun: Vec3,
    /// The open sky's light L_sky, per channel.
    pub sky: Vec3,
}

impl CloudLight {
    /// A rendered scene's clouds under `sky`: its sun's colour at `sun_relative` (the sun's
    /// normal illuminance over E; 0 without a sun) and its sky light's colour.
    pub fn under(sky: &crate::sky::Sky, sun_relative: f32) -> Self {
        CloudLight {
            sun: sky.sun_colour * sun_relative,
            sky: sky.light_colour,
        }
    }
}

/// The clouds as one frame draws them: the pass's inputs.
#[derive(Debug, Clone, Copy)]
pub struct CloudPass<'a> {
    /// The cloud and its volumes.
    pub field: &'a CloudField,
    /// Their light.
    pub light: CloudLight,
}

/// One particle as the frame draws it (f32, relative to the camera).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Splat {
    /// Centre relative to the camera, m.
    pub centre: Vec3,
    /// 1/e radius, m.
    pub radius_m: f32,
    /// Optical depth through the centre.
    pub tau: f32,
    /// Single-scattering albedo.
    pub albedo: f32,
}

impl Splat {
    /// The GPU's packing: centre, radius, τ, albedo, two pads.
    pub fn packed(&self) -> [f32; 8] {
        let c = self.centre;
        [
            c.x,
            c.y,
            c.z,
            self.radius_m,
            self.tau,
            self.albedo,
            0.0,
            0.0,
        ]
    }
}

/// A frame's splats: far to near, binned to [`TILE_PX`] tiles.
#[derive(Debug, Clone)]
pub struct CloudSplats<'a> {
    /// Far to near.
    pub splats: Vec<Splat>,
    /// Each splat's distance from the camera, m (what they are sorted by).
    pub distances: Vec<f32>,
    /// The farthest any splat's support reaches from its centre, m (the cutoff times the
    /// largest radius).
    pub reach_m: f32,
    /// Tiles across.
    pub tiles_x: u32,
    /// Per tile (row-major), the start of its run in `indices`; one more at the end.
    pub offsets: Vec<u32>,
    /// Splat indices per tile, far to near within each.
    pub indices: Vec<u32>,
    /// The sun's Γ, seen from the camera.
    pub sun: Option<(Vec3, VolumeView<'a>)>,
    /// The zenith's Γ, seen from the camera.
    pub zenith: VolumeView<'a>,
    /// The light.
    pub light: CloudLight,
    /// Henyey–Greenstein asymmetry.
    pub g: f32,
    /// The field's [`CloudField::diffuse`].
    pub diffuse: bool,
}

/// A splat placed in the frame: its tile box (inclusive), camera-space centre and support.
#[derive(Debug, Clone, Copy)]
struct Placed {
    tiles: [u32; 4],
    centre: Vec3,
    support: f32,
}

/// A splat's pixel box in `cam` (inclusive), or None when it lies wholly behind the camera or
/// off the frame. A cube around the support is projected (its image holds the sphere's, as
/// long as it lies in front); a cube reaching behind the camera takes the whole frame.
fn pixel_box(cam: &Camera, centre: Vec3, support: f32) -> Option<[u32; 4]> {
    let (w, h) = (cam.width as f32, cam.height as f32);
    let to_cam = cam.rotation.transpose();
    let c = to_cam * centre;
    if c.z - support * 3f32.sqrt() >= 0.0 {
        return None; // wholly behind (camera space looks down −z)
    }
    let full = [0, 0, cam.width - 1, cam.height - 1];
    let (mut x0, mut y0, mut x1, mut y1) = (f32::MAX, f32::MAX, f32::MIN, f32::MIN);
    for k in 0..8 {
        let o = Vec3::new(
            if k & 1 == 0 { -support } else { support },
            if k & 2 == 0 { -support } else { support },
            if k & 4 == 0 { -support } else { support },
        );
        let p = c + to_cam * o;
        if p.z > -1e-3 {
            return Some(full);
        }
        let x = cam.cx + cam.fx * p.x / -p.z;
        let y = cam.cy - cam.fy * p.y / -p.z;
        (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
    }
    if x1 < 0.0 || y1 < 0.0 || x0 >= w || y0 >= h {
        return None;
    }
    let clampx = |v: f32| v.clamp(0.0, w - 1.0) as u32;
    let clampy = |v: f32| v.clamp(0.0, h - 1.0) as u32;
    Some([clampx(x0), clampy(y0), clampx(x1), clampy(y1)])
}

/// The side planes of each tile's view pyramid (camera space, through the eye), so that a
/// splat is listed only in the tiles whose pyramid its support sphere reaches: no ray of
/// another tile can pass within its support, so the lists lose nothing.
struct TilePlanes {
    /// Per tile column, the camera-space slopes u = x/(−z) of its left and right edges, and
    /// 1/√(1 + u²) of each (the planes' normals' lengths).
    u: Vec<[f32; 4]>,
    /// Per tile row, the slopes v = y/z of its top and bottom edges, and their 1/√(1 + v²).
    v: Vec<[f32; 4]>,
}

impl TilePlanes {
    fn new(cam: &Camera) -> Self {
        let edge = |lo: u32, hi: u32, size: u32, c: f32, f: f32| {
            let a = ((lo * TILE_PX) as f32 - c) / f;
            let b = (((hi * TILE_PX).min(size)) as f32 - c) / f;
            let inv = |k: f32| 1.0 / (1.0 + k * k).sqrt();
            [a, b, inv(a), inv(b)]
        };
        TilePlanes {
            u: (0..cam.width.div_ceil(TILE_PX))
                .map(|t| edge(t, t + 1, cam.width, cam.cx, cam.fx))
                .collect(),
            v: (0..cam.height.div_ceil(TILE_PX))
                .map(|t| edge(t, t + 1, cam.height, cam.cy, cam.fy))
                .collect(),
        }
    }

    /// Whether a sphere of radius `r` at camera-space `c` reaches tile (tx, ty)'s pyramid.
    #[inline]
    fn reaches(&self, tx: u32, ty: u32, c: Vec3, r: f32) -> bool {
        let [u0, u1, nu0, nu1] = self.u[tx as usize];
        let [v0, v1, nv0, nv1] = self.v[ty as usize];
        // Signed distances to the four planes, positive inside: u ≥ u0 ⟺ x + u0 z ≥ 0, u ≤ u1
        // ⟺ −x − u1 z ≥ 0, v ≥ v0 ⟺ v0 z − y ≥ 0, v ≤ v1 ⟺ y − v1 z ≥ 0 (z < 0 in front).
        (c.x + u0 * c.z) * nu0 >= -r
            && (-c.x - u1 * c.z) * nu1 >= -r
            && (v0 * c.z - c.y) * nv0 >= -r
            && (c.y - v1 * c.z) * nv1 >= -r
    }

    /// Calls `visit(tx, k)` for each tile of row `ty` and each splat k of `boxes` (in their
    /// order) whose support reaches the tile's pyramid.
    fn row(&self, boxes: &[Placed], ty: u32, mut visit: impl FnMut(u32, u32)) {
        for (k, p) in boxes.iter().enumerate() {
            let [tx0, ty0, tx1, ty1] = p.tiles;
            if (ty0..=ty1).contains(&ty) {
                for tx in tx0..=tx1 {
                    if self.reaches(tx, ty, p.centre, p.support) {
                        visit(tx, k as u32);
                    }
                }
            }
        }
    }
}

impl<'a> CloudSplats<'a> {
    /// The splats of `pass` in `cam`'s frame.
    pub fn prepare(pass: &CloudPass<'a>, cam: &Camera) -> Result<Self> {
        let cloud = &pass.field.cloud;
        let eye = cam.position_m;
        // Each list grows with the cloud's particles: reserved fallibly.
        let what = "the clouds' splats";
        let mut order: Vec<(f32, u32, Splat)> = try_with_capacity(what, cloud.len())?;
        for i in 0..cloud.len() {
            let centre = (DVec3::from_array(cloud.positions_m[i]) - eye).as_vec3();
            order.push((
                centre.length(),
                i as u32,
                Splat {
                    centre,
                    radius_m: cloud.radii_m[i] as f32,
                    tau: cloud.optical_depths[i] as f32,
                    albedo: cloud.albedos[i] as f32,
                },
            ));
        }
        // Far to near; ties by index (a total order: the same whatever the platform or sort).
        order.par_sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let tiles_x = cam.width.div_ceil(TILE_PX);
        let tiles_y = cam.height.div_ceil(TILE_PX);
        let n_tiles = (tiles_x * tiles_y) as usize;
        let to_cam = cam.rotation.transpose();
        let tiles = TilePlanes::new(cam);
        // Each splat's tile box and camera-space centre (None off the frame), in parallel.
        let mut placed: Vec<Option<Placed>> = try_with_capacity(what, order.len())?;
        order
            .par_iter()
            .map(|(_, _, s)| {
                let support = s.radius_m * CUTOFF_RADII as f32;
                pixel_box(cam, s.centre, support).map(|b| Placed {
                    tiles: b.map(|v| v / TILE_PX),
                    centre: to_cam * s.centre,
                    support,
                })
            })
            .collect_into_vec(&mut placed);
        let mut boxes: Vec<Placed> = try_with_capacity(what, order.len())?;
        let mut splats = try_with_capacity(what, order.len())?;
        let mut distances = try_with_capacity(what, order.len())?;
        let mut reach_m = 0.0f32;
        for ((dist, _, s), p) in order.iter().zip(&placed) {
            if let Some(p) = p {
                boxes.push(*p);
                splats.push(*s);
                distances.push(*dist);
                reach_m = reach_m.max(p.support);
            }
        }
        // The splats each tile's pyramid reaches, far to near: counted per row of tiles (in
        // parallel), then written into each row's own run of `indices`.
        let mut counts = try_filled("the clouds' tile lists", n_tiles + 1, 0usize)?;
        counts[1..]
            .par_chunks_mut(tiles_x as usize)
            .enumerate()
            .for_each(|(ty, row)| tiles.row(&boxes, ty as u32, |tx, _| row[tx as usize] += 1));
        for t in 0..n_tiles {
            counts[t + 1] += counts[t];
        }
        if counts[n_tiles] > MAX_ENTRIES {
            return Err(Error::too_large(
                "the clouds' tile lists".to_string(),
                counts[n_tiles] as u128 * 4,
                MAX_ENTRIES as u64 * 4,
            ));
        }
        let mut indices = try_filled("the clouds' tile lists", counts[n_tiles], 0u32)?;
        let mut rows: Vec<(u32, &mut [u32])> = try_with_capacity(what, tiles_y as usize)?;
        let mut rest = indices.as_mut_slice();
        for ty in 0..tiles_y {
            let row = (ty * tiles_x) as usize;
            let len = counts[row + tiles_x as usize] - counts[row];
            let (head, tail) = rest.split_at_mut(len);
            rows.push((ty, head));
            rest = tail;
        }
        rows.par_iter_mut().for_each(|(ty, out)| {
            let row = (*ty * tiles_x) as usize;
            let start = counts[row];
            let mut fill: Vec<usize> = counts[row..row + tiles_x as usize]
                .iter()
                .map(|c| c - start)
                .collect();
            tiles.row(&boxes, *ty, |tx, k| {
                out[fill[tx as usize]] = k;
                fill[tx as usize] += 1;
            });
        });
        let mut offsets = try_with_capacity("the clouds' tile lists", counts.len())?;
        offsets.extend(counts.iter().map(|&c| c as u32));
        let field = pass.field;
        Ok(CloudSplats {
            splats,
            distances,
            reach_m,
            tiles_x,
            offsets,
            indices,
            sun: field
                .sun
                .as_ref()
                .map(|(d, v)| (d.as_vec3(), VolumeView::new(v, eye))),
            zenith: VolumeView::new(&field.zenith, eye),
            light: pass.light,
            g: cloud.asymmetry_g as f32,
            diffuse: field.diffuse,
        })
    }

    /// The Henyey–Greenstein phase towards a viewer looking along `d` (unit) of the sun's
    /// light (0 without a sun): the same for every fragment of a pixel.
    #[inline]
    fn phase(&self, d: Vec3) -> f32 {
        match &self.sun {
            Some((s, _)) => henyey_greenstein(f64::from(d.dot(*s)), f64::from(self.g)) as f32,
            None => 0.0,
        }
    }

    /// Composites the clouds over row `y` of `cam`'s frame: `rgb_row` (W·3) in place, behind
    /// what `depth_row` (W, m along the axis) puts nearer; `alpha_row` (W) gets the clouds'
    /// coverage when given.
    pub fn apply_row(
        &self,
        cam: &Camera,
        y: u32,
        rgb_row: &mut [f32],
        depth_row: &[f32],
        mut alpha_row: Option<&mut [f32]>,
    ) {
        let ty = y / TILE_PX;
        for tx in 0..self.tiles_x {
            let cols = tx * TILE_PX..((tx + 1) * TILE_PX).min(cam.width);
            let t = (ty * self.tiles_x + tx) as usize;
            let list = &self.indices[self.offsets[t] as usize..self.offsets[t + 1] as usize];
            if list.is_empty() {
                if let Some(a) = alpha_row.as_deref_mut() {
                    a[cols.start as usize..cols.end as usize].fill(0.0);
                }
                continue;
            }
            for x0 in cols.clone().step_by(LANES) {
                let n = (cols.end - x0).min(LANES as u32) as usize;
                let x0 = x0 as usize;
                let (trans, acc) = self.composite(cam, y, x0, &depth_row[x0..x0 + n], list);
                for l in 0..n {
                    let px = &mut rgb_row[3 * (x0 + l)..3 * (x0 + l) + 3];
                    let e = acc[l] + Vec3::from_slice(px) * trans[l];
                    px.copy_from_slice(&e.to_array());
                }
                if let Some(a) = alpha_row.as_deref_mut() {
                    for l in 0..n {
                        a[x0 + l] = 1.0 - trans[l];
                    }
                }
            }
        }
    }

    /// The clouds in front of pixels (x0 + l, y), l < `depth.len()` ≤ [`LANES`], at the depths
    /// `depth` (m along the axis), from their tile's `list`: per pixel the transmittance of
    /// the clouds and the light they add (the recurrence's sum, Σ_k (∏_{j nearer} T_j) S_k,
    /// near to far, stopped once less than [`MIN_TRANSMITTANCE`] of the light from behind
    /// gets through).
    ///
    /// The pixels walk their list together, lane by lane (each lane computes what one pixel
    /// alone would, in the same order, so the bits do not depend on the grouping): the
    /// splats' tests and opacities are computed for every lane at once, branch-free, so that
    /// the lanes' long chains of arithmetic (two exponentials nested per fragment) overlap;
    /// the light of each fragment is read per lane where the splat covers it.
    #[inline]
    fn composite(
        &self,
        cam: &Camera,
        y: u32,
        x0: usize,
        depth: &[f32],
        list: &[u32],
    ) -> ([f32; LANES], [Vec3; LANES]) {
        let back = cam.rotation.z_axis;
        let mut dir = [Vec3::ZERO; LANES];
        let mut axial = [1.0f32; LANES];
        let mut deep = [0.0f32; LANES];
        let mut beyond = [0.0f32; LANES];
        let mut phase = [0.0f32; LANES];
        let mut w_sun = [(0.0f32, 0.0f32); LANES];
        let mut w_sky = [(0.0f32, 0.0f32); LANES];
        let streams = StreamWeights::new(self.g);
        let mut live = [false; LANES];
        for (l, &dep) in depth.iter().enumerate() {
            let d = cam.ray_direction((x0 + l) as u32, y).normalize();
            dir[l] = d;
            // Depth along the axis per metre along the ray.
            axial[l] = -d.dot(back);
            deep[l] = dep;
            // A splat whose centre lies farther than the scene along the ray by more than its
            // support (|c| ≥ ray length to the scene + the cutoff radius) has no fragment in
            // front of the scene: along the ray nearer than the scene its distance from the
            // centre exceeds the cutoff. The list runs near to far by |c|, so the pixel's
            // splats end at the first such one (with a margin for rounding: the tests below
            // would skip every splat past it anyway).
            beyond[l] = (dep / axial[l] + self.reach_m) * 1.001 + 0.01;
            phase[l] = self.phase(d);
            // The light leaves towards the camera, along −d: against a stream travelling
            // along −s (the sun's) μ = d·s, along −Y (the sky's) μ = d.y.
            w_sky[l] = streams.at(d.y);
            if let Some((s, _)) = &self.sun {
                w_sun[l] = streams.at(d.dot(*s));
            }
            live[l] = true;
        }
        let mut acc = [Vec3::ZERO; LANES];
        let mut trans = [1.0f32; LANES];
        let cut2 = (CUTOFF_RADII * CUTOFF_RADII) as f32;
        for &k in list.iter().rev() {
            let dist = self.distances[k as usize];
            let s = &self.splats[k as usize];
            let r2 = s.radius_m * s.radius_m;
            let mut hit = [false; LANES];
            let mut u = [0.0f32; LANES];
            let mut along = [0.0f32; LANES];
            for l in 0..LANES {
                live[l] &= dist < beyond[l];
                let d = dir[l];
                along[l] = s.centre.dot(d);
                let rho2 = (s.centre - d * along[l]).length_squared();
                u[l] = rho2 / r2;
                hit[l] = live[l]
                    & (along[l] > 0.0)
                    & (along[l] * axial[l] < deep[l])
                    & (rho2 < cut2 * r2);
            }
            if !live.contains(&true) {
                break;
            }
            if !hit.contains(&true) {
                continue;
            }
            let mut t_k = [0.0f32; LANES];
            for l in 0..LANES {
                t_k[l] = exp_neg(-s.tau * exp_neg(-u[l]));
            }
            // The volumes where the splat covers a lane (the point of its ray nearest the
            // centre), then the diffuse light of every lane at once.
            let mut gz = [1.0f32; LANES];
            let mut gz_exit = [1.0f32; LANES];
            let mut gs = [1.0f32; LANES];
            let mut gs_exit = [1.0f32; LANES];
            for l in 0..LANES {
                if hit[l] {
                    let x = dir[l] * along[l];
                    (gz[l], gz_exit[l]) = self.zenith.sample_with_exit(x);
                    if let Some((_, v)) = &self.sun {
                        (gs[l], gs_exit[l]) = v.sample_with_exit(x);
                    }
                }
            }
            // The sun's unscattered beam ([`unscattered`]) of every lane at once, its power once
            // per splat.
            let mut beam = [0.0f32; LANES];
            if self.sun.is_some() {
                let power = unscattered_power(s.albedo, self.g);
                for l in 0..LANES {
                    beam[l] = unscattered(gs[l], power);
                }
            }
            let mut sky = gz;
            let mut sun = [0.0f32; LANES];
            if self.diffuse {
                for l in 0..LANES {
                    sky[l] = diffuse_light(gz[l], gz_exit[l], self.g, true, w_sky[l]);
                    sun[l] = diffuse_light(gs[l], gs_exit[l], self.g, false, w_sun[l]);
                }
            }
            for l in 0..LANES {
                if hit[l] {
                    let alpha = 1.0 - t_k[l];
                    let sky = self.light.sky * sky[l];
                    let source = match &self.sun {
                        Some(_) => {
                            self.light.sun * (std::f32::consts::PI * phase[l] * beam[l] + sun[l])
                                + sky
                        }
                        None => sky,
                    };
                    acc[l] += source * (trans[l] * alpha * s.albedo);
                    trans[l] *= t_k[l];
                    live[l] = trans[l] >= MIN_TRANSMITTANCE;
                }
            }
        }
        (trans, acc)
    }
}

/// The sun's unscattered beam at a point, from the sun volume's Γ and the particle's
/// [`unscattered_power`]. The volume keeps the δ-M direct beam, exp(−Σ(1 − a_i g²)τ_i): what
/// the diffuse term ([`diffuse_light`]) takes as direct, forward-scattered light included.
/// Single scattering
/// with the full Henyey–Greenstein phase must see the full extinction exp(−Στ_i), or the
/// forward peak is scattered twice (the frames' single scattering was 1.5x the path tracer's
/// first order at the clouds' depths): Γ^(1/(1 − a g²)), exact for a cloud of one albedo (every
/// generated cloud). Branch-free (`ln_normal`, `exp_neg`); `cloud.wgsl` mirrors it.
#[inline(always)]
pub fn unscattered(gamma: f32, power: f32) -> f32 {
    exp_neg(ln_normal(gamma.max(1e-30)) * power)
}

/// [`unscattered`]'s power for a particle of albedo `albedo`: 1/(1 − a g²).
#[inline(always)]
pub fn unscattered_power(albedo: f32, g: f32) -> f32 {
    1.0 / (1.0 - albedo * g * g)
}

/// `STREAM_DEPTH`·¾(1 − g)/(1 − g²) = `STREAM_DEPTH`·¾/(1 + g): the two-stream's optical
/// depth, times ¾(1 − g), per unit of −ln Γ (Γ keeps the share e^(−(1 − g²)τ) of the light, the
/// δ-M direct beam), scaled by the fitted [`STREAM_DEPTH`].
#[inline(always)]
fn two_stream_k(g: f32) -> f32 {
    STREAM_DEPTH * 0.75 / (1.0 + g)
}

/// The share of the light of a stream travelling along t that a Henyey–Greenstein particle of
/// asymmetry `g` scatters towards a viewer, the light leaving along v, μ = v·t: the phase
/// function integrated over the stream's hemisphere of directions, P(μ) = ∫_{ω·t > 0} p(ω·v) dω.
/// P(−μ) = 1 − P(μ), P(0) = ½, P(1) = (1 + g)/2g − (1 − g²)/(2g√(1 + g²)) the phase's forward
/// share (0.967 at g = 0.86); between, P(μ) ≈ ½ + (P(1) − ½)·sign μ·(1 − e^(−|μ|/w))/(1 −
/// e^(−1/w)), w = [`STREAM_WIDTH`], within 0.015 of the integral at g = 0.86 (tested; the
/// width is fitted there, the generated clouds' g).
#[inline]
pub fn stream_share(mu: f32, g: f32) -> f32 {
    StreamWeights::new(g).share(mu)
}

/// [`stream_share`] and [`stream_weights`] for one asymmetry g: what depends on g alone
/// (P(1) and the rise's normalisation) made once, so a pixel's weights cost one exponential.
#[derive(Debug, Clone, Copy)]
pub struct StreamWeights {
    /// (P(1) − ½)/(1 − e^(−1/w)).
    scale: f32,
}

impl StreamWeights {
    /// The weights of particles of asymmetry `g`.
    #[inline]
    pub fn new(g: f32) -> Self {
        let forward = if g.abs() < 1e-4 {
            0.5
        } else {
            (1.0 + g) / (2.0 * g) - (1.0 - g * g) / (2.0 * g * (1.0 + g * g).sqrt())
        };
        StreamWeights {
            scale: (forward - 0.5) / (1.0 - exp_neg(-1.0 / STREAM_WIDTH)),
        }
    }

    /// [`stream_share`] at μ.
    #[inline]
    pub fn share(self, mu: f32) -> f32 {
        let rise = 1.0 - exp_neg(-mu.abs().min(1.0) / STREAM_WIDTH);
        0.5 + self.scale * rise.copysign(mu)
    }

    /// [`stream_weights`] at μ.
    #[inline]
    pub fn at(self, mu: f32) -> (f32, f32) {
        let w = 0.5 + PHASE_SHARE * (self.share(mu) - 0.5);
        (K_THROUGH * w, K_BACK * (1.0 - w))
    }
}

/// The width in μ over which [`stream_share`] turns from one stream to the other.
pub const STREAM_WIDTH: f32 = 0.19;

/// The fitted weights of the diffuse light's two streams ([`diffuse_light`]): the light coming
/// through the column above (towards the light's travel) weighs `K_THROUGH`·w, the light
/// coming back up out of the column below `K_BACK`·(1 − w), w = ½ + `PHASE_SHARE`·(P(μ) − ½)
/// ([`stream_share`]); the columns' two-stream optical depths are scaled by [`STREAM_DEPTH`].
/// Fitted (a grid search minimising the worst |ln(frames / reference)|) to the Monte Carlo path
/// tracer's summed light (`benches/clouds_fit.py`: two generated, billowed cumulus, optical
/// depths ×1 and ×4, five suns, a side and a ground view), and checked on a third cloud at
/// another depth under other suns (`benches/results/clouds_fit.md`): the two-stream slab's
/// reflection overstates a finite cloud's (light leaves through its sides), its transmission
/// understates what a forward-scattering particle sends on along the light.
pub const PHASE_SHARE: f32 = 0.5;
/// See [`PHASE_SHARE`].
pub const K_THROUGH: f32 = 0.975;
/// See [`PHASE_SHARE`].
pub const K_BACK: f32 = 0.54;
/// The two-stream optical depth of a column, in units of the slab's ¾(1 − g)τ (fitted with
/// [`PHASE_SHARE`]): a billowed cloud is lit through many faces, not only along the column
/// towards the light, so its diffuse light falls with depth slower than a slab's (with the
/// slab's 1, the fit's thick rows spread over 0.78-1.29x of the path tracer; with 0.4,
/// 0.83-1.21x).
pub const STREAM_DEPTH: f32 = 0.4;

/// The weights (through, back) of [`diffuse_light`]'s streams for a viewer the light leaves
/// towards along v, μ = v·t, t the direction the stream's light travels ([`PHASE_SHARE`]).
#[inline]
pub fn stream_weights(mu: f32, g: f32) -> (f32, f32) {
    StreamWeights::new(g).at(mu)
}

/// The diffuse light at a point, per unit of its light's flux, from Γ there (`gamma`) and
/// where the light leaves the cloud (`exit`), seen by a viewer whose stream weights are
/// `weights` ([`stream_weights`]): w_t·D(τ_a) + w_b·D(τ_a) R(τ_b). D is the share of the light's
/// flux that comes through the column above the point (along the light), the two-stream
/// (Eddington) transmission of a conservative layer 1/(1 + ¾(1 − g)τ_a), τ_a = −ln Γ/(1 − g²)
/// (less the direct beam Γ unless `with_direct`); D R comes back out of the column below,
/// R(τ_b) = 1 − D(τ_b) its two-stream reflection, τ_b = ln(Γ/Γ_exit)/(1 − g²). At the lit face
/// of a thick cloud this is about w_b R, deep under it about w_t D.
///
/// With a = −k ln Γ and b = k ln(Γ/Γ_exit) (k from [`two_stream_k`]), D = 1/(1 + a) and D R = b/((1 + a)
/// (1 + b)): one division for both (this runs per fragment and volume).
#[inline]
pub fn diffuse_light(gamma: f32, exit: f32, g: f32, with_direct: bool, weights: (f32, f32)) -> f32 {
    let k = two_stream_k(g);
    // Γ ≤ 1 clamped to a normal number: ln without a libm call.
    let ln_gamma = ln_normal(gamma.max(1e-30));
    let above = -k * ln_gamma;
    let below = (k * (ln_gamma - ln_normal(exit.max(1e-30)))).max(0.0);
    let q = 1.0 / ((1.0 + above) * (1.0 + below));
    let d = (1.0 + below) * q;
    let reaching = if with_direct { d } else { (d - gamma).max(0.0) };
    weights.0 * reaching + weights.1 * (below * q)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Mat3;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64Mcg;

    fn cam(w: u32, h: u32) -> Camera {
        // Looking straight up from the origin.
        let rot = Mat3::from_cols(Vec3::X, Vec3::Z, -Vec3::Y);
        Camera::new(
            w,
            h,
            [w as f32, w as f32, w as f32 / 2.0, h as f32 / 2.0],
            DVec3::ZERO,
            rot,
        )
        .unwrap()
    }

    fn one(tau: f64) -> Cloud {
        Cloud::new(
            vec![[0.0, 1000.0, 0.0]],
            vec![50.0],
            vec![tau],
            vec![1.0],
            0.86,
        )
        .unwrap()
    }

    fn render(
        field: &CloudField,
        light: CloudLight,
        cam: &Camera,
        bg: f32,
    ) -> (Vec<f32>, Vec<f32>) {
        let pass = CloudPass { field, light };
        let s = CloudSplats::prepare(&pass, cam).unwrap();
        let (w, h) = (cam.width as usize, cam.height as usize);
        let mut rgb = vec![bg; 3 * w * h];
        let depth = vec![f32::INFINITY; w * h];
        let mut alpha = vec![-1.0; w * h];
        for y in 0..h {
            s.apply_row(
                cam,
                y as u32,
                &mut rgb[3 * w * y..3 * w * (y + 1)],
                &depth[w * y..w * (y + 1)],
                Some(&mut alpha[w * y..w * (y + 1)]),
            );
        }
        (rgb, alpha)
    }

    /// The open sky's light alone, no sun.
    const SKY_ONLY: CloudLight = CloudLight {
        sun: Vec3::ZERO,
        sky: Vec3::ONE,
    };

    #[test]
    fn one_particle_has_its_analytic_transmittance() {
        // The column through the centre is τ: the centre pixel keeps e^(−τ) of the background,
        // and with no light the cloud only dims it.
        let c = cam(33, 33);
        let field = CloudField::new(one(2.0), None, 16).unwrap();
        let dark = CloudLight {
            sun: Vec3::ZERO,
            sky: Vec3::ZERO,
        };
        let (rgb, alpha) = render(&field, dark, &c, 1.0);
        let mid = 16 * 33 + 16;
        assert!(
            (rgb[3 * mid] - (-2.0f32).exp()).abs() < 1e-3,
            "{}",
            rgb[3 * mid]
        );
        assert!((alpha[mid] - (1.0 - (-2.0f32).exp())).abs() < 1e-3);
        // Off the centre by ρ the column is τ e^(−ρ²/r²): the pixel 5 columns right looks 5/33
        // of the focal length off the axis.
        let x = 21usize;
        let u = (x as f32 + 0.5 - 16.5) / 33.0;
        let d = Vec3::new(u, 1.0, 0.0).normalize();
        let along = 1000.0 * d.y;
        let rho2 = (Vec3::new(0.0, 1000.0, 0.0) - d * along).length_squared();
        let want = (-2.0 * (-rho2 / 2500.0).exp()).exp();
        let got = rgb[3 * (16 * 33 + x)];
        assert!((got - want).abs() < 1e-3, "{got} vs {want}");
        // Far off the particle: untouched, coverage 0.
        assert_eq!(rgb[0], 1.0);
        assert_eq!(alpha[0], 0.0);
    }

    #[test]
    fn a_particle_above_shades_the_sky_light_of_one_below() {
        // Lit by the sky alone (L = 1) over a black background, looking up through a particle
        // at 1000 m and another at 1300 m: the lower one's direct light from above is cut by
        // the upper one's G = e^(−(1 − a f) τ) (a particle reads none of its own G, as in
        // Harris' recurrence), and the centre pixel is α_l F(Γ_l) + T_l α_u F(Γ_u), F the
        // diffuse light weighted for a view straight up the sky light's stream (μ = 1).
        let c = cam(17, 17);
        let (tau_l, tau_u) = (1.5, 2.0);
        let two = Cloud::new(
            vec![[0.0, 1000.0, 0.0], [0.0, 1300.0, 0.0]],
            vec![50.0, 50.0],
            vec![tau_l, tau_u],
            vec![1.0, 1.0],
            0.86,
        )
        .unwrap();
        let field = CloudField::new(two, None, 64).unwrap();
        let g_l = field.zenith.sample(DVec3::new(0.0, 1000.0, 0.0));
        let g_u = field.zenith.sample(DVec3::new(0.0, 1300.0, 0.0));
        let view = VolumeView::new(&field.zenith, DVec3::ZERO);
        let f = |p: Vec3| {
            let (a, b) = view.sample_with_exit(p);
            diffuse_light(a, b, 0.86, true, stream_weights(1.0, 0.86))
        };
        let (d_l, d_u) = (
            f(Vec3::new(0.0, 1000.0, 0.0)),
            f(Vec3::new(0.0, 1300.0, 0.0)),
        );
        let shade = (-(1.0 - 0.86 * 0.86) * tau_u).exp() as f32;
        // Between Harris' value (none of its own G) and all of its own G too: the volume's
        // slices blur the step at the centre over one slice.
        let own = (-(1.0 - 0.86 * 0.86) * tau_l).exp() as f32;
        assert!(
            g_l <= shade * 1.001 && g_l >= shade * own,
            "{g_l} vs {shade}"
        );
        let own_u = (-(1.0 - 0.86 * 0.86) * tau_u).exp() as f32;
        assert!(g_u <= 1.0 && g_u >= own_u, "{g_u}");
        let (rgb, _) = render(&field, SKY_ONLY, &c, 0.0);
        let mid = 8 * 17 + 8;
        let (t_l, t_u) = ((-tau_l as f32).exp(), (-tau_u as f32).exp());
        let want = (1.0 - t_l) * d_l + t_l * (1.0 - t_u) * d_u;
        assert!(
            (rgb[3 * mid] - want).abs() < 2e-3,
            "{} vs {want}",
            rgb[3 * mid]
        );
    }

    #[test]
    fn the_unscattered_beam_is_the_delta_m_share_to_its_power() {
        // Γ_δM = e^(−(1 − a g²)τ) ⇒ e^(−τ), against libm over the range a frame meets.
        for a in [0.5f32, 0.9, 0.999_9, 1.0] {
            for tau in [0.0f32, 0.01, 0.3, 2.0, 7.0, 20.0] {
                let g = 0.864f32;
                let delta_m = (-(1.0 - a * g * g) * tau).exp();
                let want = (-tau).exp();
                let got = unscattered(delta_m, unscattered_power(a, g));
                assert!(
                    (got - want).abs() <= 2e-6 * want + 1e-30,
                    "a {a} tau {tau}: {got} vs {want}"
                );
            }
        }
        // Γ = 0 (or a denormal) gives 0, not NaN.
        assert_eq!(unscattered(0.0, unscattered_power(1.0, 0.86)), 0.0);
    }

    #[test]
    fn the_sun_lights_by_the_phase_function() {
        // Sun at 90° to the view: S = α a (E_sun/E) (π Γ_full p_HG(0) + D(Γ) − Γ).
        let c = cam(17, 17);
        let tau = 0.5;
        let field = CloudField::new(one(tau), Some([1.0, 0.0, 0.0]), 64).unwrap();
        let light = CloudLight {
            sun: Vec3::splat(10.0),
            sky: Vec3::ZERO,
        };
        let (rgb, _) = render(&field, light, &c, 0.0);
        let mid = 8 * 17 + 8;
        let gamma = field
            .sun
            .as_ref()
            .unwrap()
            .1
            .sample(DVec3::new(0.0, 1000.0, 0.0));
        let p = henyey_greenstein(0.0, 0.86) as f32;
        let view = VolumeView::new(&field.sun.as_ref().unwrap().1, DVec3::ZERO);
        let (direct, exit) = view.sample_with_exit(Vec3::new(0.0, 1000.0, 0.0));
        assert!((direct - gamma).abs() < 1e-5);
        // The sun along +X, the centre pixel's view straight up: μ = 0.
        let diffuse = diffuse_light(direct, exit, 0.86, false, stream_weights(0.0, 0.86));
        // Single scattering sees the full extinction: the δ-M Γ to the power 1/(1 − a g²),
        // a = 1 (libm's powf as the reference for `unscattered`).
        let full = gamma.powf(1.0 / (1.0 - 0.86f32 * 0.86));
        assert!(full < 0.9 * gamma);
        let want = (1.0 - (-tau as f32).exp()) * 10.0 * (std::f32::consts::PI * p * full + diffuse);
        assert!(
            (rgb[3 * mid] - want).abs() < 1e-3 * want.max(1.0),
            "{} vs {want}",
            rgb[3 * mid]
        );
    }

    /// The two-stream transmission D = 1/(1 + s·¾(1 − g)τ) of the column whose direct beam
    /// keeps `gamma`, τ = −ln Γ/(1 − g²), s = [`STREAM_DEPTH`], written from the definition
    /// (libm's ln): the reference `diffuse_light`'s D is checked against.
    fn diffuse_share(gamma: f32, g: f32) -> f32 {
        let tau = -gamma.max(1e-30).ln() / (1.0 - g * g);
        1.0 / (1.0 + STREAM_DEPTH * 0.75 * (1.0 - g) * tau)
    }

    #[test]
    fn the_diffuse_share_is_the_two_stream_transmission() {
        // Γ = 1 (no cloud above): all of it; τ = 10 at g = 0.86: 1/(1 + 0.4·0.75·0.14·10).
        assert!((diffuse_share(1.0, 0.86) - 1.0).abs() < 1e-6);
        let gamma = (-(1.0f32 - 0.86 * 0.86) * 10.0).exp();
        assert!((diffuse_share(gamma, 0.86) - 1.0 / (1.0 + STREAM_DEPTH * 1.05)).abs() < 1e-4);
        // Γ → 0 (clamped at 1e-30: τ = 265): 1/(1 + 0.4·0.105·265) = 0.083.
        assert!(diffuse_share(0.0, 0.86) > 0.07 && diffuse_share(0.0, 0.86) < 0.1);
        // The diffuse light's streams, each at weight 1: none in open air; at the lit face of
        // a thick cloud (τ_b = 50 below) its reflection, 1 − 1/(1 + 0.4·0.75·0.14·50); deep under
        // it the transmission alone; the weights scale each stream.
        let ones = (1.0, 1.0);
        assert_eq!(diffuse_light(1.0, 1.0, 0.86, false, ones), 0.0);
        let thick = (-(1.0f32 - 0.86 * 0.86) * 50.0).exp();
        let r = 1.0 - 1.0 / (1.0 + STREAM_DEPTH * 0.75 * 0.14 * 50.0);
        assert!((diffuse_light(1.0, thick, 0.86, false, ones) - r).abs() < 1e-4);
        assert!((diffuse_light(1.0, thick, 0.86, false, (0.3, 0.7)) - 0.7 * r).abs() < 1e-4);
        let under = diffuse_light(thick, thick, 0.86, true, ones);
        assert!((under - diffuse_share(thick, 0.86)).abs() < 1e-6);
        let under_w = diffuse_light(thick, thick, 0.86, true, (0.3, 0.7));
        assert!((under_w - 0.3 * diffuse_share(thick, 0.86)).abs() < 1e-6);
    }

    /// P(μ) by a midpoint rule over the stream's hemisphere (400 x 800), in f64.
    fn stream_share_quadrature(mu: f64, g: f64) -> f64 {
        let v = [(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu];
        let (n, m) = (400, 800);
        let mut sum = 0.0;
        for i in 0..n {
            let c = (i as f64 + 0.5) / n as f64;
            let s = (1.0 - c * c).sqrt();
            for j in 0..m {
                let phi = (j as f64 + 0.5) / m as f64 * std::f64::consts::TAU;
                let cos = s * phi.cos() * v[0] + c * v[2];
                sum += henyey_greenstein(cos, g);
            }
        }
        sum / n as f64 * std::f64::consts::TAU / m as f64
    }

    #[test]
    fn the_stream_share_is_the_phase_over_the_streams_hemisphere() {
        for mu in [-1.0f32, -0.77, -0.32, -0.1, 0.0, 0.1, 0.35, 0.6, 1.0] {
            let want = stream_share_quadrature(f64::from(mu), 0.86);
            let got = f64::from(stream_share(mu, 0.86));
            assert!((got - want).abs() < 0.015, "μ {mu}: {got} vs {want}");
            let back = f64::from(stream_share(-mu, 0.86));
            assert!((got + back - 1.0).abs() < 1e-6);
        }
        // Isotropic particles scatter half of each stream every way.
        assert_eq!(stream_share(0.7, 0.0), 0.5);
        // The weights: a side view (μ = 0) takes K_THROUGH/2 and K_BACK/2.
        let (t, b) = stream_weights(0.0, 0.86);
        assert!((t - 0.5 * K_THROUGH).abs() < 1e-6 && (b - 0.5 * K_BACK).abs() < 1e-6);
        let (t_below, b_below) = stream_weights(0.9, 0.86);
        assert!(t_below > t && b_below < b);
    }

    #[test]
    fn nearer_surfaces_hide_the_clouds() {
        let c = cam(9, 9);
        let field = CloudField::new(one(3.0), None, 8).unwrap();
        let pass = CloudPass {
            field: &field,
            light: SKY_ONLY,
        };
        let s = CloudSplats::prepare(&pass, &c).unwrap();
        let mut rgb = vec![0.25f32; 27];
        let mut alpha = vec![0.0f32; 9];
        s.apply_row(&c, 4, &mut rgb, &[10.0; 9], Some(&mut alpha));
        assert!(rgb.iter().all(|&v| v == 0.25) && alpha.iter().all(|&a| a == 0.0));
    }

    /// `n` particles over 900-1500 m above the camera, lit by a sun.
    fn many(n: usize, seed: u64) -> CloudField {
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let positions = (0..n)
            .map(|_| {
                [
                    rng.random_range(-700.0..700.0),
                    rng.random_range(900.0..1500.0),
                    rng.random_range(-500.0..500.0),
                ]
            })
            .collect();
        let cloud = Cloud::new(
            positions,
            (0..n).map(|_| rng.random_range(20.0..90.0)).collect(),
            (0..n).map(|_| rng.random_range(0.2..4.0)).collect(),
            vec![0.99; n],
            0.86,
        )
        .unwrap();
        CloudField::new(cloud, Some([0.3, 0.8, -0.2]), 32).unwrap()
    }

    const LIGHT: CloudLight = CloudLight {
        sun: Vec3::new(3.0, 2.9, 2.7),
        sky: Vec3::ONE,
    };

    /// Row `y`'s depths, m: a scene that cuts through [`many`]'s particles (800 m to
    /// infinity, varying along the row), every sixth pixel nearer than every cloud.
    fn cut_depth(w: usize, y: usize) -> Vec<f32> {
        (0..w)
            .map(|x| match (x + y) % 6 {
                0 => f32::INFINITY,
                1 => 100.0,
                k => 800.0 + 180.0 * k as f32 + 3.0 * y as f32,
            })
            .collect()
    }

    #[test]
    fn pixels_walked_together_keep_each_pixels_own_bits() {
        // A frame whose width is no multiple of the lanes (the last group of each tile row is
        // partial), composited a row at a time against each pixel walked alone (a group of
        // one), bit for bit, with and without the diffuse light and the sun.
        let (w, h) = (45usize, 21usize);
        let c = cam(w as u32, h as u32);
        let mut field = many(300, 11);
        for (diffuse, sun) in [(true, true), (false, true), (true, false)] {
            field.diffuse = diffuse;
            let mut f = field.clone();
            if !sun {
                f.sun = None;
            }
            let pass = CloudPass {
                field: &f,
                light: LIGHT,
            };
            let s = CloudSplats::prepare(&pass, &c).unwrap();
            let mut touched = 0;
            for y in 0..h {
                let depth = cut_depth(w, y);
                let mut rgb: Vec<f32> = (0..3 * w).map(|i| 0.1 + 0.01 * i as f32).collect();
                let bg = rgb.clone();
                let mut alpha = vec![-1.0f32; w];
                s.apply_row(&c, y as u32, &mut rgb, &depth, Some(&mut alpha));
                for x in 0..w {
                    let t = (y as u32 / TILE_PX * s.tiles_x + x as u32 / TILE_PX) as usize;
                    let list = &s.indices[s.offsets[t] as usize..s.offsets[t + 1] as usize];
                    let (trans, acc) = if list.is_empty() {
                        ([1.0; LANES], [Vec3::ZERO; LANES])
                    } else {
                        s.composite(&c, y as u32, x, &depth[x..x + 1], list)
                    };
                    let alone = acc[0] + Vec3::from_slice(&bg[3 * x..3 * x + 3]) * trans[0];
                    assert_eq!(
                        alone.to_array().map(f32::to_bits),
                        [rgb[3 * x], rgb[3 * x + 1], rgb[3 * x + 2]].map(f32::to_bits),
                        "pixel ({x}, {y}), diffuse {diffuse}, sun {sun}"
                    );
                    assert_eq!((1.0 - trans[0]).to_bits(), alpha[x].to_bits());
                    touched += usize::from(trans[0] < 1.0);
                }
            }
            assert!(touched > w * h / 4, "{touched} of {} pixels", w * h);
        }
    }

    #[test]
    fn a_pixel_ends_its_splats_beyond_the_scene_without_changing_a_bit() {
        // Many particles over 900-1500 m above the camera, a scene whose depth cuts through
        // them (rows at 800 m to infinity, columns varying): the early end beyond the scene
        // (`reach_m`) against the same splats read to the end of every list (reach_m infinite:
        // `beyond` infinite, every splat tested as before), bit for bit; and the early end
        // does skip splats (a depth nearer than every cloud leaves the pixel untouched).
        let c = cam(48, 32);
        let field = many(400, 5);
        let pass = CloudPass {
            field: &field,
            light: LIGHT,
        };
        let early = CloudSplats::prepare(&pass, &c).unwrap();
        let mut full = early.clone();
        full.reach_m = f32::INFINITY;
        let (w, h) = (48usize, 32usize);
        let draw = |s: &CloudSplats<'_>| {
            let mut rgb = vec![0.4f32; 3 * w * h];
            let mut alpha = vec![0.0f32; w * h];
            for y in 0..h {
                let depth = cut_depth(w, y);
                s.apply_row(
                    &c,
                    y as u32,
                    &mut rgb[3 * w * y..3 * w * (y + 1)],
                    &depth,
                    Some(&mut alpha[w * y..w * (y + 1)]),
                );
            }
            (rgb, alpha)
        };
        let (a, b) = (draw(&early), draw(&full));
        assert!(
            a.0.iter()
                .zip(&b.0)
                .all(|(x, y)| x.to_bits() == y.to_bits())
        );
        assert!(
            a.1.iter()
                .zip(&b.1)
                .all(|(x, y)| x.to_bits() == y.to_bits())
        );
        let covered = |keep: usize| {
            (0..w * h)
                .filter(|i| (i % w + i / w) % 6 == keep)
                .map(|i| a.1[i])
                .collect::<Vec<f32>>()
        };
        assert!(covered(1).iter().all(|&v| v == 0.0));
        let open = covered(0);
        assert!(
            open.iter().sum::<f32>() / open.len() as f32 > 0.5,
            "{open:?}"
        );
    }

    #[test]
    fn splats_behind_the_camera_are_dropped() {
        let c = cam(9, 9);
        let below = Cloud::new(
            vec![[0.0, -1000.0, 0.0]],
            vec![50.0],
            vec![1.0],
            vec![1.0],
            0.86,
        )
        .unwrap();
        let field = CloudField::new(below, None, 8).unwrap();
        let pass = CloudPass {
            field: &field,
            light: SKY_ONLY,
        };
        let s = CloudSplats::prepare(&pass, &c).unwrap();
        assert!(s.splats.is_empty() && s.indices.is_empty());
    }
}
