//! The surface the snow lies on: a horizontal grid of square cells and, per cell, the height
//! of the highest surface over its centre (NaN: no surface there, e.g. where a photo shows
//! nothing).

use crate::error::{Error, Param, Result, try_filled};
use crate::scene::boxes::BoxScene;
use crate::scene::camera::Camera;

/// Most cells a cover may have: 4096².
pub const MAX_CELLS: usize = 1 << 24;

/// How far from the camera, horizontally, a photo's points enter its height field, m: beyond,
/// the photo's surfaces are taken as level open ground ([`super::render`]).
pub const PHOTO_RANGE_M: f64 = 200.0;

/// A horizontal grid: cell (i, k) spans x ∈ origin_x + [i, i+1)·spacing, z ∈ origin_z +
/// [k, k+1)·spacing; values are stored row-major, `nz` rows of `nx` cells.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    /// World (x, z) of the corner of cell (0, 0), m.
    pub origin_m: [f64; 2],
    /// Cell side, m.
    pub spacing_m: f64,
    /// Cells along x.
    pub nx: usize,
    /// Cells along z.
    pub nz: usize,
}

impl Grid {
    /// The grid of `spacing_m` cells covering x ∈ [lo[0], hi[0]], z ∈ [lo[1], hi[1]] (its
    /// corner at `lo`), refused beyond [`MAX_CELLS`] naming `resolution_m`.
    pub fn covering(lo: [f64; 2], hi: [f64; 2], spacing_m: f64) -> Result<Self> {
        crate::ranges::RESOLUTION_M.check(spacing_m)?;
        let n = |a: f64, b: f64| (((b - a) / spacing_m).ceil().max(1.0)) as usize;
        let (nx, nz) = (n(lo[0], hi[0]), n(lo[1], hi[1]));
        let cells = nx as u128 * nz as u128;
        if !(lo.iter().chain(hi.iter()).all(|v| v.is_finite())) || cells > MAX_CELLS as u128 {
            return Err(Error::Unusable {
                param: Param {
                    name: "resolution_m",
                    index: None,
                },
                value: spacing_m,
                message: format!(
                    "m over {:.1} m x {:.1} m gives {nx} x {nz} cells, more than the {MAX_CELLS} a cover may have: use coarser cells",
                    hi[0] - lo[0],
                    hi[1] - lo[1]
                ),
            });
        }
        Ok(Grid {
            origin_m: lo,
            spacing_m,
            nx,
            nz,
        })
    }

    /// Cells.
    pub fn cells(&self) -> usize {
        self.nx * self.nz
    }

    /// Area of one cell, m².
    pub fn cell_area_m2(&self) -> f64 {
        self.spacing_m * self.spacing_m
    }

    /// World (x, z) of cell (i, k)'s centre, m.
    #[inline]
    pub fn centre(&self, i: usize, k: usize) -> [f64; 2] {
        [
            self.origin_m[0] + (i as f64 + 0.5) * self.spacing_m,
            self.origin_m[1] + (k as f64 + 0.5) * self.spacing_m,
        ]
    }

    /// The cell holding world (x, z), or None outside the grid.
    #[inline]
    pub fn cell_of(&self, x: f64, z: f64) -> Option<(usize, usize)> {
        let fi = ((x - self.origin_m[0]) / self.spacing_m).floor();
        let fk = ((z - self.origin_m[1]) / self.spacing_m).floor();
        if fi >= 0.0 && fk >= 0.0 && fi < self.nx as f64 && fk < self.nz as f64 {
            Some((fi as usize, fk as usize))
        } else {
            None
        }
    }
}

/// A grid and the height of the surface over each cell's centre, m (NaN: none).
#[derive(Debug, Clone, PartialEq)]
pub struct HeightField {
    /// The grid.
    pub grid: Grid,
    /// Base height per cell, m, row-major.
    pub base_m: Vec<f64>,
}

impl HeightField {
    /// The box scene's ground (y = 0, where it has one) and box tops over `grid`: each cell
    /// the highest top of the boxes over its centre (an awning's top hides the ground beneath
    /// it: snow falling straight down lands on the awning).
    pub fn from_boxes(scene: &BoxScene, grid: Grid) -> Result<Self> {
        let ground = if scene.ground { 0.0 } else { f64::NAN };
        let mut base = try_filled("snow cover", grid.cells(), ground)?;
        let s = grid.spacing_m;
        for b in &scene.boxes {
            // Cells whose centre lies inside the box's footprint.
            let range = |lo: f32, hi: f32, o: f64, n: usize| {
                let a = ((f64::from(lo) - o) / s - 0.5).ceil().max(0.0);
                let e = ((f64::from(hi) - o) / s - 0.5).floor().min(n as f64 - 1.0);
                (a as usize, e)
            };
            let (i0, i1) = range(b.min_m.x, b.max_m.x, grid.origin_m[0], grid.nx);
            let (k0, k1) = range(b.min_m.z, b.max_m.z, grid.origin_m[1], grid.nz);
            if i1 < i0 as f64 || k1 < k0 as f64 {
                continue;
            }
            let top = f64::from(b.max_m.y);
            for k in k0..=k1 as usize {
                for i in i0..=i1 as usize {
                    let c = &mut base[k * grid.nx + i];
                    if c.is_nan() || *c < top {
                        *c = top;
                    }
                }
            }
        }
        Ok(HeightField { grid, base_m: base })
    }

    /// A photo's surfaces: every pixel with a finite depth within [`PHOTO_RANGE_M`] of the
    /// camera (horizontally) put in the world through `cam` (p = eye + ray·depth) and each
    /// cell the highest point in it; `spacing_m` cells over the points' extent.
    pub fn from_depth_map(cam: &Camera, depth_m: &[f32], spacing_m: f64) -> Result<Self> {
        crate::ranges::RESOLUTION_M.check(spacing_m)?;
        let points = photo_points(cam, depth_m);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in points.iter().flatten() {
            lo = [lo[0].min(p[0]), lo[1].min(p[2])];
            hi = [hi[0].max(p[0]), hi[1].max(p[2])];
        }
        if !lo[0].is_finite() {
            // Nothing within range: a one-cell grid at the camera with no surface.
            let e = cam.position_m;
            lo = [e.x, e.z];
            hi = lo;
        }
        let grid = Grid::covering(lo, [hi[0] + 1e-9, hi[1] + 1e-9], spacing_m)?;
        let mut base = try_filled("snow cover", grid.cells(), f64::NAN)?;
        for p in points.iter().flatten() {
            if let Some((i, k)) = grid.cell_of(p[0], p[2]) {
                let c = &mut base[k * grid.nx + i];
                if c.is_nan() || *c < p[1] {
                    *c = p[1];
                }
            }
        }
        Ok(HeightField { grid, base_m: base })
    }
}

/// Each pixel's world point (p = eye + ray · depth), or None for sky, no depth, or beyond
/// [`PHOTO_RANGE_M`] horizontally.
pub fn photo_points(cam: &Camera, depth_m: &[f32]) -> Vec<Option<[f64; 3]>> {
    let w = cam.width as usize;
    let e = cam.position_m;
    depth_m
        .iter()
        .enumerate()
        .map(|(idx, &d)| {
            if !(d.is_finite() && d > 0.0) {
                return None;
            }
            let r = cam.ray_direction((idx % w) as u32, (idx / w) as u32);
            let d = f64::from(d);
            let p = [
                e.x + f64::from(r.x) * d,
                e.y + f64::from(r.y) * d,
                e.z + f64::from(r.z) * d,
            ];
            let (dx, dz) = (p[0] - e.x, p[2] - e.z);
            (dx * dx + dz * dz <= PHOTO_RANGE_M * PHOTO_RANGE_M).then_some(p)
        })
        .collect()
}
