//! How lying snow looks where it is thin: it lies in patches, and the surface beneath shows
//! between them.
//!
//! A dusting does not lie as an even grey film: the first millimetres catch on the ground's
//! roughness and lie in patches, white where they lie and the ground's own colour between, and
//! the patches join as the snow deepens. The share of a surface the snow covers at a mean
//! depth d is [`coverage`]: c(d) = 1 − (1 − d/[`COVER_FULL_M`])² below [`COVER_FULL_M`], 1 from
//! there (our choice: its slope at d = 0 is 1/cm, as the e-folding of 1 cm the frames used
//! before, and 2 cm hide the ground whole, as fresh snow over asphalt does).
//!
//! Where the patches lie is a smooth random field over the ground, uniform on [0, 1] by
//! construction: the wet surfaces' relief noise ([`crate::wet::puddles::relief_u`], three
//! octaves through its own tabulated distribution), here on a [`SNOW_PATCH_M`] lattice
//! (features of 10 cm down to 2.5 cm). A point is under snow where u < c(d), so over a surface
//! of one depth the snow covers the share c(d) of it (in expectation; a view holds a finite
//! number of patches). Far away, where a pixel spans many patches, the pixel takes their mean
//! share instead ([`drawn_share`]: a blend over footprints from [`SHARP_BELOW`] to
//! [`BLEND_FROM`] lattice cells), which keeps the expectation c(d) at every distance and a
//! distant street from aliasing. The patches are the same in every frame and process (no
//! seed), so a cover that deepens fills in around the patches it had.

use crate::wet::puddles::{RELIEF_SCALE_M, relief_u};
use glam::Vec3;

/// The mean depth of snow from which it hides the surface beneath whole, m.
pub const COVER_FULL_M: f32 = 0.02;

/// The lattice of the patches' largest features, m.
pub const SNOW_PATCH_M: f32 = 0.1;

/// A pixel whose footprint is at most this share of [`SNOW_PATCH_M`] is drawn sharp (snow or
/// not), …
pub const SHARP_BELOW: f32 = 0.1;
/// … and from this share on as the patches' mean share, c(d); linear between.
pub const BLEND_FROM: f32 = 0.5;

/// The patches' offset in the relief noise's lattice units (away from the puddles' own).
pub const PATCH_OFFSET: f32 = 517.25;

/// The share of a surface `depth_m` of snow covers: 1 − (1 − d/[`COVER_FULL_M`])² (0 for no
/// snow, 1 from [`COVER_FULL_M`] on).
#[inline]
pub fn coverage(depth_m: f32) -> f32 {
    if depth_m <= 0.0 {
        0.0
    } else if depth_m >= COVER_FULL_M {
        1.0
    } else {
        let x = 1.0 - depth_m / COVER_FULL_M;
        1.0 - x * x
    }
}

/// The patches' field at the ground point (x, z), m: uniform on [0, 1].
#[inline]
pub fn patch_u(x: f32, z: f32) -> f32 {
    let k = RELIEF_SCALE_M / SNOW_PATCH_M;
    relief_u(x * k + PATCH_OFFSET, z * k - PATCH_OFFSET)
}

/// The side of a pixel's footprint on a surface, m: at distance `t` along the unnormalised
/// ray `d` (depth along the optical axis for a camera's rays), through a focal length of
/// `f_px` pixels, on a face of unit normal `n` (the geometric mean of its two sides: the
/// grazing side stretched by 1/|n·d̂|, at most 20×).
#[inline]
pub fn footprint_m(t: f32, d: Vec3, n: Vec3, f_px: f32) -> f32 {
    let len = d.length();
    let across = t * len / f_px;
    let cos = (n.dot(d) / len).abs().max(0.0025);
    across / cos.sqrt()
}

/// The share of a pixel at the ground point (x, z) that snow of coverage `c` covers, for a
/// pixel footprint of `footprint_m`: 1 or 0 by the patches where the footprint is small, c
/// where it spans many of them.
#[inline]
pub fn drawn_share(x: f32, z: f32, c: f32, footprint_m: f32) -> f32 {
    if c <= 0.0 || c >= 1.0 {
        return c.clamp(0.0, 1.0);
    }
    let f =
        ((footprint_m / SNOW_PATCH_M - SHARP_BELOW) / (BLEND_FROM - SHARP_BELOW)).clamp(0.0, 1.0);
    if f >= 1.0 {
        return c;
    }
    let sharp = if patch_u(x, z) < c { 1.0 } else { 0.0 };
    sharp + (c - sharp) * f
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coverage_starts_at_one_per_cm_and_is_whole_from_two_cm() {
        assert_eq!(coverage(0.0), 0.0);
        assert_eq!(coverage(-1.0), 0.0);
        assert_eq!(coverage(COVER_FULL_M), 1.0);
        assert_eq!(coverage(0.5), 1.0);
        // Slope at 0: 2 / 2 cm = 1 per cm.
        let h = 1e-5;
        assert!(((coverage(h) / h) - 100.0).abs() < 0.1);
        // Monotonic, continuous at 2 cm.
        let mut last = 0.0;
        for k in 1..=400 {
            let c = coverage(k as f32 * 1e-4);
            assert!(c >= last);
            last = c;
        }
        assert!((coverage(0.0199999) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn the_patches_cover_the_share_the_depth_gives() {
        // 250 000 points over a 50 m square (62 500 of the patches' largest lattice cells):
        // the share under snow is c within 1 % for each c, sharp or half blended.
        let side = 500;
        for c in [0.1f32, 0.3, 0.5, 0.8, 0.95] {
            let (mut sharp, mut half) = (0.0f64, 0.0f64);
            for k in 0..side * side {
                let (x, z) = (
                    0.1013 * (k % side) as f32 - 20.0,
                    0.0987 * (k / side) as f32 + 3.0,
                );
                sharp += f64::from(drawn_share(x, z, c, 0.0));
                half += f64::from(drawn_share(x, z, c, 0.06));
            }
            let n = (side * side) as f64;
            assert!(
                (sharp / n - f64::from(c)).abs() < 0.01,
                "{c}: {}",
                sharp / n
            );
            assert!((half / n - f64::from(c)).abs() < 0.01, "{c}: {}", half / n);
        }
        // Far away, the mean share exactly; none and whole are exact at any footprint.
        assert_eq!(drawn_share(3.0, 4.0, 0.37, 1.0), 0.37);
        for fp in [0.0, 0.05, 1.0] {
            assert_eq!(drawn_share(3.0, 4.0, 0.0, fp), 0.0);
            assert_eq!(drawn_share(3.0, 4.0, 1.0, fp), 1.0);
        }
    }

    #[test]
    fn near_pixels_are_snow_or_ground_in_patches_of_centimetres() {
        // Sharp: every point 0 or 1, and a point's neighbours 1 cm away agree almost always
        // (the field is smooth), those 1 m away independently (share of agreement c² + (1-c)²).
        let c = 0.5;
        let (mut near, mut far, n) = (0, 0, 40_000);
        for k in 0..n {
            let (x, z) = (0.731 * (k % 200) as f32, 0.677 * (k / 200) as f32);
            let a = drawn_share(x, z, c, 0.0);
            assert!(a == 0.0 || a == 1.0);
            near += usize::from(a == drawn_share(x + 0.01, z, c, 0.0));
            far += usize::from(a == drawn_share(x + 1.0, z + 0.5, c, 0.0));
        }
        assert!(near as f64 / n as f64 > 0.9, "{near}");
        assert!((far as f64 / n as f64 - 0.5).abs() < 0.03, "{far}");
    }

    #[test]
    fn a_footprint_is_the_pixels_side_at_its_distance_stretched_at_grazing() {
        let d = Vec3::new(0.0, 0.0, -1.0);
        // Facing the camera: t / f.
        assert!((footprint_m(10.0, d, Vec3::Z, 1000.0) - 0.01).abs() < 1e-7);
        // A ray along the axis at 2x length (off-axis) goes 2x as far per unit of depth.
        assert!((footprint_m(10.0, 2.0 * d, Vec3::Z, 1000.0) - 0.02).abs() < 1e-7);
        // At 60° from the normal, one side is stretched 2x: the geometric mean √2.
        let n = Vec3::new(0.0, (60f32).to_radians().sin(), (60f32).to_radians().cos());
        assert!((footprint_m(10.0, d, n, 1000.0) - 0.01 * 2f32.sqrt()).abs() < 1e-6);
    }
}
