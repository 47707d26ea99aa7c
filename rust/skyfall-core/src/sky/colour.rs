//! The colour of a sky with a sun, and of its sun.
//!
//! The renderer's sky *luminance* is the CIE model's ([`super::cie`]), normalised to the
//! user's E ([`super::Sky`]); this module gives it a *colour* and leaves the luminance alone.
//!
//! - **The sky's colour.** Hosek & Wilkie, *An Analytic Model for Full Spectral Sky-Dome
//!   Radiance* (ACM TOG 31(4), 2012), in its RGB form (linear Rec. 709 / sRGB primaries), as
//!   the `hw-skymodel` crate ships its datasets and fits: 9 parameters per channel, made from
//!   the sun's elevation, the turbidity and the ground albedo ([`SkyColour::new`]). Along a
//!   direction the model's RGB divided by its own luminance (Rec. 709 weights, [`LUMA`]) is the
//!   sky's *chroma* there: its luminance is 1, so the CIE luminance times it is a colour of the
//!   CIE luminance. A blue zenith and an orange sky towards a low sun follow.
//! - **Which skies.** The overcast CIE skies (Yamamoto & Tadamura's, and the general types 1–5)
//!   stay neutral (chroma 1). The cloudless types 11–15 take the model's colour at a turbidity
//!   rising from clean air to a turbid one ([`sky_turbidity`]); the partly cloudy types 6–10
//!   take it at half saturation (about half of their light comes from white clouds: our own
//!   choice, not part of either model).
//! - **The sun's colour** ([`sun_colour`]): a 5778 K black body (the sun's effective
//!   temperature) through the air mass of Kasten & Young ([`super::sun::air_mass`]), Rayleigh's
//!   optical depth (Hansen & Travis 1974's fit) and the aerosols' (Ångström's law, exponent 1.3,
//!   β from the turbidity after Preetham, Shirley & Smits 1999), summed against the CIE 1931
//!   colour-matching functions every 10 nm, to Rec. 709 RGB of luminance 1. Ozone's
//!   absorption is left out.
//! - **The sky light's colour** ([`super::Sky::light_colour`]): the colour of the light the open
//!   sky gives a horizontal surface, which tints the whole ambient-light map (a vertical face
//!   sees more of the paler horizon: within a few per cent of this tint, not modelled).

use super::cie::SkyKind;
use glam::Vec3;

/// Rec. 709 luminance of linear RGB: Y = 0.2126 R + 0.7152 G + 0.0722 B (they sum to 1, so
/// the neutral chroma (1, 1, 1) has luminance 1).
pub const LUMA: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// The ground albedo the sky model is made with (a mean land surface).
pub const GROUND_ALBEDO: f32 = 0.2;

/// Hosek–Wilkie turbidity and saturation of a CIE general sky type: None for the overcast
/// types 1–5. Cloudless 11–15: 2.5 (white-blue with a distinct corona), 3 (the CIE standard
/// clear sky, the turbidity [`super::sun::CLEAR_TURBIDITY`] of the sun's illuminance), 4.5
/// (polluted), 5.5 (turbid, broad corona), 7 (white-blue turbid); partly cloudy 6–10: 4 at
/// saturation 0.5.
pub fn sky_turbidity(sky_type: u8) -> Option<(f32, f32)> {
    match sky_type {
        6..=10 => Some((4.0, 0.5)),
        11 => Some((2.5, 1.0)),
        12 => Some((3.0, 1.0)),
        13 => Some((4.5, 1.0)),
        14 => Some((5.5, 1.0)),
        15 => Some((7.0, 1.0)),
        _ => None,
    }
}

/// The colour of a sky with a sun: the Hosek–Wilkie RGB model's state for one sun.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkyColour {
    /// The model's 9 parameters A–I for R, then G, then B.
    pub params: [f32; 27],
    /// The model's radiance scale per channel.
    pub radiances: [f32; 3],
    /// Unit vector towards the sun (its elevation clamped to [0°, 90°] for the model).
    pub sun: Vec3,
    /// How much of the model's colour is kept: chroma = 1 + s·(model's chroma − 1).
    pub saturation: f32,
    /// The turbidity the model is made with.
    pub turbidity: f32,
}

impl SkyColour {
    /// The colour of `kind`, None for a neutral sky (the overcast ones).
    pub fn new(kind: SkyKind) -> Option<Self> {
        let SkyKind::General { sky_type, sun } = kind else {
            return None;
        };
        let (turbidity, saturation) = sky_turbidity(sky_type)?;
        let elevation = sun.y.clamp(0.0, 1.0).asin();
        let state = hw_skymodel::rgb::SkyState::new(&hw_skymodel::rgb::SkyParams {
            elevation,
            turbidity,
            albedo: [GROUND_ALBEDO; 3],
        })
        .ok()?;
        let (params, radiances) = state.raw();
        let horizontal = Vec3::new(sun.x, 0.0, sun.z).normalize_or(Vec3::NEG_Z);
        let (s, c) = elevation.sin_cos();
        Some(SkyColour {
            params,
            radiances,
            sun: horizontal * c + Vec3::Y * s,
            saturation,
            turbidity,
        })
    }

    /// The model's RGB radiance along unit `dir` (its own units; below the horizon, the
    /// horizon's): Hosek & Wilkie's eq. 9 per channel.
    #[inline]
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        let cos_theta = dir.y.max(0.0);
        let cos_gamma = dir.dot(self.sun).clamp(-1.0, 1.0);
        let gamma = cos_gamma.acos();
        let zenith = cos_theta.sqrt();
        let channel = |k: usize| {
            let p = &self.params[9 * k..9 * k + 9];
            let mie = (1.0 + cos_gamma * cos_gamma)
                / (1.0 + p[8] * p[8] - 2.0 * p[8] * cos_gamma).powf(1.5);
            let lhs = 1.0 + p[0] * (p[1] / (cos_theta + 0.01)).exp();
            let rhs = p[2]
                + p[3] * (p[4] * gamma).exp()
                + p[5] * cos_gamma * cos_gamma
                + p[6] * mie
                + p[7] * zenith;
            (self.radiances[k] * lhs * rhs).max(0.0)
        };
        Vec3::new(channel(0), channel(1), channel(2))
    }

    /// The sky's chroma along unit `dir`: linear RGB of luminance 1 ([`LUMA`]), the model's
    /// colour at this sky's saturation.
    #[inline]
    pub fn chroma(&self, dir: Vec3) -> Vec3 {
        chroma_of(self.radiance(dir), self.saturation)
    }
}

/// `rgb` scaled to luminance 1 and desaturated to `saturation` (neutral where it is black).
#[inline]
pub fn chroma_of(rgb: Vec3, saturation: f32) -> Vec3 {
    let y = LUMA.dot(rgb);
    if y > 0.0 && y.is_finite() {
        Vec3::ONE + (rgb / y - Vec3::ONE) * saturation
    } else {
        Vec3::ONE
    }
}

/// The sun's effective temperature, K: its disc's spectrum outside the atmosphere is taken as
/// a black body's.
pub const SUN_TEMPERATURE_K: f64 = 5778.0;

/// Linear Rec. 709 (sRGB primaries, D65 white) from CIE XYZ (IEC 61966-2-1).
const XYZ_TO_REC709: [[f64; 3]; 3] = [
    [3.240_454_2, -1.537_138_5, -0.498_531_4],
    [-0.969_266_0, 1.876_010_8, 0.041_556_0],
    [0.055_643_4, -0.204_025_9, 1.057_225_2],
];

/// The CIE 1931 2° standard observer's colour-matching functions x̄, ȳ, z̄ at 380, 390, …,
/// 780 nm (CIE 015:2018's table, as colour-science ships it).
#[rustfmt::skip]
pub const CIE_1931_10NM: [[f64; 3]; 41] = [
    [0.001368, 3.9e-05, 0.006450001], // 380 nm
    [0.004243, 0.00012, 0.02005001], // 390 nm
    [0.01431, 0.000396, 0.06785001], // 400 nm
    [0.04351, 0.00121, 0.2074], // 410 nm
    [0.13438, 0.004, 0.6456], // 420 nm
    [0.2839, 0.0116, 1.3856], // 430 nm
    [0.34828, 0.023, 1.74706], // 440 nm
    [0.3362, 0.038, 1.77211], // 450 nm
    [0.2908, 0.06, 1.6692], // 460 nm
    [0.19536, 0.09098, 1.28764], // 470 nm
    [0.09564, 0.13902, 0.8129501], // 480 nm
    [0.03201, 0.20802, 0.46518], // 490 nm
    [0.0049, 0.323, 0.272], // 500 nm
    [0.0093, 0.503, 0.1582], // 510 nm
    [0.06327, 0.71, 0.07824999], // 520 nm
    [0.1655, 0.862, 0.04216], // 530 nm
    [0.2904, 0.954, 0.0203], // 540 nm
    [0.4334499, 0.9949501, 0.008749999], // 550 nm
    [0.5945, 0.995, 0.0039], // 560 nm
    [0.7621, 0.952, 0.0021], // 570 nm
    [0.9163, 0.87, 0.001650001], // 580 nm
    [1.0263, 0.757, 0.0011], // 590 nm
    [1.0622, 0.631, 0.0008], // 600 nm
    [1.0026, 0.503, 0.00034], // 610 nm
    [0.8544499, 0.381, 0.00019], // 620 nm
    [0.6424, 0.265, 4.999999e-05], // 630 nm
    [0.4479, 0.175, 2e-05], // 640 nm
    [0.2835, 0.107, -1.905824e-21], // 650 nm
    [0.1649, 0.061, 0.0], // 660 nm
    [0.0874, 0.032, 0.0], // 670 nm
    [0.04677, 0.017, 0.0], // 680 nm
    [0.0227, 0.00821, 0.0], // 690 nm
    [0.01135916, 0.004102, 0.0], // 700 nm
    [0.005790346, 0.002091, 0.0], // 710 nm
    [0.002899327, 0.001047, 0.0], // 720 nm
    [0.001439971, 0.00052, 0.0], // 730 nm
    [0.0006900786, 0.0002492, 0.0], // 740 nm
    [0.0003323011, 0.00012, 0.0], // 750 nm
    [0.0001661505, 6e-05, 0.0], // 760 nm
    [8.307527e-05, 3e-05, 0.0], // 770 nm
    [4.150994e-05, 1.499e-05, 0.0], // 780 nm
];

/// Rayleigh's optical depth of the whole atmosphere at sea level, λ in µm (Hansen & Travis,
/// *Light scattering in planetary atmospheres*, 1974): 0.008569 λ⁻⁴ (1 + 0.0113 λ⁻² +
/// 0.00013 λ⁻⁴).
pub fn rayleigh_optical_depth(lambda_um: f64) -> f64 {
    let l2 = lambda_um.powi(-2);
    0.008569 * l2 * l2 * (1.0 + 0.0113 * l2 + 0.00013 * l2 * l2)
}

/// Ångström's turbidity coefficient β of a turbidity T (Preetham, Shirley & Smits 1999,
/// appendix: β = 0.04608 T − 0.04586), at least 0.
pub fn angstrom_beta(turbidity: f64) -> f64 {
    (0.04608 * turbidity - 0.04586).max(0.0)
}

/// The colour of the sun's direct light at `elevation_deg` through an atmosphere of
/// `turbidity`: linear Rec. 709 RGB of luminance 1 (a 10 nm sum over 380–780 nm).
pub fn sun_colour(elevation_deg: f64, turbidity: f64) -> Vec3 {
    let m = super::sun::air_mass(elevation_deg);
    let beta = angstrom_beta(turbidity);
    let c2 = 1.438_776_877e-2; // m·K, Planck's second radiation constant
    let mut xyz = [0.0f64; 3];
    for (i, cmfs) in CIE_1931_10NM.iter().enumerate() {
        let lambda_nm = 380.0 + 10.0 * i as f64;
        let lambda_m = lambda_nm * 1e-9;
        let planck = lambda_m.powi(-5) / ((c2 / (lambda_m * SUN_TEMPERATURE_K)).exp() - 1.0);
        let um = lambda_nm * 1e-3;
        let tau = rayleigh_optical_depth(um) + beta * um.powf(-1.3);
        let e = planck * (-m * tau).exp();
        for (acc, cmf) in xyz.iter_mut().zip(cmfs) {
            *acc += e * cmf;
        }
    }
    let rgb = XYZ_TO_REC709.map(|row| row[0] * xyz[0] + row[1] * xyz[1] + row[2] * xyz[2]);
    let rgb = Vec3::new(rgb[0] as f32, rgb[1] as f32, rgb[2] as f32).max(Vec3::ZERO);
    chroma_of(rgb, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sky::sun_direction;

    /// CIE 1931 xy of linear Rec. 709 RGB (the inverse of [`XYZ_TO_REC709`], IEC 61966-2-1).
    fn xy(rgb: Vec3) -> (f64, f64) {
        let (r, g, b) = (f64::from(rgb.x), f64::from(rgb.y), f64::from(rgb.z));
        let x = 0.412_456_4 * r + 0.357_576_1 * g + 0.180_437_5 * b;
        let y = 0.212_672_9 * r + 0.715_152_2 * g + 0.072_175_0 * b;
        let z = 0.019_333_9 * r + 0.119_192_0 * g + 0.950_304_1 * b;
        (x / (x + y + z), y / (x + y + z))
    }

    /// Preetham, Shirley & Smits (1999), appendix: a clear sky's chromaticity of turbidity `t`
    /// with the sun at zenith angle `theta_s`, along a direction at zenith angle `theta` and
    /// angle `gamma` from the sun: the zenith's (x_z, y_z), shaped by Perez's distribution with
    /// their coefficients (an independent, older model).
    fn preetham(t: f64, theta_s: f64, theta: f64, gamma: f64) -> (f64, f64) {
        let th = [theta_s.powi(3), theta_s.powi(2), theta_s, 1.0];
        let zenith = |m: [[f64; 4]; 3]| {
            let row = |r: [f64; 4]| r.iter().zip(th).map(|(a, b)| a * b).sum::<f64>();
            t * t * row(m[0]) + t * row(m[1]) + row(m[2])
        };
        let xz = zenith([
            [0.00166, -0.00375, 0.00209, 0.0],
            [-0.02903, 0.06377, -0.03202, 0.00394],
            [0.11693, -0.21196, 0.06052, 0.25886],
        ]);
        let yz = zenith([
            [0.00275, -0.00610, 0.00317, 0.0],
            [-0.04214, 0.08970, -0.04153, 0.00516],
            [0.15346, -0.26756, 0.06670, 0.26688],
        ]);
        let perez = |c: [f64; 5], th: f64, g: f64| {
            (1.0 + c[0] * (c[1] / th.cos().max(1e-3)).exp())
                * (1.0 + c[2] * (c[3] * g).exp() + c[4] * g.cos().powi(2))
        };
        let cx = [
            -0.0193 * t - 0.2592,
            -0.0665 * t + 0.0008,
            -0.0004 * t + 0.2125,
            -0.0641 * t - 0.8989,
            -0.0033 * t + 0.0452,
        ];
        let cy = [
            -0.0167 * t - 0.2608,
            -0.0950 * t + 0.0092,
            -0.0079 * t + 0.2102,
            -0.0441 * t - 1.6537,
            -0.0109 * t + 0.0529,
        ];
        (
            xz * perez(cx, theta, gamma) / perez(cx, 0.0, theta_s),
            yz * perez(cy, theta, gamma) / perez(cy, 0.0, theta_s),
        )
    }

    fn preetham_zenith(t: f64, theta_s: f64) -> (f64, f64) {
        preetham(t, theta_s, 0.0, theta_s)
    }

    fn clear(sky_type: i64, elevation_deg: f64) -> SkyColour {
        let kind = SkyKind::general(sky_type, Some(sun_direction(elevation_deg, 180.0))).unwrap();
        SkyColour::new(kind).unwrap()
    }

    #[test]
    fn the_overcast_skies_stay_neutral() {
        assert!(SkyColour::new(SkyKind::Overcast).is_none());
        for t in 1..=5 {
            let kind = SkyKind::general(t, Some(sun_direction(30.0, 0.0))).unwrap();
            assert!(SkyColour::new(kind).is_none(), "type {t}");
        }
        for t in 6..=15 {
            let kind = SkyKind::general(t, Some(sun_direction(30.0, 0.0))).unwrap();
            assert!(SkyColour::new(kind).is_some(), "type {t}");
        }
    }

    #[test]
    fn a_clear_midday_zenith_is_blue_as_preetham_gives_it() {
        for (el, t) in [(60.0, 12), (45.0, 12), (30.0, 11), (60.0, 13)] {
            let c = clear(t, el);
            let (x, y) = xy(c.chroma(Vec3::Y));
            let (px, py) = preetham_zenith(f64::from(c.turbidity), (90.0 - el).to_radians());
            assert!((0.20..0.29).contains(&x), "type {t} sun {el}: x {x}");
            assert!(
                (x - px).abs() < 0.03 && (y - py).abs() < 0.03,
                "type {t} sun {el}: ({x}, {y}) vs Preetham ({px}, {py})"
            );
            // Luminance 1: the CIE luminance is kept.
            assert!((LUMA.dot(c.chroma(Vec3::Y)) - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn the_whole_sky_follows_preethams_chromaticity() {
        // Every direction 5°-85° up at 8 azimuths, suns 10°-60° up, the clear types 11-13:
        // within 0.05 of Preetham et al.'s x and y everywhere, median 0.02 (two models fitted
        // to different simulations; they differ most near the horizon and at turbidity 4.5,
        // where Hosek & Wilkie found Preetham's model too yellow).
        let mut diffs = Vec::new();
        for el_s in [10.0, 20.0, 30.0, 45.0, 60.0] {
            for t in [11, 12, 13] {
                let c = clear(t, el_s);
                let sun = sun_direction(el_s, 180.0);
                for el in (5..=85).step_by(10) {
                    for k in 0..8 {
                        let dir = sun_direction(f64::from(el), f64::from(k) * 45.0);
                        let gamma = f64::from(dir.dot(sun).clamp(-1.0, 1.0)).acos();
                        let (px, py) = preetham(
                            f64::from(c.turbidity),
                            (90.0 - el_s).to_radians(),
                            (90.0 - f64::from(el)).to_radians(),
                            gamma,
                        );
                        let (x, y) = xy(c.chroma(dir));
                        let d = (x - px).abs().max((y - py).abs());
                        assert!(
                            d < 0.05,
                            "type {t} sun {el_s} dir {el}/{k}: ({x:.3}, {y:.3}) vs ({px:.3}, {py:.3})"
                        );
                        diffs.push(d);
                    }
                }
            }
        }
        diffs.sort_by(f64::total_cmp);
        let median = diffs[diffs.len() / 2];
        assert!(median < 0.02, "median {median}");
    }

    #[test]
    fn the_horizon_under_a_low_sun_is_orange_and_opposite_it_paler() {
        let c = clear(12, 2.0);
        let toward = Vec3::new(0.0, 0.02, 1.0).normalize(); // the sun is due south (+Z)
        let away = Vec3::new(0.0, 0.02, -1.0).normalize();
        let (xt, yt) = xy(c.chroma(toward));
        let (xa, _) = xy(c.chroma(away));
        assert!(xt > 0.40 && yt > 0.37, "towards the sun ({xt}, {yt})");
        assert!(xa < xt - 0.05, "away {xa} vs towards {xt}");
        let rgb = c.chroma(toward);
        assert!(rgb.x > rgb.y && rgb.y > rgb.z, "{rgb}");
    }

    #[test]
    fn half_saturation_is_half_way_to_neutral_at_the_same_luminance() {
        let full = clear(11, 40.0);
        let half = SkyColour {
            saturation: 0.5,
            ..full
        };
        let d = Vec3::new(0.3, 0.6, -0.2).normalize();
        let (f, h) = (full.chroma(d), half.chroma(d));
        assert!((h - (Vec3::ONE + (f - Vec3::ONE) * 0.5)).length() < 1e-6);
        assert!((LUMA.dot(h) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn the_colour_matching_table_has_the_cie_observers_integrals() {
        // ∫ȳ dλ = 106.857 over the 1 nm table (CIE 015:2018); the equal-energy white E has
        // x = y = 1/3, so the three integrals agree (a check of the transcription).
        let sum = |k: usize| CIE_1931_10NM.iter().map(|r| r[k]).sum::<f64>() * 10.0;
        let (x, y, z) = (sum(0), sum(1), sum(2));
        assert!((y / 106.857 - 1.0).abs() < 2e-3, "{y}");
        assert!(
            (x / y - 1.0).abs() < 2e-3 && (z / y - 1.0).abs() < 2e-3,
            "{x} {y} {z}"
        );
        assert_eq!(CIE_1931_10NM[17], [0.4334499, 0.9949501, 0.008749999]); // 550 nm
    }

    #[test]
    fn the_sun_reddens_as_it_sets() {
        let high = sun_colour(60.0, 3.0);
        let low = sun_colour(5.0, 3.0);
        let (xh, _) = xy(high);
        let (xl, yl) = xy(low);
        // A high sun is near white (the black body's 5778 K, x 0.326, yellowed a little by
        // the air); a low one orange.
        assert!((0.32..0.36).contains(&xh), "high x {xh}");
        assert!(xl > 0.42 && yl > 0.38, "low ({xl}, {yl})");
        assert!((LUMA.dot(low) - 1.0).abs() < 1e-5 && low.min_element() >= 0.0);
        assert!(rayleigh_optical_depth(0.55) > 0.09 && rayleigh_optical_depth(0.55) < 0.1);
    }
}
