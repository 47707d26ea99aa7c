//! World-anchored voxels: the world is cut into 1 m voxels at integer coordinates, each with
//! its own seeded generator, so particles are the same for any camera, frame or process;
//! particles wrap inside their voxel as they move, so every voxel is statistically the same at
//! all times. Which voxels are near the camera and can draw into its frame, visited column by
//! column in parallel in a fixed order.

use crate::scene::camera::Camera;
use crate::seed::derive;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// A particle anchored in the world, kept when within the region's radius.
pub trait Anchored {
    /// Its position relative to the region's centre, m.
    fn position_m(&self) -> Vec3;
}

/// The seed of a voxel's generator: the user's `seed` mixed with the voxel's coordinates, then
/// `keys` (what the voxel's stream is for: a diameter bin, a texture, ...).
pub fn voxel_seed(seed: u64, voxel: [i64; 3], keys: &[u64]) -> u64 {
    let mut all = [0u64; 8];
    let n = 3 + keys.len().min(5);
    all[..3].copy_from_slice(&[voxel[0] as u64, voxel[1] as u64, voxel[2] as u64]);
    all[3..n].copy_from_slice(&keys[..n - 3]);
    derive(seed, &all[..n])
}

/// x − ⌊x⌋ (in [0, 1] for |x| < 2⁶³: positions and scrolls are metres).
#[inline]
pub fn wrap(x: f64) -> f64 {
    x - floor(x)
}

/// ⌊x⌋ for |x| < 2⁶³ by truncation, the same bits as `f64::floor` (−0 included), which is a
/// libm call on targets without a rounding instruction.
#[inline]
pub fn floor(x: f64) -> f64 {
    let t = (x as i64 as f64).copysign(x);
    if t > x { t - 1.0 } else { t }
}

/// Whether a voxel (by its centre relative to the camera) meets `cam`'s view frustum once its box is grown by
/// `margin_m`: box against plane, the box is outside a plane when its corner farthest inside
/// is outside.
pub fn in_view(cam: &Camera, margin: f32) -> impl Fn(Vec3) -> bool + Sync + use<> {
    let (w, h) = (cam.width as f32, cam.height as f32);
    // Inward side planes of the frustum in camera space (the camera looks along −z), turned
    // into the world.
    let planes = [
        Vec3::new(1.0, 0.0, -cam.cx / cam.fx),
        Vec3::new(-1.0, 0.0, -(w - cam.cx) / cam.fx),
        Vec3::new(0.0, -1.0, -cam.cy / cam.fy),
        Vec3::new(0.0, 1.0, -(h - cam.cy) / cam.fy),
        Vec3::new(0.0, 0.0, -1.0),
    ]
    .map(|n| cam.rotation * n.normalize());
    move |c: Vec3| {
        planes
            .iter()
            .all(|n| n.dot(c) + 0.5 * n.abs().element_sum() >= -margin)
    }
}

/// Runs `fill` for every voxel within `radius_m` of `center_m` that `keep_voxel` accepts
/// (by its centre relative to `center_m`), columns in parallel, and keeps the particles within `radius_m`, in a
/// deterministic order. `fill` pushes a voxel's particles after reserving room for them with
/// `try_reserve`, and returns false where that failed; the whole list is reserved fallibly
/// too: either is [`crate::Error::OutOfMemory`], naming `what`.
pub fn voxels_where<P: Anchored + Send + Clone>(
    what: &str,
    center_m: DVec3,
    radius_m: f64,
    ground: bool,
    keep_voxel: impl Fn(Vec3) -> bool + Sync,
    fill: impl Fn([i64; 3], &mut Vec<P>) -> bool + Sync,
) -> crate::error::Result<Vec<P>> {
    // The first refusal ends the column and is reported.
    let columns = map_voxel_columns(center_m, radius_m, ground, keep_voxel, |voxels| {
        let mut out = FallibleColumn {
            items: Vec::new(),
            refused: None,
        };
        for v in voxels {
            if !fill(v, &mut out.items) {
                out.refused = Some(out.items.capacity().max(1) * 2);
                break;
            }
        }
        out
    });
    if let Some(n) = columns.iter().find_map(|c| c.refused) {
        return Err(crate::error::Error::out_of_memory::<P>(what, n));
    }
    crate::error::try_concat(what, columns.into_iter().map(|c| c.items).collect())
}

/// A column's particles, and the length its list could not grow to (None: all made).
struct FallibleColumn<P> {
    items: Vec<P>,
    refused: Option<usize>,
}

impl<P> AsMut<Vec<P>> for FallibleColumn<P> {
    fn as_mut(&mut self) -> &mut Vec<P> {
        &mut self.items
    }
}

/// `per_column` of the voxels within `radius_m` of `center_m` that `keep_voxel` accepts
/// (by its centre relative to `center_m`), one call per column of constant x (voxels in y, then z order), columns in
/// parallel; the particles each call returns (positioned relative to `center_m`) are cut to
/// those within `radius_m`. The columns come
/// back in x order, so the result is the same in every run.
pub fn map_voxel_columns<P: Anchored, T: Send + AsMut<Vec<P>>>(
    center_m: DVec3,
    radius_m: f64,
    ground: bool,
    keep_voxel: impl Fn(Vec3) -> bool + Sync,
    per_column: impl Fn(&mut dyn Iterator<Item = [i64; 3]>) -> T + Sync,
) -> Vec<T> {
    let c = center_m;
    let r = radius_m;
    let lo = (c - DVec3::splat(r)).floor();
    let hi = (c + DVec3::splat(r)).floor();
    (lo.x as i64..=hi.x as i64)
        .into_par_iter()
        .map(|ix| {
            let mut voxels = (lo.y as i64..=hi.y as i64)
                .filter(|&iy| !(ground && iy < 0))
                .flat_map(|iy| (lo.z as i64..=hi.z as i64).map(move |iz| [ix, iy, iz]))
                .filter(|&[ix, iy, iz]| {
                    // nearest point of the voxel to the centre
                    let q = DVec3::new(
                        c.x.clamp(ix as f64, ix as f64 + 1.0),
                        c.y.clamp(iy as f64, iy as f64 + 1.0),
                        c.z.clamp(iz as f64, iz as f64 + 1.0),
                    );
                    q.distance(c) <= r
                        && keep_voxel(
                            (DVec3::new(ix as f64, iy as f64, iz as f64) + 0.5 - c).as_vec3(),
                        )
                });
            let mut out = per_column(&mut voxels);
            out.as_mut()
                .retain(|d| d.position_m().as_dvec3().length() <= r);
            out
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_is_x_minus_its_floor_bit_for_bit() {
        let xs = [
            0.0,
            -0.0,
            0.25,
            1.0,
            -1.0,
            -0.25,
            3.999_999_999,
            -2.5e-17,
            1e-300,
            7.3e9,
            -7.3e9,
            123.456,
            -123.456,
        ];
        for x in xs
            .into_iter()
            .chain((0..2000).map(|k| (k as f64 - 1000.0) * 0.013_7))
        {
            assert_eq!(wrap(x).to_bits(), (x - x.floor()).to_bits(), "{x}");
        }
    }

    #[test]
    fn floor_by_truncation_is_floor() {
        for x in [
            -3.5,
            -3.0,
            -0.0,
            0.0,
            -1e-300,
            1e-300,
            0.999_999,
            2.0,
            -2.000_001,
            9e15,
            -9e15,
            123_456.789,
        ] {
            assert_eq!(floor(x), x.floor(), "{x}");
        }
    }

    #[test]
    fn a_voxel_seed_is_the_derived_key_of_its_coordinates_then_keys() {
        let v = [3, -2, 7];
        let want = derive(5, &[3, (-2i64) as u64, 7, 1, 2]);
        assert_eq!(voxel_seed(5, v, &[1, 2]), want);
        assert_ne!(voxel_seed(5, v, &[2, 1]), want);
    }
}
