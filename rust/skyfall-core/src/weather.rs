//! The weather of a frame, as the user sets it (Python's `skyfall.Weather`, field for field),
//! and what the frame's passes derive from it: the extinction of the air and the rain (the haze
//! model), the cloud base, the sky, the haze with its airlight, the rain region.

use crate::error::{Error, Param, Result};
use crate::haze::{Drawn, Haze};
use crate::physics::extinction::rain_extinction_per_m;
use crate::physics::snow::Snowfall;
use crate::rain::drops::{RainMethod, RainRegion};
use crate::ranges;
use crate::sky::cie::SkyKind;
use crate::sky::{Sky, cloud_base_m, sun_direction};
use crate::snow::flakes::{FLAKE_DRAWN_MIN_MM, SnowRegion};
pub use crate::snow::streaks::SnowOpacity;

/// −ln(0.02): the meteorological visibility is where contrast falls to 2 % (Koschmieder).
pub const KOSCHMIEDER: f64 = 3.912;

/// The sky's luminance distribution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SkySpec {
    /// The CIE standard overcast sky (Yamamoto & Tadamura's).
    Overcast,
    /// A CIE S 011 general sky, type 1–15.
    General(i64),
}

/// A frame's weather.
#[derive(Debug, Clone, PartialEq)]
pub struct Weather {
    /// Rain rate R, mm/h.
    pub rain_rate_mm_h: f64,
    /// Snowfall rate as liquid-water equivalent, mm/h.
    pub snow_rate_mm_h: f64,
    /// Bulk density of the snow cover, kg/m³.
    pub snow_density_kg_m3: f64,
    /// Radius of the snow region drawn as flakes, m.
    pub snow_near_m: f64,
    /// How the flakes' opacity falls with distance.
    pub snow_opacity: SnowOpacity,
    /// Meteorological visibility of the air without rain, m (inf: perfectly clear).
    pub visibility_m: f64,
    /// Horizontal illuminance E of the open sky at the ground, lux.
    pub sky_illuminance_lux: f64,
    /// Wind, m/s.
    pub wind_m_s: [f64; 3],
    /// Radius of the rain region drawn as streaks, m.
    pub rain_near_m: f64,
    /// Drops farther than this horizontally, m (below `rain_near_m`), are drawn as the far
    /// level of detail's layers ([`crate::rain::far`]); None: every drop one by one.
    pub rain_far_m: Option<f64>,
    /// Diameters whose bins are drawn, mm.
    pub rain_diameters_mm: Vec<f64>,
    /// Whether drops near the camera are drawn as streaks.
    pub rain_streaks: bool,
    /// Drops or billboards.
    pub rain_method: RainMethod,
    /// Whether boxes keep the rain off what they cover.
    pub rain_sheltered: bool,
    /// How long the rain has fallen at `rain_rate_mm_h` on the surfaces, s: their water film
    /// ([`crate::wet`]); None: long enough to fill them; 0: dry surfaces (no wet stage).
    pub rain_duration_s: Option<f64>,
    /// How long ago that rain stopped, s: the surfaces dry ([`crate::wet::film`]), and no rain
    /// falls in the frame (no streaks, no rain in the haze); 0: it is raining.
    pub dry_s: f64,
    /// The sky.
    pub sky: SkySpec,
    /// The sun's (elevation, azimuth), deg, for the skies that need one.
    pub sun_deg: Option<(f64, f64)>,
    /// Cloud base height, m; None: [`cloud_base_m`] of the rain rate.
    pub cloud_base_m: Option<f64>,
    /// The sun's direct normal illuminance at the ground, lux; None: the clear sky's
    /// ([`crate::sky::sun::clear_sky_sun_lux`]) for the CIE types 7–15 (the skies with a
    /// visible sun), none for the others.
    pub sun_illuminance_lux: Option<f64>,
}

impl Weather {
    /// Checks every field against its range ([`crate::ranges`]).
    pub fn validate(&self) -> Result<()> {
        ranges::RAIN_RATE_MM_H.check(self.rain_rate_mm_h)?;
        ranges::SNOW_RATE_MM_H.check(self.snow_rate_mm_h)?;
        ranges::SNOW_DENSITY_KG_M3.check(self.snow_density_kg_m3)?;
        ranges::VISIBILITY_M.check(self.visibility_m)?;
        ranges::SKY_ILLUMINANCE_LUX.check(self.sky_illuminance_lux)?;
        for (i, &w) in self.wind_m_s.iter().enumerate() {
            ranges::WIND_M_S.check_at(Some(i), w)?;
        }
        ranges::RAIN_NEAR_M.check(self.rain_near_m)?;
        if let Some(far) = self.rain_far_m {
            ranges::RAIN_FAR_M.check(far)?;
            if far >= self.rain_near_m {
                return Err(crate::error::Error::Invalid {
                    param: crate::error::Param {
                        name: "rain_far_m",
                        index: None,
                    },
                    message: format!(
                        "rain_far_m = {far} m must be less than rain_near_m = {} m (the far \
                         level of detail draws the drops between them)",
                        self.rain_near_m
                    ),
                });
            }
        }
        ranges::SNOW_NEAR_M.check(self.snow_near_m)?;
        if let Some(t) = self.rain_duration_s {
            ranges::RAIN_DURATION_S.check(t)?;
        }
        ranges::DRY_S.check(self.dry_s)?;
        ranges::RAIN_DIAMETERS_MM.check_all(&self.rain_diameters_mm)?;
        if let Some((el, az)) = self.sun_deg {
            ranges::SUN_ELEVATION_DEG.check(el)?;
            ranges::SUN_AZIMUTH_DEG.check(az)?;
        }
        if let Some(h) = self.cloud_base_m {
            ranges::CLOUD_BASE_M.check(h)?;
        }
        if let Some(e) = self.sun_illuminance_lux {
            ranges::SUN_ILLUMINANCE_LUX.check(e)?;
            if e > 0.0 && self.sun_deg.is_none() {
                return Err(crate::error::Error::Invalid {
                    param: crate::error::Param {
                        name: "sun_illuminance_lux",
                        index: None,
                    },
                    message: "a sun needs a position: give sun_elevation_deg and sun_azimuth_deg"
                        .into(),
                });
            }
        }
        if let SkySpec::General(t) = self.sky {
            ranges::SKY.check(t as f64)?;
        }
        Ok(())
    }

    /// Koschmieder extinction of the air, 3.912 / visibility_m, 1/m (0 for infinite visibility).
    pub fn air_extinction_per_m(&self) -> f64 {
        if self.visibility_m.is_infinite() {
            0.0
        } else {
            KOSCHMIEDER / self.visibility_m
        }
    }

    /// Extinction by rain, 1/m ([`rain_extinction_per_m`] of the rate falling).
    pub fn rain_extinction_per_m(&self) -> f64 {
        rain_extinction_per_m(self.falling_rain_mm_h())
    }

    /// The rain rate falling in the frame, mm/h: `rain_rate_mm_h`, or 0 once the rain stopped
    /// (`dry_s` > 0).
    pub fn falling_rain_mm_h(&self) -> f64 {
        if self.dry_s > 0.0 {
            0.0
        } else {
            self.rain_rate_mm_h
        }
    }

    /// The water the rain left on the surfaces ([`crate::wet::film`]).
    pub fn film(&self) -> crate::wet::film::Film {
        crate::wet::film::Film {
            rate_mm_h: self.rain_rate_mm_h,
            duration_s: self.rain_duration_s,
            dry_s: self.dry_s,
        }
    }

    /// Extinction by falling snow, 1/m ([`Snowfall::extinction_per_m`] of the rate; 0 without
    /// snow).
    pub fn snow_extinction_per_m(&self) -> f64 {
        if self.snow_rate_mm_h > 0.0 {
            Snowfall::new(self.snow_rate_mm_h).extinction_per_m()
        } else {
            0.0
        }
    }

    /// Total extinction σ = σ_air + σ_rain + σ_snow, 1/m.
    pub fn extinction_per_m(&self) -> f64 {
        let sigma = self.air_extinction_per_m() + self.rain_extinction_per_m();
        if self.snow_rate_mm_h > 0.0 {
            sigma + self.snow_extinction_per_m()
        } else {
            sigma
        }
    }

    /// The snow region of a frame at `time_s` with `seed`, when it snows.
    pub fn snow_region(&self, time_s: f64, seed: u64) -> Result<Option<SnowRegion>> {
        if self.snow_rate_mm_h <= 0.0 {
            return Ok(None);
        }
        SnowRegion::new(
            self.snow_rate_mm_h,
            self.snow_near_m,
            self.wind_m_s,
            time_s,
            seed,
        )
        .map(Some)
    }

    /// The cloud base H in use, m: the given one, or [`cloud_base_m`] of the rain rate.
    pub fn cloud_base_height_m(&self) -> f64 {
        self.cloud_base_m
            .unwrap_or_else(|| cloud_base_m(self.falling_rain_mm_h()))
    }

    /// The sun's direct light: its direction (unit, towards it) and its normal illuminance at
    /// the ground over E, through the haze below the cloud base (e^(−σH/sin h)); None without
    /// a sun.
    pub fn sun(&self) -> Option<(glam::Vec3, f64)> {
        let (el, az) = self.sun_deg?;
        let lux = match (self.sun_illuminance_lux, self.sky) {
            (Some(e), _) => e,
            (None, SkySpec::General(t)) if t >= 7 => crate::sky::sun::clear_sky_sun_lux(el),
            (None, _) => 0.0,
        };
        if lux <= 0.0 {
            return None;
        }
        let sin_h = el.to_radians().sin().max(1e-3);
        let beam = (-self.extinction_per_m() * self.cloud_base_height_m() / sin_h).exp();
        Some((sun_direction(el, az), lux * beam / self.sky_illuminance_lux))
    }

    /// The sky's kind, with its sun.
    pub fn sky_kind(&self) -> Result<SkyKind> {
        let sun = self.sun_deg.map(|(el, az)| sun_direction(el, az));
        match self.sky {
            SkySpec::Overcast => Ok(SkyKind::Overcast),
            SkySpec::General(t) => SkyKind::general(t, sun),
        }
    }

    /// The normalised sky seen through this weather's haze below the cloud base.
    pub fn sky(&self) -> Result<Sky> {
        Sky::cached(
            self.sky_kind()?,
            self.extinction_per_m(),
            self.cloud_base_height_m(),
        )
    }

    /// The haze of a frame seen from `eye_height_m` above the ground with the airlight
    /// `airlight` (linear RGB in the frame's units: the sky's [`Sky::airlight`] times the
    /// viewpoint's share of the open sky's light, Yamamoto & Tadamura's Is = ks·E_hv; or a
    /// photo's own): σ, the airlight, and the cloud base's height above the eye, where sky
    /// pixels' paths end. None when σ = 0, so that clear weather returns the scene bit for bit.
    pub fn haze(&self, airlight: [f32; 3], eye_height_m: f64) -> Result<Option<Haze>> {
        let sigma = self.extinction_per_m();
        if sigma <= 0.0 {
            return Ok(None);
        }
        let ceiling = (self.cloud_base_height_m() - eye_height_m).max(0.0);
        let haze = Haze::new(sigma as f32, airlight, ceiling as f32)?;
        haze.with_drawn(self.drawn_extinction()).map(Some)
    }

    /// The extinction a frame draws as particles, taken off the haze near the eye: the rain's
    /// drops in the drawn bins within `rain_near_m` (when it draws streaks), the flakes of the
    /// drawn sizes within `snow_near_m`.
    pub fn drawn_extinction(&self) -> [Drawn; 2] {
        let rain = if self.draws_streaks() {
            Drawn {
                radius_m: self.rain_near_m as f32,
                extinction_per_m: (self.rain_extinction_per_m()
                    * drawn_share(self.falling_rain_mm_h(), &self.rain_diameters_mm))
                    as f32,
            }
        } else {
            Drawn::default()
        };
        let snow = if self.snow_rate_mm_h > 0.0 {
            let min_mm = crate::physics::snow::flake_melted_mm(FLAKE_DRAWN_MIN_MM);
            Drawn {
                radius_m: self.snow_near_m as f32,
                extinction_per_m: Snowfall::new(self.snow_rate_mm_h)
                    .extinction_between_per_m(min_mm, f64::INFINITY)
                    as f32,
            }
        } else {
            Drawn::default()
        };
        [rain, snow]
    }

    /// Whether the frame draws the rain near the camera as streaks.
    pub fn draws_streaks(&self) -> bool {
        self.falling_rain_mm_h() > 0.0 && self.rain_streaks
    }

    /// The rain region of a frame at `time_s` with `seed`, when it draws streaks.
    pub fn rain_region(&self, time_s: f64, seed: u64) -> Result<Option<RainRegion>> {
        if !self.draws_streaks() {
            return Ok(None);
        }
        self.region(time_s, seed).map(Some)
    }

    /// The drops' region around a camera at `time_s` with `seed` (whether or not a frame would
    /// draw them).
    pub fn region(&self, time_s: f64, seed: u64) -> Result<RainRegion> {
        let mut region = RainRegion::new(
            self.falling_rain_mm_h(),
            &self.rain_diameters_mm,
            self.rain_near_m,
            self.wind_m_s,
            time_s,
            seed,
        )?;
        region.method = self.rain_method;
        region.far_m = self.rain_far_m;
        Ok(region)
    }
}

impl SkySpec {
    /// `"overcast"`, or a CIE general sky type given as a number.
    pub fn from_type(sky_type: i64) -> Self {
        if sky_type == 0 {
            SkySpec::Overcast
        } else {
            SkySpec::General(sky_type)
        }
    }

    /// Parses the name of a sky (only `"overcast"` has one).
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "overcast" => Ok(SkySpec::Overcast),
            other => Err(Error::Invalid {
                param: Param {
                    name: "sky",
                    index: None,
                },
                message: format!("{other:?} must be \"overcast\" or a CIE general sky type 1-15"),
            }),
        }
    }
}

/// The drawn bins' share of the rain's extinction: [`crate::physics::extinction::bins_share`]
/// of the bins of `diameters_mm`; 0 for bins that cannot be made.
pub fn drawn_share(rain_rate_mm_h: f64, diameters_mm: &[f64]) -> f64 {
    let Ok(bins) = crate::rain::bins::diameter_bins(diameters_mm) else {
        return 0.0;
    };
    crate::physics::extinction::bins_share(rain_rate_mm_h, &bins)
}

impl TryFrom<&Weather> for crate::snow::cover::CoverWeather {
    type Error = Error;

    /// What the snow cover takes of `w`, once `w` is valid.
    fn try_from(w: &Weather) -> Result<Self> {
        w.validate()?;
        Ok(crate::snow::cover::CoverWeather {
            snow_rate_mm_h: w.snow_rate_mm_h,
            wind_m_s: w.wind_m_s,
            snow_density_kg_m3: w.snow_density_kg_m3,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn weather(rate: f64, visibility_m: f64) -> Weather {
        Weather {
            rain_rate_mm_h: rate,
            snow_rate_mm_h: 0.0,
            snow_density_kg_m3: 100.0,
            snow_near_m: 8.0,
            snow_opacity: SnowOpacity::Extinction,
            visibility_m,
            sky_illuminance_lux: 10_000.0,
            wind_m_s: [0.0; 3],
            rain_near_m: 5.0,
            rain_far_m: None,
            rain_diameters_mm: vec![1.0, 1.5, 2.0],
            rain_streaks: true,
            rain_method: RainMethod::Billboards,
            rain_sheltered: true,
            rain_duration_s: Some(0.0),
            dry_s: 0.0,
            sky: SkySpec::Overcast,
            sun_deg: None,
            cloud_base_m: None,
            sun_illuminance_lux: None,
        }
    }

    #[test]
    fn the_haze_is_koschmieder_plus_rain() {
        // Visibility V is where e^(−σ V) = 2 %: σ_air = −ln(0.02) / V.
        let w = weather(0.0, 1000.0);
        assert!(((-0.02f64.ln()) / 1000.0 - w.extinction_per_m()).abs() < 2e-7);
        assert!(
            weather(0.0, f64::INFINITY)
                .haze([0.4; 3], 0.0)
                .unwrap()
                .is_none()
        );
        let wet = weather(10.0, 2000.0);
        let want = KOSCHMIEDER / 2000.0 + rain_extinction_per_m(10.0);
        assert_eq!(wet.extinction_per_m(), want);
        let h = wet.haze([0.2, 0.3, 0.4], 1.6).unwrap().unwrap();
        assert_eq!(h.extinction_per_m, want as f32);
        assert_eq!(h.airlight, [0.2, 0.3, 0.4]);
        // sky pixels are hazed up to the cloud base, above the eye
        assert_eq!(h.sky_ceiling_m, (cloud_base_m(10.0) - 1.6) as f32);
    }

    #[test]
    fn snow_adds_its_own_extinction_to_the_haze() {
        let mut w = weather(2.0, 3000.0);
        let dry = w.extinction_per_m();
        assert_eq!(w.snow_extinction_per_m(), 0.0);
        assert!(w.snow_region(0.0, 1).unwrap().is_none());
        w.snow_rate_mm_h = 1.5;
        let sigma_snow = Snowfall::new(1.5).extinction_per_m();
        assert_eq!(w.snow_extinction_per_m(), sigma_snow);
        assert_eq!(w.extinction_per_m(), dry + sigma_snow);
        let r = w.snow_region(2.5, 7).unwrap().unwrap();
        assert_eq!((r.near_m, r.time_s, r.seed), (8.0, 2.5, 7));
        w.snow_near_m = 0.0;
        let e = w.validate().unwrap_err().to_string();
        assert!(e.starts_with("snow_near_m = 0"), "{e}");
    }

    #[test]
    fn the_drawn_share_is_the_bins_cross_section_over_the_whole() {
        // ∫ e^(−ΛD) D² over the bins over ∫ over [0, ∞) (= 2/Λ³), by the midpoint rule.
        let lam = crate::physics::dsd::mp_slope_per_mm(25.0);
        let n = 200_000;
        let numeric: f64 = [(0.9, 1.1), (1.1, 1.3)]
            .iter()
            .map(|&(lo, hi): &(f64, f64)| {
                let h = (hi - lo) / n as f64;
                (0..n)
                    .map(|k| {
                        let d = lo + (k as f64 + 0.5) * h;
                        (-lam * d).exp() * d * d * h
                    })
                    .sum::<f64>()
            })
            .sum::<f64>()
            * lam.powi(3)
            / 2.0;
        let share = drawn_share(25.0, &[1.0, 1.2]);
        assert!((share - numeric).abs() < 1e-9, "{share} vs {numeric}");
        let mut w = weather(25.0, 2000.0);
        w.rain_diameters_mm = vec![1.0, 1.2];
        let [rain, snow] = w.drawn_extinction();
        assert_eq!(rain.radius_m, 5.0);
        assert!(
            (f64::from(rain.extinction_per_m) / (w.rain_extinction_per_m() * numeric) - 1.0).abs()
                < 1e-6
        );
        assert_eq!(snow, Drawn::default());
        w.rain_streaks = false;
        assert_eq!(w.drawn_extinction()[0], Drawn::default());
    }

    #[test]
    fn the_cloud_base_and_the_rain_follow_the_weather() {
        let mut w = weather(10.0, f64::INFINITY);
        assert_eq!(w.cloud_base_height_m(), cloud_base_m(10.0));
        w.cloud_base_m = Some(700.0);
        assert_eq!(w.cloud_base_height_m(), 700.0);
        let r = w.rain_region(1.5, 3).unwrap().unwrap();
        assert_eq!(
            (r.rain_rate_mm_h, r.time_s, r.seed, r.method),
            (10.0, 1.5, 3, RainMethod::Billboards)
        );
        w.rain_streaks = false;
        assert!(w.rain_region(1.5, 3).unwrap().is_none());
        assert!(weather(0.0, 1.0).rain_region(0.0, 0).unwrap().is_none());
    }

    #[test]
    fn out_of_range_fields_are_named() {
        let mut w = weather(10.0, 1000.0);
        w.wind_m_s[2] = 61.0;
        let e = w.validate().unwrap_err().to_string();
        assert!(e.contains("wind_m_s[2]") && e.contains("61"), "{e}");
        let mut w = weather(10.0, 1000.0);
        w.sky = SkySpec::General(16);
        assert!(w.validate().unwrap_err().to_string().contains("sky"));
        assert!(SkySpec::parse("clear").is_err());
        assert_eq!(SkySpec::from_type(0), SkySpec::Overcast);
    }
}
