//! The walk: the pixels a streak covers in a band of rows, with their coverage and inverse
//! depth, steep streaks four pixels at a time (see [`for_each_fragment_x4`]).

use super::num::{ceil_nonneg, floor_nonneg, idx_f32};
use super::streak::{ScreenStreak, reach};
use glam::Vec4;

/// Calls `f(i, a, inv_z)` for the pixels of rows `y0..y0 + rows` (a band of a `w`-wide
/// frame) that the streak may cover: `i` the index within the band, `a` = α·coverage (0 where
/// it misses the pixel: `f` must treat a = 0 as nothing) and `inv_z` the streak's inverse depth
/// there (1/m), as [`ScreenStreak::fragment`] computes them (up to rounding: a product by 1/L
/// for the division by L). Far to near order is the caller's.
///
/// On a steep streak each row visits a window of the same width around the axis, so the
/// loops have fixed trip counts and the coverage no branch: the branches of a data-dependent
/// span mispredict on nearly every row of a thin streak.
#[inline]
pub fn for_each_fragment(
    s: &ScreenStreak,
    y0: usize,
    rows: usize,
    w: usize,
    f: impl FnMut(usize, f32, f32),
) {
    for_each_fragment_in(s, y0, rows, w, 0..w, f);
}

/// [`for_each_fragment`], the shallow streaks' rows walked only within the columns `cols`
/// (steep streaks' windows are a few pixels: the caller filters those by column).
pub fn for_each_fragment_in(
    s: &ScreenStreak,
    y0: usize,
    rows: usize,
    w: usize,
    cols: std::ops::Range<usize>,
    mut f: impl FnMut(usize, f32, f32),
) {
    if s.max.y <= idx_f32(y0)
        || s.min.y >= idx_f32(y0 + rows)
        || s.max.x <= 0.0
        || s.min.x >= idx_f32(w)
    {
        return;
    }
    let (ya, yb) = (
        floor_nonneg(s.min.y.max(idx_f32(y0))),
        ceil_nonneg(s.max.y.min(idx_f32(y0 + rows))),
    );
    let steep = s.half > 0.0;
    if steep {
        let (slope, half) = (s.slope, s.half);
        // A pixel is covered only if its centre lies strictly within `half` of the axis'
        // crossing: an open interval of 2·half holds at most ⌈2·half⌉ pixel centres, the first
        // at ⌊xc − half + ½⌋.
        let span = ceil_nonneg(2.0 * half).clamp(1, w);
        let rows_of = SteepRows {
            s,
            y0,
            w,
            slope,
            half,
        };
        // Thin (w < 1 px all along): the coverage across is w·(1 − d). The drawing paths walk
        // steep streaks with for_each_fragment_x4; this walk is their fallback and reference.
        if s.wa.max(s.wb) < 1.0 {
            rows_of.run::<true>(ya..yb, span, &mut f);
        } else {
            rows_of.run::<false>(ya..yb, span, &mut f);
        }
    } else {
        let (dx, dy) = (s.dir.x, s.dir.y);
        // Within the bounds and `cols`, and on each row within the window where the pixel
        // centre can be covered: −½ < along < len + ½ and across < reach (both linear in the
        // column; |dx| ≥ √¾ for a shallow streak), widened by a pixel for rounding. The other
        // pixels of the row have no coverage.
        let (bx0, bx1) = (
            s.min.x.max(0.0).max(idx_f32(cols.start)),
            s.max.x.min(idx_f32(w)).min(idx_f32(cols.end.min(w))),
        );
        if bx1 <= bx0 {
            return;
        }
        let reach = reach(s.wa, s.wb);
        for y in ya..yb {
            let qy = idx_f32(y) + 0.5 - s.a.y;
            // along = qy·dy + qx·dx and across = qx·dy − qy·dx, with qx = x + ½ − a.x
            let (l0, l1) = ((-0.5 - qy * dy) / dx, (s.len + 0.5 - qy * dy) / dx);
            let (mut lo, mut hi) = (l0.min(l1), l0.max(l1));
            if dy.abs() > 1e-3 {
                let (c0, c1) = ((qy * dx - reach) / dy, (qy * dx + reach) / dy);
                lo = lo.max(c0.min(c1));
                hi = hi.min(c0.max(c1));
            }
            let (lo, hi) = (
                (lo + s.a.x - 0.5 - 1.0).max(bx0),
                (hi + s.a.x - 0.5 + 1.0).min(bx1),
            );
            if lo.partial_cmp(&hi) != Some(std::cmp::Ordering::Less) {
                continue;
            }
            for x in floor_nonneg(lo)..ceil_nonneg(hi) {
                let qx = idx_f32(x) + 0.5 - s.a.x;
                let (a, inv_z) = s.coverage::<false>(qy * dy + qx * dx, (qx * dy - qy * dx).abs());
                f((y - y0) * w + x, a, inv_z);
            }
        }
    }
}

/// [`for_each_fragment`] four pixels at a time, within the columns `cols`: calls
/// `f(i, a, inv_z)` with `i` the band index of the first of four consecutive pixels of a row
/// and `a`, `inv_z` theirs, the same values lane for lane (a = 0 where the streak misses a
/// pixel or the pixel is outside `cols`; `f` must treat it as nothing). Every pixel in `cols`
/// the streak covers is in exactly one call; the four pixels may reach up to three columns
/// past `cols` (always within the row). For steep streaks in frames at
/// least a window wide, which are nearly all of them; returns false, having called nothing,
/// for the others (walk those with [`for_each_fragment`]).
#[inline]
pub fn for_each_fragment_x4(
    s: &ScreenStreak,
    y0: usize,
    rows: usize,
    w: usize,
    cols: std::ops::Range<usize>,
    mut f: impl FnMut(usize, Vec4, Vec4),
) -> bool {
    if s.half <= 0.0 {
        return false;
    }
    // Windows of ⌈2·half⌉ pixels (see for_each_fragment), in chunks of four.
    let chunks = ceil_nonneg(2.0 * s.half).max(1).div_ceil(4);
    if 4 * chunks > w {
        return false;
    }
    let cols = cols.start..cols.end.min(w);
    if s.max.y <= idx_f32(y0)
        || s.min.y >= idx_f32(y0 + rows)
        || s.max.x <= idx_f32(cols.start)
        || s.min.x >= idx_f32(cols.end)
    {
        return true;
    }
    let (ya, yb) = (
        floor_nonneg(s.min.y.max(idx_f32(y0))),
        ceil_nonneg(s.max.y.min(idx_f32(y0 + rows))),
    );
    let thin = s.wa.max(s.wb) < 1.0;
    let c = (idx_f32(cols.start), idx_f32(cols.end));
    match (thin, chunks) {
        (true, 1) => steep_x4::<true, 1>(s, ya..yb, y0, w, c, &mut f),
        (false, 1) => steep_x4::<false, 1>(s, ya..yb, y0, w, c, &mut f),
        (false, 2) => steep_x4::<false, 2>(s, ya..yb, y0, w, c, &mut f),
        (_, _) => steep_x4::<false, 0>(s, ya..yb, y0, w, c, &mut f),
    }
    true
}

/// The rows `ys` of a steep streak, `f` per chunk of four pixels of each row's window
/// (`CHUNKS` chunks; 0: as many as the window needs), lanes outside the columns
/// [`cols.0`, `cols.1`) zeroed. `THIN`: under a pixel wide all along.
#[inline(always)]
fn steep_x4<const THIN: bool, const CHUNKS: usize>(
    s: &ScreenStreak,
    ys: std::ops::Range<usize>,
    y0: usize,
    w: usize,
    cols: (f32, f32),
    f: &mut impl FnMut(usize, Vec4, Vec4),
) {
    let (c0, c1) = (Vec4::splat(cols.0), Vec4::splat(cols.1));
    let inside = |x: Vec4, a: Vec4| Vec4::select(x.cmpge(c0) & x.cmplt(c1), a, Vec4::ZERO);
    let chunks = if CHUNKS > 0 {
        CHUNKS
    } else {
        ceil_nonneg(2.0 * s.half).max(1).div_ceil(4)
    };
    let (dx, dy) = (s.dir.x, s.dir.y);
    let last = w - 4 * chunks;
    let lanes = Vec4::new(0.0, 1.0, 2.0, 3.0);
    let mut ys = ys;
    if CHUNKS == 1 {
        // Windows of up to four pixels (nearly every streak): four rows at a time, one per
        // lane. The rows' windows and coverages are computed side by side (a row alone is a
        // chain of dependent steps, float to integer and back, that leaves the core mostly
        // waiting), then transposed to four pixels per row.
        let (ax, ay) = (Vec4::splat(s.a.x), Vec4::splat(s.a.y));
        let lastf = idx_f32(last);
        while ys.len() >= 4 {
            let y = ys.start;
            let qy = Vec4::splat(idx_f32(y)) + lanes + Vec4::splat(0.5) - ay;
            let xc = ax + qy * s.slope;
            let x0 = (xc - Vec4::splat(s.half) + Vec4::splat(0.5))
                .max(Vec4::ZERO)
                .floor()
                .min(Vec4::splat(lastf));
            let qx0 = x0 + Vec4::splat(0.5) - ax;
            let (along0, across0) = (qy * dy + qx0 * dx, qx0 * dy - qy * dx);
            let mut cov = [Vec4::ZERO; 4];
            let mut inv = [Vec4::ZERO; 4];
            for j in 0..4 {
                let jf = idx_f32(j);
                (cov[j], inv[j]) = s.coverage_x4::<THIN>(
                    along0 + Vec4::splat(jf * dx),
                    (across0 + Vec4::splat(jf * dy)).abs(),
                );
            }
            // (pixel j, row l) → (row l, pixel j)
            let cov = glam::Mat4::from_cols(cov[0], cov[1], cov[2], cov[3]).transpose();
            let inv = glam::Mat4::from_cols(inv[0], inv[1], inv[2], inv[3]).transpose();
            // x0 holds whole numbers in [0, 2²³): adding 2²³ puts each in the low mantissa
            // bits, read without a float-to-integer conversion.
            let x0f = x0;
            let x0 = (x0 + Vec4::splat(8_388_608.0)).to_array();
            for l in 0..4 {
                let x = Vec4::splat(x0f[l]) + lanes;
                f(
                    (y + l - y0) * w + (x0[l].to_bits() - 0x4B00_0000) as usize,
                    inside(x, cov.col(l)),
                    inv.col(l),
                );
            }
            ys.start += 4;
        }
    }
    for y in ys {
        let qy = idx_f32(y) + 0.5 - s.a.y;
        let xc = s.a.x + qy * s.slope;
        let x0 = floor_nonneg((xc - s.half + 0.5).max(0.0)).min(last);
        let qx0 = idx_f32(x0) + 0.5 - s.a.x;
        let (along0, across0) = (qy * dy + qx0 * dx, qx0 * dy - qy * dx);
        let row = (y - y0) * w + x0;
        for c in 0..chunks {
            // j·dx and j·dy as the scalar walk forms them (same bits).
            let j = lanes + Vec4::splat(idx_f32(4 * c));
            let along = Vec4::splat(along0) + j * dx;
            let across = (Vec4::splat(across0) + j * dy).abs();
            let (a, inv_z) = s.coverage_x4::<THIN>(along, across);
            f(
                row + 4 * c,
                inside(Vec4::splat(idx_f32(x0 + 4 * c)) + lanes, a),
                inv_z,
            );
        }
    }
}

/// A steep streak's rows (see [`for_each_fragment`]).
struct SteepRows<'a> {
    s: &'a ScreenStreak,
    y0: usize,
    w: usize,
    slope: f32,
    half: f32,
}

impl SteepRows<'_> {
    /// Visits the window of `span` pixels on each row of `ys`; `THIN`: the streak is under a
    /// pixel wide all along.
    #[inline(always)]
    fn run<const THIN: bool>(
        &self,
        ys: std::ops::Range<usize>,
        span: usize,
        f: &mut impl FnMut(usize, f32, f32),
    ) {
        let s = self.s;
        let (dx, dy) = (s.dir.x, s.dir.y);
        for y in ys {
            let qy = idx_f32(y) + 0.5 - s.a.y;
            let xc = s.a.x + qy * self.slope;
            let x0 = floor_nonneg((xc - self.half + 0.5).max(0.0)).min(self.w - span);
            let qx0 = idx_f32(x0) + 0.5 - s.a.x;
            let (along0, across0) = (qy * dy + qx0 * dx, qx0 * dy - qy * dx);
            let row = (y - self.y0) * self.w + x0;
            for j in 0..span {
                let jf = idx_f32(j);
                let (a, inv_z) = s.coverage::<THIN>(along0 + jf * dx, (across0 + jf * dy).abs());
                f(row + j, a, inv_z);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::particles::Particle as Drop;
    use crate::particles::streak::screen_streak;
    use crate::scene::camera::Camera;
    use glam::Vec2;
    use glam::{Mat3, Vec3};

    #[test]
    fn the_windowed_walk_visits_every_covered_pixel_with_its_coverage() {
        // Against ScreenStreak::fragment at every pixel (the per-pixel definition rain.wgsl
        // mirrors): random drops near and far, thin and wide, steep and slanted, dots, and
        // streaks leaving the frame; walked in bands of 7 rows.
        use rand::{Rng, SeedableRng};
        let (w, h) = (64usize, 45usize);
        let cam = Camera::new(
            w as u32,
            h as u32,
            [40.0, 40.0, 32.0, 22.5],
            Vec3::ZERO,
            Mat3::IDENTITY,
        )
        .unwrap();
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(9);
        let mut checked = 0;
        for _ in 0..400 {
            let z: f32 = rng.random_range(0.1..6.0);
            let p = Vec3::new(
                rng.random_range(-1.0..1.0) * z,
                rng.random_range(-0.8..0.8) * z,
                -z,
            );
            let v = Vec3::new(
                rng.random_range(-6.0..6.0),
                rng.random_range(-9.0..1.0),
                rng.random_range(-3.0..3.0),
            );
            let d = Drop {
                position_m: p,
                velocity_m_s: v,
                diameter_m: rng.random_range(0.5e-3..6e-3),
                id: [0; 5],
            };
            let exposure = if rng.random_bool(0.1) {
                1e-5
            } else {
                1.0 / 30.0
            };
            let Some(s) = screen_streak(&cam, &d, exposure, Vec3::ZERO) else {
                continue;
            };
            let mut walked = vec![0.0f32; w * h];
            for y0 in (0..h).step_by(7) {
                let rows = 7.min(h - y0);
                for_each_fragment(&s, y0, rows, w, |i, a, inv_z| {
                    walked[y0 * w + i] += a;
                    if a > 0.0 {
                        let (_, z) = s
                            .fragment(Vec2::new((i % w) as f32 + 0.5, (y0 + i / w) as f32 + 0.5))
                            .unwrap_or((0.0, f32::NAN));
                        assert!(
                            (1.0 / inv_z - z).abs() <= 1e-4 * z,
                            "{} vs {z}",
                            1.0 / inv_z
                        );
                    }
                });
            }
            for (i, got) in walked.iter().enumerate() {
                let want = s
                    .fragment(Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5))
                    .map_or(0.0, |f| f.0);
                // rounding only (the walk steps from the streak's start): nothing missed, nothing extra
                assert!(
                    (got - want).abs() <= 2e-4 * s.alpha,
                    "pixel {i}: {got} vs {want} ({s:?})"
                );
            }
            checked += 1;
        }
        assert!(checked > 100, "{checked}");
    }

    #[test]
    fn the_four_wide_walk_visits_every_covered_pixel_of_its_columns_once() {
        // Against ScreenStreak::fragment at every pixel, walked in bands of 7 rows and tiles
        // of 13 columns (so windows cross tile edges and the frame's right edge): every pixel
        // gets its coverage from exactly one tile, lanes outside a tile carry a = 0.
        use rand::{Rng, SeedableRng};
        let (w, h) = (64usize, 45usize);
        let cam = Camera::new(
            w as u32,
            h as u32,
            [40.0, 40.0, 32.0, 22.5],
            Vec3::ZERO,
            Mat3::IDENTITY,
        )
        .unwrap();
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(11);
        let (mut checked, mut thin) = (0, 0);
        for _ in 0..600 {
            let z: f32 = rng.random_range(0.1..6.0);
            let p = Vec3::new(
                rng.random_range(-1.0..1.0) * z,
                rng.random_range(-0.8..0.8) * z,
                -z,
            );
            let v = Vec3::new(
                rng.random_range(-4.0..4.0),
                rng.random_range(-9.0..1.0),
                rng.random_range(-3.0..3.0),
            );
            let d = Drop {
                position_m: p,
                velocity_m_s: v,
                diameter_m: rng.random_range(0.5e-3..6e-3),
                id: [0; 5],
            };
            let Some(s) = screen_streak(&cam, &d, 1.0 / 30.0, Vec3::ZERO) else {
                continue;
            };
            let mut walked = vec![0.0f32; w * h];
            let mut all = true;
            for y0 in (0..h).step_by(7) {
                let rows = 7.min(h - y0);
                for c0 in (0..w).step_by(13) {
                    let cols = c0..(c0 + 13).min(w);
                    all &= for_each_fragment_x4(&s, y0, rows, w, cols.clone(), |i, a, inv_z| {
                        let (row, x) = (i / w, i % w);
                        assert!(row < rows && x + 4 <= w, "{i}");
                        for l in 0..4 {
                            if a[l] > 0.0 {
                                assert!(
                                    cols.contains(&(x + l)),
                                    "lane {l} at x = {} outside {cols:?}",
                                    x + l
                                );
                                let (_, z) = s
                                    .fragment(Vec2::new(
                                        (x + l) as f32 + 0.5,
                                        (y0 + row) as f32 + 0.5,
                                    ))
                                    .unwrap_or((0.0, f32::NAN));
                                assert!(
                                    (1.0 / inv_z[l] - z).abs() <= 1e-4 * z,
                                    "{} vs {z}",
                                    1.0 / inv_z[l]
                                );
                            }
                            walked[(y0 + row) * w + x + l] += a[l];
                        }
                    });
                }
            }
            if !all {
                continue; // not steep: the scalar walk's case
            }
            for (i, got) in walked.iter().enumerate() {
                let want = s
                    .fragment(Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5))
                    .map_or(0.0, |f| f.0);
                assert!(
                    (got - want).abs() <= 2e-4 * s.alpha,
                    "pixel {i}: {got} vs {want} ({s:?})"
                );
            }
            checked += 1;
            thin += usize::from(s.wa.max(s.wb) < 1.0);
        }
        assert!(checked > 200 && thin > 50, "{checked} {thin}");
    }
}
