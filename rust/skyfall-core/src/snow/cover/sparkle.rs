//! The sparkle of sunlit snow: the sun mirrored by single ice facets.
//!
//! Fresh snow is a heap of ice crystals whose faces are small flat mirrors. A facet sends the
//! sun's disc into the camera when its normal lies within half the sun's angular radius r of
//! the half vector h between the directions to the sun and to the camera, and the camera then
//! sees the sun's own radiance, L_sun = E_sun / (π r²), times ice's Fresnel reflectance, over
//! the facet: a point far brighter than the snow around it. Our documented choices:
//! - the facets tile the surface, each [`FACET_M`] across (fresh snow's grains have optical
//!   radii of 0.05–0.2 mm), with normals uniform over the hemisphere about the surface's;
//! - ice's refractive index [`ICE_INDEX`], 1.311 at 550 nm (Warren & Brandt, *Optical
//!   constants of ice from the ultraviolet to the microwave: a revised compilation*, JGR 2008);
//! - the sun's angular radius [`SUN_RADIUS_RAD`], 0.2666°.
//!
//! So a pixel whose footprint on the snow has area A holds N = (A/FACET_M²)·r²/8 glinting
//! facets on average ([`glint_count`]; π(r/2)² of the hemisphere's 2π), each adding
//! R(h·v)·FACET_M²·(h·v) / (r²·A·(n·v)) to the pixel's radiance per unit of the sun's
//! illuminance (radiance in units of E/π, illuminance in units of E). Their number is Poisson:
//! a pixel is drawn with a glint with probability 1 − e^(−N) (a hash of its point on a
//! 0.5 mm lattice: the same glints in every frame of a still camera, twinkling as it moves),
//! carrying N/(1 − e^(−N)) of them, so that its expectation, R(h·v)·(h·v)/(8(n·v)) per unit
//! of the sun's illuminance ([`sparkle_mean`]), holds at every distance. That mean is about
//! 1 % of the sunlit snow's Lambertian light (more at grazing views, where ice reflects more):
//! the sparkle changes how snow looks near the camera (about 0.7 % of its pixels at centimetre
//! footprints, each brighter than the snow by about half under a sun 30° up) and hardly its
//! brightness; far away a pixel holds many dim glints, their mean.

use crate::wet::optics::fresnel;
use crate::wet::puddles::{cell_hash, unit};
use glam::Vec3;

/// The side of the ice facets that glint, m.
pub const FACET_M: f32 = 2.0e-4;

/// Ice's refractive index at 550 nm.
pub const ICE_INDEX: f32 = 1.311;

/// The sun's angular radius, rad (0.2666°).
pub const SUN_RADIUS_RAD: f32 = 4.653e-3;

/// The lattice a pixel's glint is drawn on, m.
pub const GLINT_CELL_M: f32 = 5.0e-4;

/// Fresnel's reflectance of unpolarised light on ice at an angle of incidence of cosine `c`
/// ([`fresnel`], the wet surfaces' own, at [`ICE_INDEX`]).
#[inline]
pub fn ice_fresnel(c: f32) -> f32 {
    fresnel(f64::from(c), f64::from(ICE_INDEX)) as f32
}

/// The mean number of facets glinting on a footprint of `area_m2`.
#[inline]
pub fn glint_count(area_m2: f32) -> f32 {
    area_m2 / (FACET_M * FACET_M) * (SUN_RADIUS_RAD * SUN_RADIUS_RAD / 8.0)
}

/// The half vector of the unit directions to the sun `l` and to the camera `v`, with h·n, h·v
/// and n·v, or None where the sun or the camera is behind the face `n` (or h is).
#[inline]
fn geometry(n: Vec3, v: Vec3, l: Vec3) -> Option<(f32, f32)> {
    let (nv, nl) = (n.dot(v), n.dot(l));
    if nv <= 0.0 || nl <= 0.0 {
        return None;
    }
    let h = (v + l).normalize();
    Some((h.dot(v).clamp(0.0, 1.0), nv))
}

/// The sparkle's expectation on a face of normal `n`, seen along `v` (unit, towards the
/// camera) under the sun along `l`: R(h·v)·(h·v)/(8(n·v)) (radiance over E/π per unit of the
/// sun's normal illuminance over E).
pub fn sparkle_mean(n: Vec3, v: Vec3, l: Vec3) -> f32 {
    geometry(n, v, l).map_or(0.0, |(hv, nv)| ice_fresnel(hv) * hv / (8.0 * nv))
}

/// The sparkle a pixel adds at the point `p` of a face of normal `n` seen along `to_camera`
/// (towards the camera, any length) under the sun along `l`, on a footprint of side
/// `footprint_m` (its area that squared): 0, or N/(1 − e^(−N)) glints with probability
/// 1 − e^(−N) (see the module). Radiance over E/π per unit of the sun's normal illuminance
/// over E. Most pixels draw none and cost a hash (1 − e^(−N) ≤ N).
pub fn sparkle(p: Vec3, n: Vec3, to_camera: Vec3, l: Vec3, footprint_m: f32) -> f32 {
    let area = footprint_m * footprint_m;
    let count = glint_count(area);
    if count <= 0.0 || !count.is_finite() {
        return 0.0;
    }
    let u = unit(cell_hash(p, GLINT_CELL_M, 0x51a7));
    if u >= count {
        return 0.0;
    }
    let hit = 1.0 - (-count).exp();
    if u >= hit {
        return 0.0;
    }
    let Some((hv, nv)) = geometry(n, to_camera.normalize(), l) else {
        return 0.0;
    };
    let one =
        ice_fresnel(hv) * FACET_M * FACET_M * hv / (SUN_RADIUS_RAD * SUN_RADIUS_RAD * area * nv);
    one * count / hit
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ice_reflects_two_percent_at_normal_incidence_and_all_at_grazing() {
        // ((n - 1) / (n + 1))^2 = 0.01801 for n = 1.311; 1 at grazing; Brewster's angle
        // (atan 1.311 = 52.67°): the p-polarised half vanishes, R = rs² / 2.
        let r0 = ((ICE_INDEX - 1.0) / (ICE_INDEX + 1.0)).powi(2);
        assert!((ice_fresnel(1.0) - r0).abs() < 1e-7);
        assert!((ice_fresnel(0.0) - 1.0).abs() < 1e-6);
        let b = ICE_INDEX.atan();
        let (ci, si) = (b.cos(), b.sin());
        let ct = (1.0 - (si / ICE_INDEX).powi(2)).sqrt();
        let rs = (ci - ICE_INDEX * ct) / (ci + ICE_INDEX * ct);
        assert!((ice_fresnel(ci) - 0.5 * rs * rs).abs() < 1e-6);
    }

    #[test]
    fn the_glints_number_and_mean_are_the_facets_expectation() {
        // Level snow under a sun 30° up, seen from 45°: over 400 000 points the share of
        // pixels with a glint is 1 - e^(-N) and the mean sparkle is R(h·v)(h·v)/(8 n·v), for
        // footprints from 1 cm (N = 0.007: a glint in 0.7 % of pixels) to 10 cm (N = 0.68).
        let n = Vec3::Y;
        let l = Vec3::new(0.0, 30f32.to_radians().sin(), 30f32.to_radians().cos());
        let v = Vec3::new(
            std::f32::consts::FRAC_1_SQRT_2,
            std::f32::consts::FRAC_1_SQRT_2,
            0.0,
        );
        let want = sparkle_mean(n, v, l);
        assert!(want > 0.0);
        for fp in [0.01f32, 0.03, 0.1] {
            let count = glint_count(fp * fp);
            let (mut lit, mut sum, side) = (0u32, 0.0f64, 632);
            for k in 0..side * side {
                let p = Vec3::new(0.0137 * (k % side) as f32, 0.0, 0.0131 * (k / side) as f32);
                let s = sparkle(p, n, v, l, fp);
                lit += u32::from(s > 0.0);
                sum += f64::from(s);
            }
            let points = (side * side) as f64;
            let share = f64::from(lit) / points;
            let expect = 1.0 - (-f64::from(count)).exp();
            // Binomial: 4 standard deviations.
            let sd = (expect * (1.0 - expect) / points).sqrt();
            assert!(
                (share - expect).abs() < 4.0 * sd,
                "{fp}: {share} vs {expect}"
            );
            let mean = sum / points;
            let rel = (mean / f64::from(want) - 1.0).abs();
            assert!(
                rel < 4.0 * ((1.0 - expect) / (expect * points)).sqrt(),
                "{fp}: {mean} vs {want}"
            );
        }
    }

    #[test]
    fn no_sparkle_facing_away_from_the_sun_or_the_camera() {
        let p = Vec3::new(1.0, 0.0, 2.0);
        let up = Vec3::Y;
        let below = Vec3::new(0.0, -0.5, 0.866);
        let v = Vec3::new(0.0, 0.6, 0.8);
        assert_eq!(sparkle(p, up, v, below, 0.05), 0.0);
        assert_eq!(sparkle(p, up, below, v, 0.05), 0.0);
        assert_eq!(sparkle_mean(up, v, below), 0.0);
    }
}
