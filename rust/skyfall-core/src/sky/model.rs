//! A sky as the renderer uses it: a luminance distribution, the rain's attenuation along each
//! direction, and the normalisation to the user's horizontal illuminance.

use super::cie::{Shape, SkyKind};
use super::colour::{SkyColour, chroma_of, sun_colour};
use crate::error::{Range, Result};
use crate::haze::path_to_ceiling_m;
use crate::physics::quadrature::integrate;
use glam::Vec3;
use std::f64::consts::{PI, TAU};

/// Cloud base height H for a rain rate, m: H = 1500 − 250·ln(1 + R / (1 mm/h)), kept in
/// [300, 1500] m (1500 m dry, 900 m at 10 mm/h, 520 m at 50 mm/h, 350 m at 100 mm/h).
///
/// Yamamoto & Tadamura give H as a function of R after Shibata (1999) without printing it; this is our
/// own smooth stand-in spanning the bases of rain-bearing nimbostratus (heavier rain, lower
/// base). Only the *shape* of the sky depends on it (τ = exp(−σH/sin γ) per direction), since
/// the sky is normalised to the given E; `Weather.cloud_base_m` overrides it.
pub fn cloud_base_m(rain_rate_mm_h: f64) -> f64 {
    (1500.0 - 250.0 * rain_rate_mm_h.max(0.0).ln_1p()).clamp(300.0, 1500.0)
}

/// Unit vector towards a sun at `elevation_deg` above the horizon and `azimuth_deg` from −Z
/// (north) towards +X (east).
pub fn sun_direction(elevation_deg: f64, azimuth_deg: f64) -> Vec3 {
    let (el, az) = (elevation_deg.to_radians(), azimuth_deg.to_radians());
    Vec3::new(
        (az.sin() * el.cos()) as f32,
        el.sin() as f32,
        (-az.cos() * el.cos()) as f32,
    )
}

/// Elevation breaks of the normalisation quadrature in μ = sin γ: it resolves the steep
/// gradation exp(b/μ) and exp(−σH/μ) near the horizon.
const MU_BREAKS: [f64; 4] = [0.02, 0.08, 0.25, 0.5];
/// Azimuth steps of the normalisation quadrature and of the horizon's mean (periodic midpoint
/// rule).
const AZIMUTHS: usize = 360;

/// The sines and cosines of the normalisation's azimuths, (k + ½)·2π/[`AZIMUTHS`]: computed
/// once (a sky's normalisation reads them 72 000 times).
fn azimuth_sin_cos() -> &'static [(f64, f64); AZIMUTHS] {
    static TABLE: std::sync::OnceLock<[(f64, f64); AZIMUTHS]> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|k| ((k as f64 + 0.5) * TAU / AZIMUTHS as f64).sin_cos())
    })
}

/// A normalised sky seen through the rain and mist below its cloud base.
///
/// The cloud base emits L_c = s·ℓ(ω), ℓ the sky type's luminance relative to its zenith. Seen
/// from the ground along ω (elevation γ, μ = sin γ) through the layer of depth H and
/// extinction σ, the sky is
///
/// L(ω) = L_c(ω)·τ(μ) + A·(1 − τ(μ)),  τ(μ) = e^(−σ d(μ)),
///
/// d(μ) the path to the cloud base, H/μ overhead and √(2RH) along the horizon (the base is a
/// shell over the Earth's sphere, [`path_to_ceiling_m`]),
/// the cloud base attenuated plus the light the drops and the mist scatter into the path. The
/// in-scattered radiance at saturation, the airlight A = s·ℓ̄_h, is the cloud base's own
/// horizon luminance (ℓ̄_h: ℓ averaged over the horizon's azimuths): raindrops scatter visible
/// light and hardly absorb it (single-scattering albedo ≈ 1), so the layer redistributes the
/// cloud base's light rather than losing it, and it makes the horizon continuous (at γ → 0 the
/// path is 138 km under a 1500 m base, and the sky there is A in any real rain). The scale s makes the open ground receive
/// E, ∫ L cos θ dω = E (relative units: π), rain included, since E is what a lux meter there
/// reads. As the rain thickens the sky tends to the uniform A = E/π: the low sky brightens
/// towards the airlight, the zenith dims, and a street canyon's floor, which sees only the
/// high sky, receives less. In clear air (σ = 0) L = L_c: the CIE shapes unchanged. The haze
/// pass applies the same law to a sky pixel along its own ray ([`crate::haze::Haze`]), so the
/// frames' sky, the haze's airlight and the ambient-light map come from this one radiance field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sky {
    /// The luminance distribution.
    pub kind: SkyKind,
    /// σ of the air and rain below the cloud base, 1/m.
    pub extinction_per_m: f64,
    /// Cloud base height H, m.
    pub cloud_base_m: f64,
    /// s = π / ∫ (ℓτ + ℓ̄_h(1 − τ)) cos θ dω: multiplies ℓ into the cloud base's luminance
    /// relative to E/π. Bounded: between π/∫ℓ cos θ dω (clear) and 1/ℓ̄_h (dense fog).
    pub scale: f64,
    /// The airlight A = s·ℓ̄_h, relative to E/π.
    pub airlight: f64,
    /// ℓ̄_h, the horizon's mean of ℓ.
    horizon: f64,
    /// ℓ, ready to evaluate ([`SkyKind::shape`]).
    shape: Shape,
    /// The sky's colour (Hosek & Wilkie's), None for a neutral (overcast) sky.
    pub colour: Option<SkyColour>,
    /// The horizon's colour: ℓ-weighted mean chroma over its azimuths, the airlight's colour
    /// (linear RGB of luminance 1; neutral without a colour).
    pub horizon_colour: Vec3,
    /// The colour of the light the open sky gives a horizontal surface through the rain
    /// (luminance 1), which tints the ambient-light map.
    pub light_colour: Vec3,
    /// The colour of the sun's direct light (luminance 1; neutral without a colour).
    pub sun_colour: Vec3,
}

/// Skies [`Sky::cached`] keeps: a frame's sky is the same from frame to frame of a sequence or
/// a dataset, and its normalisation is a quadrature (about 0.8 ms).
const SKY_CACHE: usize = 16;

impl Sky {
    /// [`Sky::new`], remembered for the last [`SKY_CACHE`] distinct (kind, σ, H): the same bits.
    pub fn cached(kind: SkyKind, extinction_per_m: f64, cloud_base_m: f64) -> Result<Self> {
        type Entry = (SkyKind, u64, u64, Sky);
        static CACHE: std::sync::Mutex<Vec<Entry>> = std::sync::Mutex::new(Vec::new());
        let (s, h) = (extinction_per_m.to_bits(), cloud_base_m.to_bits());
        if let Ok(c) = CACHE.lock()
            && let Some(e) = c.iter().find(|e| e.0 == kind && e.1 == s && e.2 == h)
        {
            return Ok(e.3);
        }
        let sky = Sky::new(kind, extinction_per_m, cloud_base_m)?;
        if let Ok(mut c) = CACHE.lock() {
            if c.len() >= SKY_CACHE {
                c.remove(0);
            }
            c.push((kind, s, h, sky));
        }
        Ok(sky)
    }

    /// Normalised sky: ∫ L cos θ dω over the open hemisphere equals E (relative: π).
    pub fn new(kind: SkyKind, extinction_per_m: f64, cloud_base_m: f64) -> Result<Self> {
        Range::closed(0.0, 1e3, "1/m").check("extinction_per_m", None, extinction_per_m)?;
        crate::ranges::CLOUD_BASE_M.check(cloud_base_m)?;
        let azimuths = azimuth_sin_cos();
        let shape = kind.shape();
        let horizon = azimuths
            .iter()
            .map(|&(sin, cos)| shape.relative_to_zenith(Vec3::new(sin as f32, 0.0, -cos as f32)))
            .sum::<f64>()
            / AZIMUTHS as f64;
        let colour = SkyColour::new(kind);
        let mut sky = Sky {
            kind,
            extinction_per_m,
            cloud_base_m,
            scale: 1.0,
            airlight: horizon,
            horizon,
            shape,
            colour,
            horizon_colour: Vec3::ONE,
            light_colour: Vec3::ONE,
            sun_colour: Vec3::ONE,
        };
        let ring = |mu: f64| {
            let (s, c) = (mu, (1.0 - mu * mu).max(0.0).sqrt());
            // ℓ = gradation(μ)·indicatrix(ω): the gradation once per ring
            let mut sum = 0.0;
            for &(sin, cos) in azimuths {
                let dir = Vec3::new((c * sin) as f32, s as f32, (-c * cos) as f32);
                sum += shape.indicatrix(dir);
            }
            let mean = shape.gradation(f64::from(s as f32)) * sum / AZIMUTHS as f64;
            let tau = sky.transmittance(mu);
            (mean * tau + horizon * (1.0 - tau)) * TAU * mu
        };
        let mut breaks: Vec<f64> = MU_BREAKS.to_vec();
        if let SkyKind::General { sun, .. } = kind {
            breaks.push(f64::from(sun.y)); // the circumsolar cusp's ring
        }
        let total = integrate(ring, 0.0, 1.0, &breaks, 4);
        sky.scale = PI / total;
        sky.airlight = sky.scale * horizon;
        if let Some(c) = colour {
            sky.horizon_colour = horizon_colour(&shape, &c);
            sky.light_colour = sky.sky_light_colour();
            let elevation_deg = f64::from(c.sun.y.clamp(0.0, 1.0).asin().to_degrees());
            sky.sun_colour = sun_colour(elevation_deg, f64::from(c.turbidity));
        }
        Ok(sky)
    }

    /// The colour of the light the open sky gives a horizontal surface: [`light_colour_of`] its
    /// received light ([`Sky::received_rgb`]: ℓτ·chroma + ℓ̄_h(1 − τ) in the horizon's colour).
    fn sky_light_colour(&self) -> Vec3 {
        light_colour_of(|dir| self.received_rgb(dir))
    }

    /// τ(μ) = e^(−σ d(μ)), the cloud base's transmittance down to the ground along a direction
    /// of sin(elevation) μ, d the path to the cloud base ([`path_to_ceiling_m`]: H/μ overhead,
    /// √(2RH) along the horizon); 1 without extinction.
    #[inline]
    pub fn transmittance(&self, mu: f64) -> f64 {
        if self.extinction_per_m <= 0.0 {
            1.0
        } else {
            let d = path_to_ceiling_m(mu as f32, self.cloud_base_m as f32);
            (-self.extinction_per_m * f64::from(d)).exp()
        }
    }

    /// Luminance of the cloud base along `dir`, relative to E/π, without the rain in between:
    /// a box frame's sky pixel before the haze pass, which attenuates it along the pixel's ray
    /// to the cloud base and adds the in-scattered light (giving [`Sky::received`]).
    #[inline]
    pub fn emitted(&self, dir: Vec3) -> f64 {
        self.scale * self.shape.relative_to_zenith(dir)
    }

    /// [`Sky::emitted`] in f32, as a frame's sky pixel holds it.
    #[inline]
    pub fn sky_pixel(&self, dir: Vec3) -> f32 {
        self.emitted(dir) as f32
    }

    /// The sky's chroma along unit `dir` (linear RGB of luminance 1; neutral without a colour).
    #[inline]
    pub fn chroma(&self, dir: Vec3) -> Vec3 {
        self.colour.map_or(Vec3::ONE, |c| c.chroma(dir))
    }

    /// A frame's sky pixel in colour: [`Sky::sky_pixel`] times the sky's chroma there.
    #[inline]
    pub fn sky_pixel_rgb(&self, dir: Vec3) -> Vec3 {
        match &self.colour {
            None => Vec3::splat(self.sky_pixel(dir)),
            Some(c) => c.chroma(dir) * self.sky_pixel(dir),
        }
    }

    /// [`Sky::received`] in colour: L_c·τ·chroma + A·(1 − τ)·horizon colour (linear RGB whose
    /// luminance is [`Sky::received`]).
    pub fn received_rgb(&self, dir: Vec3) -> Vec3 {
        let tau = self.transmittance(f64::from(dir.y));
        let lc = self.scale * self.shape.relative_to_zenith(dir) * tau;
        let a = self.scale * self.horizon * (1.0 - tau);
        self.chroma(dir) * lc as f32 + self.horizon_colour * a as f32
    }

    /// Luminance reaching the ground along `dir`, relative to E/π: L_c·τ + A·(1 − τ).
    #[inline]
    pub fn received(&self, dir: Vec3) -> f64 {
        self.received_at(dir, &self.at_elevation(f64::from(dir.y)))
    }

    /// What [`Sky::received`] owes the elevation alone, at sin(elevation) `mu`: for many
    /// directions at one elevation (a sky table's azimuths), worked out once.
    #[inline]
    pub fn at_elevation(&self, mu: f64) -> AtElevation {
        AtElevation {
            tau: self.transmittance(mu),
            gradation: self.shape.gradation(mu),
        }
    }

    /// [`Sky::received`] along `dir` whose elevation's part is `at` (its
    /// [`Sky::at_elevation`]): the same value.
    #[inline]
    pub fn received_at(&self, dir: Vec3, at: &AtElevation) -> f64 {
        let l = at.gradation * self.shape.indicatrix(dir);
        self.scale * (l * at.tau + self.horizon * (1.0 - at.tau))
    }
}

/// What a sky's received luminance owes the elevation alone ([`Sky::at_elevation`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AtElevation {
    /// τ, the cloud base's transmittance down to the ground.
    tau: f64,
    /// ℓ's gradation ([`Shape::gradation`]).
    gradation: f64,
}

/// The colour (linear RGB of luminance 1) of the light a horizontal surface receives from a
/// sky sending `received_rgb(dir)` along each unit direction above the horizon: ∫ L cos θ dω
/// by a midpoint rule, 48 steps in sin(elevation) by 96 azimuths (a tint, not a
/// normalisation). A clear sky's ([`Sky::light_colour`]) and one with clouds in it
/// (`crate::cloud::dome::clouded_light`).
pub fn light_colour_of(received_rgb: impl Fn(Vec3) -> Vec3) -> Vec3 {
    let (n_mu, n_az) = (48, 96);
    let mut sum = Vec3::ZERO;
    for i in 0..n_mu {
        let mu = (i as f64 + 0.5) / n_mu as f64;
        let cos_el = (1.0 - mu * mu).sqrt();
        for k in 0..n_az {
            let (sin, cos) = ((k as f64 + 0.5) * TAU / n_az as f64).sin_cos();
            let dir = Vec3::new((cos_el * sin) as f32, mu as f32, (-cos_el * cos) as f32);
            sum += received_rgb(dir) * mu as f32;
        }
    }
    chroma_of(sum, 1.0)
}

/// The horizon's colour: Σ ℓ·chroma / Σ ℓ over [`AZIMUTHS`] azimuths at elevation 0.
fn horizon_colour(shape: &Shape, c: &SkyColour) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for &(sin, cos) in azimuth_sin_cos() {
        let dir = Vec3::new(sin as f32, 0.0, -cos as f32);
        sum += c.chroma(dir) * shape.relative_to_zenith(dir) as f32;
    }
    chroma_of(sum, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ L cos θ dω over the hemisphere by a midpoint rule in elevation and azimuth (independent
    /// of the normalisation's Gauss quadrature), relative to E/π: π when E is kept.
    fn hemisphere_integral(sky: &Sky) -> f64 {
        let (n_el, n_az) = (3000, 180);
        let mut sum = 0.0;
        for i in 0..n_el {
            let el = (i as f64 + 0.5) / n_el as f64 * FRAC_PI_2;
            for k in 0..n_az {
                let az = (k as f64 + 0.5) / n_az as f64 * TAU;
                let dir = Vec3::new(
                    (el.cos() * az.sin()) as f32,
                    el.sin() as f32,
                    (-el.cos() * az.cos()) as f32,
                );
                sum += sky.received(dir) * el.sin() * el.cos();
            }
        }
        sum * (FRAC_PI_2 / n_el as f64) * (TAU / n_az as f64)
    }

    use crate::sky::colour::LUMA;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn clear_skies_keep_their_cie_shape_and_airlight() {
        let s = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
        // L/(E/π) at the zenith is 9/7 for the overcast sky (Lz = 9E/7π), 3/7 at the horizon.
        assert!((s.scale - 9.0 / 7.0).abs() < 1e-9, "{}", s.scale);
        assert!((s.emitted(Vec3::new(1.0, 0.0, 0.0)) - 3.0 / 7.0).abs() < 1e-9);
        assert!((s.airlight - 3.0 / 7.0).abs() < 1e-9);
        assert_eq!(s.received(Vec3::Y), s.emitted(Vec3::Y));
        // The uniform sky (CIE type 5): E/π everywhere, its airlight too.
        let u = Sky::new(SkyKind::general(5, None).unwrap(), 0.0, 1000.0).unwrap();
        assert!((u.airlight - 1.0).abs() < 1e-6 && (u.scale - 1.0).abs() < 1e-6);
    }

    #[test]
    fn every_sky_gives_e_in_any_rain() {
        let sun = Some(sun_direction(35.0, 120.0));
        for kind in [
            SkyKind::Overcast,
            SkyKind::general(5, None).unwrap(),
            SkyKind::general(12, sun).unwrap(),
        ] {
            for sigma in [0.0, 3e-4, 1.5e-3, 3.912e-3, 0.04, 1e3] {
                let s = Sky::new(kind, sigma, 900.0).unwrap();
                let e = hemisphere_integral(&s) / PI;
                assert!((e - 1.0).abs() < 2e-3, "{kind:?} σ {sigma}: E {e}");
                assert!(s.scale.is_finite() && s.airlight.is_finite());
            }
        }
    }

    #[test]
    fn heavy_rain_turns_the_sky_to_its_airlight() {
        let dir = |deg: f64| {
            let r = deg.to_radians();
            Vec3::new(0.0, r.sin() as f32, -r.cos() as f32)
        };
        let clear = Sky::new(SkyKind::Overcast, 0.0, 900.0).unwrap();
        let rain = Sky::new(SkyKind::Overcast, 1.5e-3, 900.0).unwrap();
        let fog = Sky::new(SkyKind::Overcast, 0.04, 900.0).unwrap();
        // At the horizon the path is infinite: the sky is the airlight in any rain.
        assert!((rain.received(dir(0.0)) - rain.airlight).abs() < 1e-12);
        // Rain flattens the overcast sky: the low sky brightens, the zenith dims ...
        assert!(rain.received(dir(10.0)) > clear.received(dir(10.0)));
        assert!(rain.received(Vec3::Y) < clear.received(Vec3::Y));
        // ... and in fog (σH = 36) it is the airlight everywhere, E/π.
        for deg in [0.0, 10.0, 45.0, 90.0] {
            assert!((fog.received(dir(deg)) - 1.0).abs() < 1e-9, "{deg}");
        }
        assert!((fog.airlight - 1.0).abs() < 1e-9);
        assert!(
            (cloud_base_m(0.0) - 1500.0).abs() < 1e-9 && (cloud_base_m(1e6) - 300.0).abs() < 1e-9
        );
        let sun = sun_direction(30.0, 90.0);
        assert!((sun - Vec3::new(0.866_025_4, 0.5, 0.0)).length() < 1e-6);
    }

    #[test]
    fn a_colour_sky_keeps_its_luminance_and_the_overcast_one_stays_grey() {
        let sun = Some(sun_direction(50.0, 150.0));
        for sigma in [0.0, 1.5e-3] {
            let clear = Sky::new(SkyKind::general(12, sun).unwrap(), sigma, 1500.0).unwrap();
            for dir in [
                Vec3::Y,
                Vec3::new(0.5, 0.3, -0.8).normalize(),
                Vec3::new(0.0, 0.05, 1.0).normalize(),
            ] {
                let rgb = clear.sky_pixel_rgb(dir);
                let l = LUMA.dot(rgb);
                assert!((l / clear.sky_pixel(dir) - 1.0).abs() < 1e-5, "{dir}: {l}");
                let r = LUMA.dot(clear.received_rgb(dir)) as f64;
                assert!((r / clear.received(dir) - 1.0).abs() < 1e-5, "{dir}: {r}");
            }
            // In clear air the sky light on the ground is blue, paler than the zenith (in rain
            // it tends to the horizon's near-white); the sun is warm.
            let (zen, light) = (clear.chroma(Vec3::Y), clear.light_colour);
            if sigma == 0.0 {
                assert!(light.z > light.y && light.y > light.x, "{light}");
                assert!(light.z < zen.z, "{light} vs zenith {zen}");
            }
            assert!(clear.sun_colour.x > clear.sun_colour.z);
            assert!((LUMA.dot(light) - 1.0).abs() < 1e-5);
        }
        // In dense fog the sky light is the horizon's colour.
        let fog = Sky::new(SkyKind::general(12, sun).unwrap(), 0.04, 900.0).unwrap();
        assert!((fog.light_colour - fog.horizon_colour).length() < 1e-4);
        let grey = Sky::new(SkyKind::Overcast, 1.5e-3, 900.0).unwrap();
        assert!(grey.colour.is_none());
        assert_eq!(
            grey.sky_pixel_rgb(Vec3::Y),
            Vec3::splat(grey.sky_pixel(Vec3::Y))
        );
        assert_eq!(
            (grey.light_colour, grey.horizon_colour, grey.sun_colour),
            (Vec3::ONE, Vec3::ONE, Vec3::ONE)
        );
    }
}
