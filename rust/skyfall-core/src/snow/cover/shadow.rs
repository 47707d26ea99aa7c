//! The shadow buffer of the paper's §4.2, rendered along one of the snow's fall paths instead
//! of a light's rays: every point of the height field (cell tops, and the sides a cell shows
//! above its lowest neighbour, sampled once per texel along the drift's major axis; a side lower
//! than the bias by its top alone) is projected along the path onto the level y = y₀ (the
//! lowest surface), q = (x, z) + s·(y − y₀) with s the path's horizontal drift per metre, into
//! texels of the grid's cell size; a texel keeps the highest point that projects into it (the first
//! surface the snow falling along that line meets). A cell is lit when its own top is that
//! highest point, within [`ShadowBuffer::bias_m`] (half a texel of fall, Δx/(2|s|), which keeps
//! slopes up to half as steep as the fall line from shadowing themselves).
//!
//! The heights need not be metres of height: the cover passes each point's *lift* (its height
//! with the canopy's slower wind below the roofs folded in, [`super::wind::Canopy::lift_m`]),
//! under which a curved path is straight; any height that grows with the height works.

use super::heightfield::Grid;

/// The buffer may extend beyond the grid, along the drift, by this many times the grid's
/// larger side; points projecting further are lit (nothing is rendered there).
const MAX_EXTENSION: f64 = 4.0;

/// The shadow buffer of one step.
#[derive(Debug, Clone)]
pub struct ShadowBuffer {
    origin_m: [f64; 2],
    spacing_m: f64,
    nx: usize,
    nz: usize,
    /// Highest surface per texel, m (−inf: none).
    texels: Vec<f64>,
    drift: [f64; 2],
    y0_m: f64,
    /// Height tolerance of the lit test, m.
    pub bias_m: f64,
}

impl ShadowBuffer {
    /// Renders the surface `top_m` (per cell of `grid`, NaN: none) along the drift `drift`
    /// (horizontal m per m of fall).
    /// Its texels are allocated fallibly ([`crate::Error::OutOfMemory`]).
    pub fn render(grid: &Grid, top_m: &[f64], drift: [f64; 2]) -> crate::error::Result<Self> {
        let (mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY);
        for &t in top_m.iter().filter(|t| !t.is_nan()) {
            y0 = y0.min(t);
            y1 = y1.max(t);
        }
        if !y0.is_finite() {
            (y0, y1) = (0.0, 0.0);
        }
        let s = grid.spacing_m;
        let span = (grid.nx.max(grid.nz) as f64) * s * MAX_EXTENSION;
        let reach = [
            (drift[0] * (y1 - y0)).clamp(-span, span),
            (drift[1] * (y1 - y0)).clamp(-span, span),
        ];
        let extra = |r: f64| (r.abs() / s).ceil() as usize;
        // Texels aligned with the cells, extended on the side the drift carries the shadows.
        let below = |r: f64| if r < 0.0 { extra(r) as f64 * s } else { 0.0 };
        let lo = [
            grid.origin_m[0] - below(reach[0]),
            grid.origin_m[1] - below(reach[1]),
        ];
        let (nx, nz) = (grid.nx + extra(reach[0]), grid.nz + extra(reach[1]));
        let ds = (drift[0] * drift[0] + drift[1] * drift[1]).sqrt();
        let bias_m = if ds > 0.0 {
            0.5 * s / ds
        } else {
            f64::INFINITY
        };
        let mut buf = ShadowBuffer {
            origin_m: lo,
            spacing_m: s,
            nx,
            nz,
            texels: crate::error::try_filled(
                "the snow cover's shadow buffer",
                nx.saturating_mul(nz),
                f64::NEG_INFINITY,
            )?,
            drift,
            y0_m: y0,
            bias_m,
        };
        // Sample the sides once per texel along the drift's major axis (a line drawn as
        // Bresenham draws it: each column or row of texels it crosses once).
        let major = drift[0].abs().max(drift[1].abs());
        let dy = if major > 0.0 {
            s / major
        } else {
            f64::INFINITY
        };
        let top = |i: isize, k: isize| -> f64 {
            if i < 0 || k < 0 || i >= grid.nx as isize || k >= grid.nz as isize {
                return y0;
            }
            let t = top_m[k as usize * grid.nx + i as usize];
            if t.is_nan() { y0 } else { t }
        };
        for k in 0..grid.nz {
            for i in 0..grid.nx {
                let t = top_m[k * grid.nx + i];
                if t.is_nan() {
                    continue;
                }
                let (ii, kk) = (i as isize, k as isize);
                let low = top(ii - 1, kk)
                    .min(top(ii + 1, kk))
                    .min(top(ii, kk - 1))
                    .min(top(ii, kk + 1))
                    .min(t);
                let c = grid.centre(i, k);
                // A side lower than half a texel of fall is drawn by its top alone: the points
                // below it could only shade what lies within the lit test's bias of them.
                let n = if t - low >= bias_m && dy.is_finite() {
                    (((t - low) / dy).ceil() as usize).min(8 * (nx + nz))
                } else {
                    0
                };
                for j in 0..=n {
                    let y = if n == 0 {
                        t
                    } else {
                        t - (t - low) * j as f64 / n as f64
                    };
                    if let Some(idx) = buf.texel(c, y) {
                        let v = &mut buf.texels[idx];
                        if *v < y {
                            *v = y;
                        }
                    }
                }
            }
        }
        Ok(buf)
    }

    /// The texel the point (c.x, y, c.z) projects into, or None outside the buffer.
    #[inline]
    fn texel(&self, c: [f64; 2], y: f64) -> Option<usize> {
        let h = y - self.y0_m;
        let qx = c[0] + self.drift[0] * h;
        let qz = c[1] + self.drift[1] * h;
        let fi = (qx - self.origin_m[0]) / self.spacing_m;
        let fk = (qz - self.origin_m[1]) / self.spacing_m;
        // floor(f) >= 0 and < n exactly when 0 <= f < n: then truncation is the floor (and
        // it needs no call into libm, which baseline x86-64 makes for `floor`).
        if fi >= 0.0 && fk >= 0.0 && fi < self.nx as f64 && fk < self.nz as f64 {
            Some(fk as usize * self.nx + fi as usize)
        } else {
            None
        }
    }

    /// Whether the snow falling along the drift reaches the point (c.x, y, c.z) of the
    /// surface (nothing higher projects into its texel, within the bias).
    #[inline]
    pub fn lit(&self, c: [f64; 2], y: f64) -> bool {
        match self.texel(c, y) {
            Some(idx) => y + self.bias_m >= self.texels[idx],
            None => true,
        }
    }
}
