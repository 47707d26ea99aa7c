//! A sky as the renderer uses it: a luminance distribution, the rain's attenuation along each
//! direction, and the normalisation to the user's horizontal illuminance.

use super::cie::SkyKind;
use crate::error::{Range, Result};
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
/// Azimuth steps of the normalisation quadrature (periodic midpoint rule).
const AZIMUTHS: usize = 360;

/// The largest optical depth σH below the cloud base that shapes the sky. Denser (under
/// ~30 m visibility at a 1500 m base) the sky is shaped as at this depth: the quadratures of
/// the normalisation and of the illuminance tables no longer resolve the narrower zenith peak
/// (at σH = 600 they disagreed by 15 %, at 1200 by 2.5×), and light in such fog is scattered
/// many times, which the single-scattering sky does not describe anyway.
pub const MAX_SKY_OPTICAL_DEPTH: f64 = 200.0;

/// The most a sky pixel shows, relative to E/π ([`Sky::sky_pixel`]): in dense fog the cloud base
/// is e^(σH) times brighter than E, which overflows f32, and ∞·0 in the haze (t = 0 for the
/// sky) would be NaN. A sky pixel that bright is always hazed to the airlight.
pub const SKY_PIXEL_MAX: f64 = 1e30;

/// A normalised sky with rain attenuation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sky {
    /// The luminance distribution.
    pub kind: SkyKind,
    /// σ of the air and rain below the cloud base, 1/m.
    pub extinction_per_m: f64,
    /// Cloud base height H, m.
    pub cloud_base_m: f64,
    /// π / ∫ (L/Lz) τ cos θ dω: multiplies L/Lz into luminance relative to E/π. In dense fog
    /// (σH of hundreds) the cloud base must be e^(σH) times brighter than E to light the ground
    /// through it, so this may be huge or infinite; what reaches the ground is finite.
    pub scale: f64,
    /// `scale` · τ at the zenith (e^(−σH)), computed without forming either: multiplies
    /// (L/Lz)·τ/τ_zenith into the luminance received at the ground.
    pub received_scale: f64,
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

    /// Normalised sky: ∫ L τ cos θ dω over the open hemisphere equals E (relative: π).
    pub fn new(kind: SkyKind, extinction_per_m: f64, cloud_base_m: f64) -> Result<Self> {
        Range::closed(0.0, 1e3, "1/m").check("extinction_per_m", None, extinction_per_m)?;
        crate::ranges::CLOUD_BASE_M.check(cloud_base_m)?;
        let mut sky = Sky {
            kind,
            extinction_per_m,
            cloud_base_m,
            scale: 1.0,
            received_scale: 1.0,
        };
        let ring = |mu: f64| {
            let (s, c) = (mu, (1.0 - mu * mu).max(0.0).sqrt());
            let mut sum = 0.0;
            for k in 0..AZIMUTHS {
                let az = (k as f64 + 0.5) * TAU / AZIMUTHS as f64;
                let dir = Vec3::new((c * az.sin()) as f32, s as f32, (-c * az.cos()) as f32);
                sum += kind.relative_to_zenith(dir);
            }
            sum * TAU / AZIMUTHS as f64 * sky.relative_transmittance(mu) * mu
        };
        let mut breaks: Vec<f64> = MU_BREAKS.to_vec();
        if let SkyKind::General { sun, .. } = kind {
            breaks.push(f64::from(sun.y)); // the circumsolar cusp's ring
        }
        // Normalised with τ relative to the zenith's, so that neither the integral nor the
        // received luminance under- or overflows in dense fog.
        let total = integrate(ring, 0.0, 1.0, &breaks, 4);
        sky.received_scale = PI / total;
        sky.scale = sky.received_scale * sky.optical_depth().exp();
        Ok(sky)
    }

    /// σH, capped at [`MAX_SKY_OPTICAL_DEPTH`].
    #[inline]
    fn optical_depth(&self) -> f64 {
        (self.extinction_per_m * self.cloud_base_m).min(MAX_SKY_OPTICAL_DEPTH)
    }

    /// τ(μ) / τ(zenith) = exp(−σ·H·(1/μ − 1)): 0 at and below the horizon (when σ > 0), 1
    /// without extinction.
    #[inline]
    fn relative_transmittance(&self, mu: f64) -> f64 {
        if self.extinction_per_m <= 0.0 {
            1.0
        } else if mu <= 0.0 {
            0.0
        } else {
            (-self.optical_depth() * (1.0 / mu - 1.0)).exp()
        }
    }

    /// Luminance of the sky (the cloud base) along `dir`, relative to E/π, without the rain
    /// in between: what a sky pixel shows when there is no haze.
    #[inline]
    pub fn emitted(&self, dir: Vec3) -> f64 {
        self.scale * self.kind.relative_to_zenith(dir)
    }

    /// [`Sky::emitted`] as a frame's sky pixel shows it: at most [`SKY_PIXEL_MAX`].
    #[inline]
    pub fn sky_pixel(&self, dir: Vec3) -> f32 {
        self.emitted(dir).min(SKY_PIXEL_MAX) as f32
    }

    /// Luminance reaching the ground along `dir`, relative to E/π: [`Sky::emitted`] · τ.
    #[inline]
    pub fn received(&self, dir: Vec3) -> f64 {
        self.received_scale
            * self.kind.relative_to_zenith(dir)
            * self.relative_transmittance(f64::from(dir.y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overcast_scale_is_nine_sevenths() {
        let s = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
        // L/(E/π) at the zenith is 9/7 for the overcast sky (Lz = 9E/7π).
        assert!((s.scale - 9.0 / 7.0).abs() < 1e-9, "{}", s.scale);
        assert!((s.emitted(Vec3::new(1.0, 0.0, 0.0)) - 3.0 / 7.0).abs() < 1e-9);
    }

    #[test]
    fn rain_dims_the_low_sky_most_and_keeps_e() {
        let s = Sky::new(SkyKind::Overcast, 1.5e-3, cloud_base_m(10.0)).unwrap();
        let zen = s.received(Vec3::Y) / s.emitted(Vec3::Y);
        let low = s.received(Vec3::new(0.0, 0.2, 0.98).normalize())
            / s.emitted(Vec3::new(0.0, 0.2, 0.98).normalize());
        assert!(low < zen && zen < 1.0);
        assert!(s.scale > 9.0 / 7.0);
        assert!(
            (cloud_base_m(0.0) - 1500.0).abs() < 1e-9 && (cloud_base_m(1e6) - 300.0).abs() < 1e-9
        );
        let sun = sun_direction(30.0, 90.0);
        assert!((sun - Vec3::new(0.866_025_4, 0.5, 0.0)).length() < 1e-6);
    }
}
