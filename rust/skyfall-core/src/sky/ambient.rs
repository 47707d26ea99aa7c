//! The ambient-light map (Yamamoto & Tadamura §4.3): sky illuminance on the five normals at the nodes of
//! a uniform 3D grid, interpolated trilinearly.
//!
//! Nodes inside a box (strictly inside in X and Z, from its base up to below its roof) hold no
//! meaningful light: they are marked solid, and sampling interpolates over the cell's open
//! corners only (weights renormalised), so a point beneath a thin awning reads the nodes below
//! it, not the sky above it, and a point on a wall the light in front of the wall. Solid
//! nodes are also filled from their open neighbours (repeated 6-neighbour averaging), for the
//! rare cell whose corners are all solid. Points outside the grid take the nearest boundary
//! value.
//!
//! [`AmbientMap::sample`] is the CPU reference of the WGSL `ambient_sample` in
//! `skyfall-gpu`'s `common.wgsl`.

use super::illuminance::{CHANNELS, SkyTable, VisibleSky, boxes_above};
use crate::error::{Error, Param, Range, Result, check_cancel, try_filled};
use crate::scene::boxes::BoxScene;
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// Most nodes a map may have (16 M: 320 MB of float32).
pub const MAX_NODES: usize = 16 << 20;
/// The largest |coordinate| of a map's bounds, m (the box scene's world).
pub const MAP_EXTENT_M: f64 = 1e6;
/// Valid grid spacings.
pub const SPACING_M: Range = crate::ranges::SPACING_M.range;

/// Illuminance relative to E on five normals over a grid.
#[derive(Debug, Clone, PartialEq)]
pub struct AmbientMap {
    /// Position of node (0, 0, 0), m.
    pub origin_m: Vec3,
    /// Node spacing, m.
    pub spacing_m: f32,
    /// Nodes along X, Y, Z.
    pub dims: [usize; 3],
    /// Values, [`CHANNELS`] per node, node (i, j, k) at ((i·ny + j)·nz + k)·5.
    pub values: Vec<f32>,
    /// 1 for nodes inside a box, 0 for open ones, node (i, j, k) at (i·ny + j)·nz + k.
    pub solid: Vec<u32>,
    /// The colour of the light this map's sky gives a horizontal surface (linear RGB of
    /// luminance 1), where it is not the sky's own [`super::Sky::light_colour`]: a sky with
    /// clouds in it (`crate::cloud::dome`). A frame lit by the map takes it.
    pub light_colour: Option<Vec3>,
}

/// Whether a node is inside a box (and so filled from outside).
pub(crate) fn solid(scene: &BoxScene, p: Vec3) -> bool {
    scene.boxes.iter().any(|b| {
        p.x > b.min_m.x
            && p.x < b.max_m.x
            && p.z > b.min_m.z
            && p.z < b.max_m.z
            && p.y >= b.min_m.y
            && p.y < b.max_m.y
    })
}

impl AmbientMap {
    /// A map of one node: the same light everywhere (a scene without occluders).
    pub fn uniform(values: [f32; CHANNELS]) -> Self {
        AmbientMap {
            origin_m: Vec3::ZERO,
            spacing_m: 1.0,
            dims: [1, 1, 1],
            values: values.to_vec(),
            solid: vec![0],
            light_colour: None,
        }
    }

    /// Node count for a box `min_m`..`max_m` at `spacing_m`, validated.
    pub fn grid_dims(min_m: Vec3, max_m: Vec3, spacing_m: f64) -> Result<[usize; 3]> {
        Self::grid_dims_for(min_m, max_m, spacing_m, "spacing_m")
    }

    /// [`Self::grid_dims`], errors naming the spacing as its caller's user knows it
    /// (`ambient_spacing_m` for a frame's map); too fine a spacing is refused with the
    /// coarsest that fits.
    pub fn grid_dims_for(
        min_m: Vec3,
        max_m: Vec3,
        spacing_m: f64,
        name: &'static str,
    ) -> Result<[usize; 3]> {
        SPACING_M.check(name, None, spacing_m)?;
        let coord = Range::closed(-MAP_EXTENT_M, MAP_EXTENT_M, "m");
        for k in 0..3 {
            coord.check("bounds.min", Some(k), f64::from(min_m[k]))?;
            coord.check("bounds.max", Some(k), f64::from(max_m[k]))?;
            if max_m[k] < min_m[k] {
                return Err(Error::Invalid {
                    param: Param {
                        name: "bounds",
                        index: Some(k),
                    },
                    message: format!("max {} is below min {}", max_m[k], min_m[k]),
                });
            }
        }
        let extent = [0, 1, 2].map(|k| f64::from(max_m[k] - min_m[k]));
        let dims_at = |s: f64| extent.map(|e| (e / s).ceil() as usize + 1);
        let count = |d: [usize; 3]| d.iter().map(|&n| n as u128).product::<u128>();
        let dims = dims_at(spacing_m);
        let nodes = count(dims);
        if nodes > MAX_NODES as u128 {
            // The coarsest spacing that fits, rounded up to two significant digits.
            let mut s = spacing_m * (nodes as f64 / MAX_NODES as f64).cbrt();
            while count(dims_at(s)) > MAX_NODES as u128 {
                s *= 1.02;
            }
            let per = 10f64.powi(1 - s.log10().floor() as i32);
            let s = (s * per).ceil() / per;
            return Err(Error::Unusable {
                param: Param { name, index: None },
                value: spacing_m,
                message: format!(
                    "m needs {}x{}x{} = {nodes} map nodes over these bounds, more than the {MAX_NODES} a map may have: use {name} >= {s} m or smaller bounds",
                    dims[0], dims[1], dims[2]
                ),
            });
        }
        Ok(dims)
    }

    /// Builds the map over `min_m`..`max_m` (the last node may overshoot `max_m` by less than
    /// a spacing), nodes in parallel.
    pub fn build(
        scene: &BoxScene,
        samples: &SkyTable,
        min_m: Vec3,
        max_m: Vec3,
        spacing_m: f64,
    ) -> Result<Self> {
        Self::build_cancellable(
            scene,
            samples,
            min_m,
            max_m,
            spacing_m,
            &AtomicBool::new(false),
        )
    }

    /// [`AmbientMap::build`], stopping with [`Error::Cancelled`] soon after `cancel` is set:
    /// it is checked before every node (one node is `samples.azimuths()` azimuths over the
    /// boxes above it: milliseconds at 65536 azimuths) and every pass of the solid fill. A
    /// grid whose buffers cannot be allocated is [`Error::OutOfMemory`].
    pub fn build_cancellable(
        scene: &BoxScene,
        samples: &SkyTable,
        min_m: Vec3,
        max_m: Vec3,
        spacing_m: f64,
        cancel: &AtomicBool,
    ) -> Result<Self> {
        let dims = Self::grid_dims(min_m, max_m, spacing_m)?;
        let [nx, ny, nz] = dims;
        let s = spacing_m as f32;
        let nodes = nx * ny * nz;
        let mut values = try_filled("the ambient map's values", nodes * CHANNELS, 0.0f32)?;
        let mut is_solid = try_filled("the ambient map's solid nodes", nodes, false)?;
        let dirs = samples.dirs();
        values
            .par_chunks_mut(nz * CHANNELS)
            .zip(is_solid.par_chunks_mut(nz))
            .enumerate()
            .for_each_init(VisibleSky::default, |sky, (ij, (column, solid_col))| {
                let (i, j) = (ij / ny, ij % ny);
                let y = min_m.y + j as f32 * s;
                let above = boxes_above(scene, y);
                for k in 0..nz {
                    if cancel.load(Ordering::Relaxed) {
                        return;
                    }
                    let p = min_m + Vec3::new(i as f32 * s, j as f32 * s, k as f32 * s);
                    if solid(scene, p) {
                        solid_col[k] = true;
                    } else {
                        sky.clear();
                        sky.find(&above, dirs, p);
                        column[k * CHANNELS..(k + 1) * CHANNELS]
                            .copy_from_slice(&sky.light(samples));
                    }
                }
            });
        check_cancel(cancel, "the ambient-light map")?;
        Self::finish(min_m, s, dims, values, is_solid, cancel)
    }

    /// The map of `values` over the grid (`min_m`, spacing `s`, `dims`), its solid nodes
    /// `is_solid` filled from their open neighbours.
    pub(crate) fn finish(
        min_m: Vec3,
        s: f32,
        dims: [usize; 3],
        values: Vec<f32>,
        is_solid: Vec<bool>,
        cancel: &AtomicBool,
    ) -> Result<Self> {
        let plan = FillPlan::new(dims, &is_solid, cancel)?;
        let mut solid = try_filled("the ambient map's solid nodes", is_solid.len(), 0u32)?;
        for (o, &b) in solid.iter_mut().zip(&is_solid) {
            *o = u32::from(b);
        }
        Ok(Self::finish_planned(min_m, s, dims, values, solid, &plan))
    }

    /// [`Self::finish`] with the solid nodes' fill planned before ([`FillPlan::new`] of these
    /// `dims` and solid nodes), `solid` those nodes as the map holds them: the same map.
    pub(crate) fn finish_planned(
        min_m: Vec3,
        s: f32,
        dims: [usize; 3],
        mut values: Vec<f32>,
        solid: Vec<u32>,
        plan: &FillPlan,
    ) -> Self {
        plan.apply(&mut values);
        AmbientMap {
            origin_m: min_m,
            spacing_m: s,
            dims,
            values,
            solid,
            light_colour: None,
        }
    }

    /// Trilinear interpolation of the five channels at `p` (clamped to the grid) over the
    /// cell's open corners; over all of them when every corner with weight is solid.
    #[inline]
    pub fn sample(&self, p: Vec3) -> [f32; CHANNELS] {
        if let Ok(only) = <[f32; CHANNELS]>::try_from(&self.values[..]) {
            // One node (the open sky of a scene without occluders): its values everywhere.
            return only;
        }
        let mut base = [0usize; 3];
        let mut frac = [0.0f32; 3];
        for a in 0..3 {
            let n = self.dims[a];
            let g = ((p[a] - self.origin_m[a]) / self.spacing_m).clamp(0.0, (n - 1) as f32);
            // g ≥ 0: truncation is the floor (f32::floor is a libm call on SSE2 targets).
            let i0 = (g as usize).min(n.saturating_sub(2));
            base[a] = i0;
            frac[a] = if n > 1 { g - i0 as f32 } else { 0.0 };
        }
        let [_, ny, nz] = self.dims;
        let mut open = [0.0f32; CHANNELS];
        let mut open_w = 0.0f32;
        let mut out = [0.0f32; CHANNELS];
        for corner in 0..8usize {
            let off = [corner & 1, (corner >> 1) & 1, (corner >> 2) & 1];
            let mut w = 1.0;
            let mut ijk = [0usize; 3];
            for a in 0..3 {
                w *= if off[a] == 1 { frac[a] } else { 1.0 - frac[a] };
                ijk[a] = (base[a] + off[a]).min(self.dims[a] - 1);
            }
            if w == 0.0 {
                continue;
            }
            let n = (ijk[0] * ny + ijk[1]) * nz + ijk[2];
            let is_open = self.solid[n] == 0;
            for (c, v) in self.values[n * CHANNELS..(n + 1) * CHANNELS]
                .iter()
                .enumerate()
            {
                out[c] += w * v;
                if is_open {
                    open[c] += w * v;
                }
            }
            if is_open {
                open_w += w;
            }
        }
        if open_w > 0.0 {
            open.map(|v| v / open_w)
        } else {
            out
        }
    }

    /// The channel a surface with unit axis-aligned normal `n` reads: 0 up, 1 +X, 2 −X, 3 +Z,
    /// 4 −Z, None for a face looking down (no sky).
    #[inline]
    pub fn channel(n: Vec3) -> Option<usize> {
        if n.y > 0.5 {
            Some(0)
        } else if n.y < -0.5 {
            None
        } else if n.x > 0.5 {
            Some(1)
        } else if n.x < -0.5 {
            Some(2)
        } else if n.z > 0.5 {
            Some(3)
        } else {
            Some(4)
        }
    }
}

/// Default bounds of a scene's map: the boxes' extent and `extra` points (the camera, the rain
/// region), from the ground to a spacing above the tallest roof.
pub fn scene_bounds(scene: &BoxScene, extra: &[Vec3], spacing_m: f32) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for b in &scene.boxes {
        lo = lo.min(b.min_m);
        hi = hi.max(b.max_m);
    }
    for p in extra {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    if !lo.is_finite() {
        return (Vec3::ZERO, Vec3::ZERO);
    }
    if scene.ground {
        lo.y = lo.y.max(0.0);
    }
    (lo, hi + Vec3::new(0.0, spacing_m, 0.0))
}

/// The order in which a map's solid nodes are filled, and from which neighbours: each takes
/// the mean of its 6-neighbours filled before it, layer by layer inward (a layer's nodes read
/// only the open nodes and the layers before). It depends only on the grid and its solid
/// nodes, so a horizon plans it once for all its maps.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct FillPlan {
    /// (node, its first neighbour in `from`, their count), in fill order.
    steps: Vec<(u32, u32, u8)>,
    /// The neighbours each step averages, step after step.
    from: Vec<u32>,
}

impl FillPlan {
    /// The plan for a grid of `dims` nodes whose solid ones are `is_solid`; solid nodes with no
    /// open node to reach (a grid of solid nodes only) are left out and stay 0.
    pub(crate) fn new(dims: [usize; 3], is_solid: &[bool], cancel: &AtomicBool) -> Result<Self> {
        let [nx, ny, nz] = dims;
        let idx = |i: usize, j: usize, k: usize| (i * ny + j) * nz + k;
        let mut pending = try_filled("the ambient map's fill", is_solid.len(), false)?;
        pending.copy_from_slice(is_solid);
        let mut next = pending.clone();
        let mut plan = FillPlan::default();
        let solid_count = is_solid.iter().filter(|&&b| b).count();
        plan.steps.try_reserve_exact(solid_count).map_err(|_| {
            Error::out_of_memory::<(u32, u32, u8)>("the ambient map's fill", solid_count)
        })?;
        while pending.iter().any(|&p| p) {
            check_cancel(cancel, "the ambient-light map")?;
            next.copy_from_slice(&pending);
            let pending_count = pending.iter().filter(|&&p| p).count();
            plan.from.try_reserve(6 * pending_count).map_err(|_| {
                Error::out_of_memory::<u32>("the ambient map's fill", 6 * pending_count)
            })?;
            let mut progress = false;
            for i in 0..nx {
                for j in 0..ny {
                    for k in 0..nz {
                        let n = idx(i, j, k);
                        if !pending[n] {
                            continue;
                        }
                        let nbrs = [
                            (i > 0).then(|| idx(i - 1, j, k)),
                            (i + 1 < nx).then(|| idx(i + 1, j, k)),
                            (j > 0).then(|| idx(i, j - 1, k)),
                            (j + 1 < ny).then(|| idx(i, j + 1, k)),
                            (k > 0).then(|| idx(i, j, k - 1)),
                            (k + 1 < nz).then(|| idx(i, j, k + 1)),
                        ];
                        let first = plan.from.len();
                        plan.from.extend(
                            nbrs.into_iter()
                                .flatten()
                                .filter(|&m| !pending[m])
                                .map(|m| m as u32),
                        );
                        let count = plan.from.len() - first;
                        if count > 0 {
                            plan.steps.push((n as u32, first as u32, count as u8));
                            next[n] = false;
                            progress = true;
                        }
                    }
                }
            }
            std::mem::swap(&mut pending, &mut next);
            if !progress {
                break; // every node solid: they stay 0
            }
        }
        Ok(plan)
    }

    /// The bytes it holds.
    pub(crate) fn bytes(&self) -> usize {
        self.steps.len() * size_of::<(u32, u32, u8)>() + self.from.len() * size_of::<u32>()
    }

    /// Fills the planned nodes of `values` ([`CHANNELS`] per node).
    pub(crate) fn apply(&self, values: &mut [f32]) {
        for &(n, first, count) in &self.steps {
            let mut acc = [0.0f32; CHANNELS];
            for &m in &self.from[first as usize..first as usize + usize::from(count)] {
                let m = m as usize;
                for (a, v) in acc
                    .iter_mut()
                    .zip(&values[m * CHANNELS..(m + 1) * CHANNELS])
                {
                    *a += v;
                }
            }
            let n = n as usize;
            for (c, a) in acc.iter().enumerate() {
                values[n * CHANNELS + c] = a / f32::from(count);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::boxes::SceneBox;
    use crate::sky::illuminance::irradiance;
    use crate::sky::{Sky, cie::SkyKind};

    #[test]
    fn trilinear_is_exact_for_linear_fields_and_clamps() {
        let (nx, ny, nz) = (4, 3, 5);
        let f = |p: Vec3, c: usize| 0.5 + 0.1 * p.x - 0.2 * p.y + 0.05 * p.z + c as f32;
        let origin = Vec3::new(-1.0, 0.0, 2.0);
        let mut values = Vec::new();
        for i in 0..nx {
            for j in 0..ny {
                for k in 0..nz {
                    let p = origin + 0.5 * Vec3::new(i as f32, j as f32, k as f32);
                    values.extend((0..CHANNELS).map(|c| f(p, c)));
                }
            }
        }
        let m = AmbientMap {
            origin_m: origin,
            spacing_m: 0.5,
            dims: [nx, ny, nz],
            values,
            solid: vec![0; nx * ny * nz],
            light_colour: None,
        };
        for p in [Vec3::new(-0.3, 0.7, 2.9), Vec3::new(0.5, 1.0, 4.0), origin] {
            for (c, v) in m.sample(p).iter().enumerate() {
                assert!((v - f(p, c)).abs() < 1e-5, "{p} {c}");
            }
        }
        // beyond the grid: the boundary value
        assert!((m.sample(Vec3::new(-9.0, 0.0, 2.0))[0] - f(origin, 0)).abs() < 1e-6);
        assert_eq!(
            AmbientMap::uniform([1.0, 0.4, 0.4, 0.4, 0.4]).sample(Vec3::splat(7.0)),
            [1.0, 0.4, 0.4, 0.4, 0.4]
        );
    }

    #[test]
    fn nodes_inside_boxes_take_the_light_outside() {
        let wall = SceneBox {
            min_m: Vec3::new(2.0, 0.0, -50.0),
            max_m: Vec3::new(4.0, 10.0, 50.0),
            albedo: Vec3::ONE,
        };
        let scene = BoxScene::new(vec![wall], true, Vec3::ONE).unwrap();
        let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
        let s = SkyTable::new(&sky, 256).unwrap();
        let m = AmbientMap::build(
            &scene,
            &s,
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(6.0, 4.0, 0.0),
            1.0,
        )
        .unwrap();
        assert_eq!(m.dims, [7, 5, 1]);
        let at = |i: usize, j: usize| &m.values[(i * 5 + j) * CHANNELS..(i * 5 + j + 1) * CHANNELS];
        // node x = 3 is inside: filled from x = 2 and x = 4 (both on the wall's faces)
        for c in 0..CHANNELS {
            assert!((at(3, 2)[c] - 0.5 * (at(2, 2)[c] + at(4, 2)[c])).abs() < 1e-6);
        }
        // on the wall face x = 2, the -X channel sees open sky, the +X channel none
        assert!(at(2, 2)[2] > 0.35 && at(2, 2)[1] == 0.0);
        // direct evaluation agrees at the nodes
        let direct = irradiance(&boxes_above(&scene, 1.0), &s, Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(m.sample(Vec3::new(1.0, 1.0, 0.0)), direct);
        assert!(AmbientMap::build(&scene, &s, Vec3::ZERO, Vec3::splat(1e5), 0.1).is_err());
        // Halfway between the open node x = 2 and the solid x = 3, the open one alone counts.
        assert_eq!(m.solid[3 * 5 + 2], 1);
        assert_eq!(
            m.sample(Vec3::new(2.5, 2.0, 0.0)),
            m.sample(Vec3::new(2.0, 2.0, 0.0))
        );
    }

    #[test]
    fn a_thin_awning_does_not_leak_the_sky_above_it_below_it() {
        // A 0.25 m awning at 3 m over x in [0, 4]: the 1 m grid's nodes at y = 3 lie inside it.
        let awning = SceneBox {
            min_m: Vec3::new(0.0, 3.0, -50.0),
            max_m: Vec3::new(4.0, 3.25, 50.0),
            albedo: Vec3::ONE,
        };
        let scene = BoxScene::new(vec![awning], true, Vec3::ONE).unwrap();
        let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
        let t = SkyTable::new(&sky, 64).unwrap();
        let m = AmbientMap::build(
            &scene,
            &t,
            Vec3::new(-2.0, 0.0, 0.0),
            Vec3::new(6.0, 6.0, 0.0),
            1.0,
        )
        .unwrap();
        let direct = |p: Vec3| irradiance(&boxes_above(&scene, p.y), &t, p)[0];
        for p in [
            Vec3::new(2.0, 2.6, 0.0),
            Vec3::new(2.3, 2.9, 0.0),
            Vec3::new(2.0, 3.6, 0.0),
        ] {
            let (got, want) = (m.sample(p)[0], direct(p));
            // the residual is the field's own variation between the open nodes used
            assert!((got - want).abs() < 0.12, "{p}: map {got} direct {want}");
        }
    }
}
