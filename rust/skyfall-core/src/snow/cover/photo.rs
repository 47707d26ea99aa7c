//! A photo's snow per pixel: the depth of the cover on each pixel's surface, from the depth
//! map through the camera, and the depth map's noise cleaned from it (drawn by
//! [`super::render::SnowRender::photo_row`]).

use super::SnowCover;
use super::heightfield::{PHOTO_RANGE_M, photo_points};
use crate::error::{Result, try_filled};
use crate::scene::camera::Camera;
use glam::Vec3;

/// A photo pixel's normal is taken from the depth map's points this share of the image's
/// width to either side (4 px at 741 px).
const NORMAL_SPAN_FRACTION: f32 = 1.0 / 185.0;

/// Snow on photo surfaces whose normal's y is at least this (60° from level).
const UP_MIN: f32 = 0.5;
/// … and fully from this (about 37°).
const UP_FULL: f32 = 0.8;

/// The depth of snow on each pixel's surface of a photo, m: its cell's depth where the pixel's
/// point lies on the cell's top surface (within two cells' width and 1 % of its distance: the
/// depth map's noise) and its normal (from the
/// depth map through the camera, [`NORMAL_SPAN_FRACTION`] of the width across) faces up, weighted from 0 at 60° from level to 1 at 37°;
/// pixels beyond [`PHOTO_RANGE_M`] get the open ground's cover, as level ground in the open.
/// Then the depth map's noise is cleaned away ([`clean_speckles`]: holes in a covered surface
/// filled, lone specks removed).
pub fn photo_depth_m(cover: &SnowCover, cam: &Camera, depth_m: &[f32]) -> Result<Vec<f32>> {
    let g = cover.field.grid;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let points = photo_points(cam, depth_m);
    let open = cover.open_depth_m as f32;
    let eye = cam.eye();
    let world = |x: usize, y: usize| -> Option<Vec3> {
        let d = depth_m[y * w + x];
        (d.is_finite() && d > 0.0).then(|| eye + cam.ray_direction(x as u32, y as u32) * d)
    };
    // Neighbours NORMAL_SPAN_FRACTION of the width apart: a depth map's steps (quantised
    // disparities, sensor noise) would turn a floor into a staircase of walls.
    let k = ((w as f32 * NORMAL_SPAN_FRACTION).round() as usize).max(1);
    let v = cover.fall_velocity_m_s;
    let up_wind = -Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32).normalize_or(Vec3::NEG_Y);
    let mut out = try_filled("the snow cover's depth per pixel", w * h, 0.0f32)?;
    for y in 0..h {
        for x in 0..w {
            let Some(p) = world(x, y) else { continue };
            // The normal from the neighbours, each side the nearer in depth (edges of objects
            // would bend it).
            let pick = |a: Option<Vec3>, b: Option<Vec3>| match (a, b) {
                (Some(a), Some(b)) => {
                    if (a - p).length_squared() <= (b - p).length_squared() {
                        Some(a - p)
                    } else {
                        Some(p - b)
                    }
                }
                (Some(a), None) => Some(a - p),
                (None, Some(b)) => Some(p - b),
                (None, None) => None,
            };
            let dx = pick(
                (x + k < w).then(|| world(x + k, y)).flatten(),
                (x >= k).then(|| world(x - k, y)).flatten(),
            );
            let dy = pick(
                (y + k < h).then(|| world(x, y + k)).flatten(),
                (y >= k).then(|| world(x, y - k)).flatten(),
            );
            let (Some(dx), Some(dy)) = (dx, dy) else {
                continue;
            };
            let mut n = dx.cross(dy).normalize_or_zero();
            if n.dot(eye - p) < 0.0 {
                n = -n;
            }
            let up = ((n.y - UP_MIN) / (UP_FULL - UP_MIN)).clamp(0.0, 1.0);
            if up <= 0.0 {
                continue;
            }
            let d = match points[y * w + x] {
                Some(q) => match g.cell_of(q[0], q[2]) {
                    Some((i, k)) => {
                        let c = k * g.nx + i;
                        let b = cover.field.base_m[c];
                        // Within two cells and 1 % of the distance (a depth map's noise) of
                        // the cell's top.
                        let tol = 2.0 * g.spacing_m + 0.01 * f64::from(depth_m[y * w + x]);
                        if !b.is_nan() && q[1] >= b - tol {
                            cover.depth_m[c] as f32
                        } else if !sheltered(cam, depth_m, p, up_wind) {
                            // Below its cell's top (another surface seen over the same cell),
                            // yet open to the snow in the photo's own 2.5D view: level open
                            // ground's cover.
                            open
                        } else {
                            0.0
                        }
                    }
                    None => 0.0,
                },
                // Beyond the height field's range: level open ground.
                None => {
                    let (dxz, dzz) = (f64::from(p.x - eye.x), f64::from(p.z - eye.z));
                    if dxz * dxz + dzz * dzz > PHOTO_RANGE_M * PHOTO_RANGE_M {
                        open
                    } else {
                        0.0
                    }
                }
            };
            out[y * w + x] = d * up;
        }
    }
    clean_speckles(&out, depth_m, w, h)
}

/// The window of [`clean_speckles`], as a share of the image's width either side (2 px at 480, at
/// least 2).
const CLEAN_SPAN_FRACTION: f32 = 1.0 / 240.0;
/// Neighbours on the same surface as a pixel: depths within this share of its own.
const SAME_SURFACE: f32 = 0.02;
/// A pixel with snow keeps it when at least this share of its neighbours on its surface have
/// snow too.
const KEEP_MIN: f32 = 0.3;
/// A pixel without snow takes its neighbours' mean depth when more than this share of them
/// have snow.
const FILL_MIN: f32 = 0.7;

/// A depth map's noise tips single pixels' normals past the test for an upward surface: a
/// covered floor gets holes and a wall specks. Within a window of [`CLEAN_SPAN_FRACTION`] of the
/// width, among the neighbours on the pixel's own surface (depth within [`SAME_SURFACE`]):
/// a pixel with snow where fewer than [`KEEP_MIN`] of them have any loses it (a speck); a pixel
/// without snow where more than [`FILL_MIN`] of them have some takes their mean depth (a hole).
/// Where a floor meets a wall about half the neighbours have snow: the edge stays where it was.
pub(crate) fn clean_speckles(
    snow_m: &[f32],
    depth_m: &[f32],
    w: usize,
    h: usize,
) -> Result<Vec<f32>> {
    use rayon::prelude::*;
    let mut out = try_filled("the snow cover's depth per pixel", w * h, 0.0f32)?;
    let r = ((w as f32 * CLEAN_SPAN_FRACTION).round() as usize).max(2);
    out.par_chunks_mut(w.max(1))
        .enumerate()
        .for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                let c = y * w + x;
                let own = snow_m[c];
                *o = own;
                let d = depth_m[c];
                if !(d.is_finite() && d > 0.0) {
                    continue;
                }
                let (mut n, mut with, mut sum) = (0u32, 0u32, 0.0f32);
                for yy in y.saturating_sub(r)..(y + r + 1).min(h) {
                    for xx in x.saturating_sub(r)..(x + r + 1).min(w) {
                        let j = yy * w + xx;
                        // (NaN or infinite depths are on no surface.)
                        let same = (depth_m[j] - d).abs() <= SAME_SURFACE * d;
                        if j == c || !same {
                            continue;
                        }
                        n += 1;
                        if snow_m[j] > 0.0 {
                            with += 1;
                            sum += snow_m[j];
                        }
                    }
                }
                if n == 0 {
                    continue;
                }
                let share = with as f32 / n as f32;
                if own > 0.0 && share < KEEP_MIN {
                    *o = 0.0;
                } else if own <= 0.0 && share > FILL_MIN {
                    *o = sum / with as f32;
                }
            }
        });
    Ok(out)
}

/// How far above a photo's point [`sheltered`] looks for what covers it, m.
const SHELTER_REACH_M: f32 = 3.0;
/// Its steps, m.
const SHELTER_STEP_M: f32 = 0.02;
/// How far behind the depth map's surface a point counts as inside what the photo shows, m.
const SHELTER_THICKNESS_M: f32 = 0.3;

/// The 2.5D shadow test through a photo's depth map: whether the snow falling towards `p`
/// (from `up_wind`, the reverse of its fall) meets what the photo shows first: points up that
/// line, in steps, projected into the image, each hidden behind the depth map's surface by
/// less than [`SHELTER_THICKNESS_M`] (the surface is taken that thick) shelters `p`.
fn sheltered(cam: &Camera, depth_m: &[f32], p: Vec3, up_wind: Vec3) -> bool {
    let (w, h) = (cam.width as f32, cam.height as f32);
    let inv = cam.rotation.transpose();
    let eye = cam.eye();
    let steps = (SHELTER_REACH_M / SHELTER_STEP_M) as usize;
    for j in 1..=steps {
        let s = p + up_wind * (j as f32 * SHELTER_STEP_M);
        let c = inv * (s - eye);
        let z = -c.z;
        if z <= 0.0 {
            return false;
        }
        let u = cam.cx + cam.fx * c.x / z;
        let v = cam.cy - cam.fy * c.y / z;
        if !(u >= 0.0 && v >= 0.0 && u < w && v < h) {
            return false;
        }
        let d = depth_m[v as usize * cam.width as usize + u as usize];
        if d < z - SHELTER_STEP_M && z - d < SHELTER_THICKNESS_M {
            return true;
        }
    }
    false
}
