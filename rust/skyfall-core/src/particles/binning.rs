//! Tile binning: which streaks can touch each tile of pixels, in list (far to near) order, so
//! that a tile walks only its own. Shared by both CPU outputs and the GPU pass.

use super::streak::ScreenStreak;
use crate::error::{Error, Result, try_filled};

/// Per row of `tile_w` × `tile_h` tiles that a streak may touch, `f(row, first column, end
/// column)` (end-exclusive), rows in order: its bounding box's columns when the box is a single
/// column of tiles, else per row the columns it can reach there (see
/// [`ScreenStreak::columns_in_rows`]: a slanted streak meets far fewer tiles than its box).
#[inline]
fn tile_spans(
    s: &ScreenStreak,
    width: u32,
    height: u32,
    tile_w: u32,
    tile_h: u32,
    mut f: impl FnMut(u32, u32, u32),
) {
    let (x0, x1, y0, y1) = s.pixel_bounds(width, height);
    let (i0, i1) = (x0 / tile_w, x1.div_ceil(tile_w));
    if i1 <= i0 + 1 {
        for j in y0 / tile_h..y1.div_ceil(tile_h) {
            f(j, i0, i1);
        }
        return;
    }
    for j in y0 / tile_h..y1.div_ceil(tile_h) {
        let rows = (j * tile_h).max(y0)..((j + 1) * tile_h).min(y1);
        let (c0, c1) = s.columns_in_rows(rows, (x0, x1), width);
        if c1 > c0 {
            f(j, c0 / tile_w, c1.div_ceil(tile_w));
        }
    }
}

/// Streak indices per `tile_w` × `tile_h` pixel tile (row-major tiles), in list order:
/// (offsets, indices) with the tile t's streaks at `indices[offsets[t]..offsets[t + 1]]`.
/// The two halves of the list are binned in parallel and joined tile by tile. The lists are
/// reserved fallibly ([`Error::OutOfMemory`]: heavy rain in a large frame lists tens of
/// millions of entries).
pub fn bin_by_tiles(
    streaks: &[ScreenStreak],
    width: u32,
    height: u32,
    tile_w: u32,
    tile_h: u32,
) -> Result<(Vec<u32>, Vec<u32>)> {
    let tx = width.div_ceil(tile_w);
    let tiles = (tx * height.div_ceil(tile_h)) as usize;
    let half = streaks.len() / 2;
    let bin = |first: usize, part: &[ScreenStreak]| {
        let mut counts = try_filled("the tile lists' offsets", tiles + 1, 0u32)?;
        for s in part {
            tile_spans(s, width, height, tile_w, tile_h, |j, i0, i1| {
                for i in i0..i1 {
                    counts[(j * tx + i) as usize + 1] += 1;
                }
            });
        }
        for t in 1..counts.len() {
            counts[t] += counts[t - 1];
        }
        let mut fill = counts.clone();
        let mut indices = try_filled("the tile lists", counts[tiles] as usize, 0u32)?;
        for (k, s) in part.iter().enumerate() {
            tile_spans(s, width, height, tile_w, tile_h, |j, i0, i1| {
                for i in i0..i1 {
                    let t = (j * tx + i) as usize;
                    indices[fill[t] as usize] = (first + k) as u32;
                    fill[t] += 1;
                }
            });
        }
        Ok::<_, Error>((counts, indices))
    };
    let (a, b) = rayon::join(|| bin(0, &streaks[..half]), || bin(half, &streaks[half..]));
    let ((oa, ia), (ob, ib)) = (a?, b?);
    // Tile t: the first half's streaks, then the second's (list order).
    let mut offsets = Vec::new();
    offsets
        .try_reserve_exact(tiles + 1)
        .map_err(|_| Error::out_of_memory::<u32>("the tile lists' offsets", tiles + 1))?;
    let mut indices = Vec::new();
    indices
        .try_reserve_exact(ia.len() + ib.len())
        .map_err(|_| Error::out_of_memory::<u32>("the tile lists", ia.len() + ib.len()))?;
    offsets.push(0u32);
    for t in 0..tiles {
        indices.extend_from_slice(&ia[oa[t] as usize..oa[t + 1] as usize]);
        indices.extend_from_slice(&ib[ob[t] as usize..ob[t + 1] as usize]);
        offsets.push(indices.len() as u32);
    }
    Ok((offsets, indices))
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
    fn binning_lists_each_tiles_streaks_in_order() {
        // Per tile, in list order (the halves are binned in parallel and joined): every streak
        // that covers a pixel of the tile, and only streaks whose pixel bounds meet it. Slanted
        // streaks are listed in far fewer tiles than their bounds meet.
        use rand::{Rng, SeedableRng};
        let (w, h) = (200u32, 90u32);
        let cam = Camera::new(w, h, [80.0, 80.0, 100.0, 45.0], Vec3::ZERO, Mat3::IDENTITY).unwrap();
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(8);
        let streaks: Vec<ScreenStreak> = (0..301)
            .filter_map(|_| {
                let z: f32 = rng.random_range(0.2..6.0);
                let p = Vec3::new(
                    rng.random_range(-1.5..1.5) * z,
                    rng.random_range(-0.8..0.8) * z,
                    -z,
                );
                let v = Vec3::new(
                    rng.random_range(-12.0..12.0),
                    rng.random_range(-9.0..1.0),
                    0.0,
                );
                let d: f32 = rng.random_range(0.5e-3..6e-3);
                screen_streak(
                    &cam,
                    &Drop {
                        position_m: p,
                        velocity_m_s: v,
                        diameter_m: d,
                        id: [0; 5],
                    },
                    1.0 / 30.0,
                    Vec3::ZERO,
                )
            })
            .collect();
        // the tiles each streak covers, pixel by pixel
        let covered: Vec<Vec<(u32, u32)>> = streaks
            .iter()
            .map(|s| {
                let mut px = Vec::new();
                for y in 0..h {
                    for x in 0..w {
                        if s.fragment(Vec2::new(x as f32 + 0.5, y as f32 + 0.5))
                            .is_some()
                        {
                            px.push((x, y));
                        }
                    }
                }
                px
            })
            .collect();
        for (tw, th) in [(16, 16), (128, 16), (200, 7), (2, 4)] {
            let (offsets, indices) = bin_by_tiles(&streaks, w, h, tw, th).unwrap();
            let tx = w.div_ceil(tw);
            let mut boxed = 0usize;
            for t in 0..(tx * h.div_ceil(th)) {
                let (x, y) = ((t % tx) * tw, (t / tx) * th);
                let list = &indices[offsets[t as usize] as usize..offsets[t as usize + 1] as usize];
                assert!(
                    list.windows(2).all(|p| p[0] < p[1]),
                    "tile {t} out of order"
                );
                let meets = |k: usize| {
                    let (x0, x1, y0, y1) = streaks[k].pixel_bounds(w, h);
                    x0 < x + tw && x1 > x && y0 < y + th && y1 > y
                };
                boxed += (0..streaks.len()).filter(|&k| meets(k)).count();
                assert!(list.iter().all(|&k| meets(k as usize)), "tile {t}");
                for (k, px) in covered.iter().enumerate() {
                    if px
                        .iter()
                        .any(|&(px, py)| px >= x && px < x + tw && py >= y && py < y + th)
                    {
                        assert!(
                            list.contains(&(k as u32)),
                            "tile {t} ({tw}x{th}) misses streak {k}"
                        );
                    }
                }
            }
            if (tw, th) == (2, 4) {
                // (2096 against 4240 when written)
                assert!(
                    (indices.len() as f64) < 0.6 * boxed as f64,
                    "{} entries, bounds {boxed}",
                    indices.len()
                );
            }
        }
    }
}
