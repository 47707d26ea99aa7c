//! How much water lies on a surface: a bucket per surface, filled by the rain the surface
//! receives, spilling what it cannot hold, and emptied by evaporation after the rain stops.
//!
//! A surface of normal n receives the rain of open ground times its exposure, the mean over
//! three drops (the volume quartiles of Marshall & Palmer's distribution, falling at Beard's
//! terminal velocity and carried by the wind) of max(0, −n·v̂)/(−v̂_y), and none of a drop's
//! share where a box lies up its path (the rain's shelter: under an awning, under a box, the
//! lee of a wall in a wind).
//!
//! The constants are documented choices, not measurements of one road:
//! - [`STORAGE_MM`]: the depression storage of an impervious surface, 1 mm (hydrology
//!   manuals give 0.5–2.5 mm for pavement); what falls beyond it runs off.
//! - [`WET_FILM_MM`]: the film at which a surface reads fully wet, 0.2 mm (road-weather
//!   sensors call a road wet above about 0.1–0.2 mm of water); below it the wetness is
//!   the film's share of it, as patches that join.
//! - [`DRYING_MM_H`]: evaporation from a wet road after the rain, 0.25 mm/h (of the order of a
//!   cool, overcast day's potential evaporation): a fully wet road needs 4 h to dry.

use crate::physics::fall_speed::FallSpeed;
use glam::Vec3;

/// Water a surface holds before the rest runs off, mm.
pub const STORAGE_MM: f64 = 1.0;

/// The film at which a surface reads fully wet, mm.
pub const WET_FILM_MM: f64 = 0.2;

/// Evaporation from a wet surface after the rain, mm/h.
pub const DRYING_MM_H: f64 = 0.25;

/// Exposures below this are no rain at all: a face that receives under 0.1 % of open ground's
/// rain (a wall in a calm, a photo's upright surface whose normal the depth map tilts by a
/// hair) stays dry even after a long rain.
pub const MIN_EXPOSURE: f64 = 1e-3;

/// Quantiles ΛD of the volume quartiles of Marshall & Palmer's distribution (the water
/// volume in D³e^(−ΛD) dD is a gamma(4) distribution in ΛD: its quartiles).
const VOLUME_QUARTILES: [f64; 3] = [2.5353, 3.6721, 5.1094];

/// The rain a scene's surfaces have received: its rate, for how long, and how long ago it
/// stopped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Film {
    /// The rain's rate, mm/h.
    pub rate_mm_h: f64,
    /// How long it rained, s; None: long enough to fill every exposed surface.
    pub duration_s: Option<f64>,
    /// How long ago it stopped, s (0: it is raining).
    pub dry_s: f64,
}

impl Film {
    /// Water on a surface of `exposure` (its rain over open ground's), mm.
    pub fn water_mm(&self, exposure: f64) -> f64 {
        if exposure < MIN_EXPOSURE {
            return 0.0;
        }
        let received = self.rate_mm_h * exposure;
        let filled = if received <= 0.0 {
            0.0
        } else {
            match self.duration_s {
                None => STORAGE_MM,
                Some(t) => (received * t / 3600.0).min(STORAGE_MM),
            }
        };
        (filled - DRYING_MM_H * self.dry_s / 3600.0).max(0.0)
    }

    /// The wetness of a surface of `exposure`, 0–1: its water over [`WET_FILM_MM`], at most 1.
    pub fn wetness(&self, exposure: f64) -> f32 {
        (self.water_mm(exposure) / WET_FILM_MM).min(1.0) as f32
    }

    /// Whether any surface is wet at all.
    pub fn any(&self) -> bool {
        self.wetness(1.0) > 0.0 || self.wetness(RAIN_EXPOSURE_MAX) > 0.0
    }
}

/// The largest exposure a face can have (a wall facing a gale's rain), for [`Film::any`].
const RAIN_EXPOSURE_MAX: f64 = 50.0;

/// The rain's directions of fall (unit, downwards), one per volume quartile drop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RainDirections(pub [Vec3; 3]);

impl RainDirections {
    /// The directions of the quartile drops of rain at `rate_mm_h` in the wind `wind_m_s`
    /// (straight down without rain).
    pub fn new(rate_mm_h: f64, wind_m_s: [f64; 3]) -> Self {
        let law = FallSpeed::beard_standard();
        let lam = crate::physics::dsd::mp_slope_per_mm(rate_mm_h.max(1e-3));
        let wind = Vec3::new(wind_m_s[0] as f32, wind_m_s[1] as f32, wind_m_s[2] as f32);
        RainDirections(VOLUME_QUARTILES.map(|q| {
            let v = wind - Vec3::Y * law.m_s(q / lam) as f32;
            if v.y < 0.0 { v.normalize() } else { -Vec3::Y }
        }))
    }

    /// The exposure of a face of unit normal `n` at `p` (see the module docs): each drop's
    /// max(0, −n·v̂)/(−v̂_y), zero where `sheltered(p, −v̂)` (a box up its path), averaged.
    pub fn exposure(&self, n: Vec3, sheltered: impl Fn(Vec3) -> bool) -> f64 {
        let mut sum = 0.0;
        for v in self.0 {
            let hit = -n.dot(v);
            if hit > 0.0 && !sheltered(-v) {
                sum += f64::from(hit / -v.y);
            }
        }
        sum / 3.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_quartiles_split_a_gamma_4_in_four() {
        // P(4, x) = 1 - e^-x (1 + x + x²/2 + x³/6)
        for (q, want) in VOLUME_QUARTILES.iter().zip([0.25, 0.5, 0.75]) {
            let p = 1.0 - (-q).exp() * (1.0 + q + q * q / 2.0 + q * q * q / 6.0);
            assert!((p - want).abs() < 1e-4, "{q}: {p}");
        }
    }

    #[test]
    fn water_fills_to_the_storage_and_dries_linearly() {
        let f = |t: Option<f64>, dry: f64| Film {
            rate_mm_h: 2.0,
            duration_s: t,
            dry_s: dry,
        };
        // 2 mm/h for 3 min: 0.1 mm, half the wet film
        assert!((f(Some(180.0), 0.0).water_mm(1.0) - 0.1).abs() < 1e-12);
        assert!((f(Some(180.0), 0.0).wetness(1.0) - 0.5).abs() < 1e-6);
        assert_eq!(f(Some(7200.0), 0.0).water_mm(1.0), STORAGE_MM);
        assert_eq!(f(None, 0.0).water_mm(1.0), STORAGE_MM);
        assert_eq!(f(Some(0.0), 0.0).wetness(1.0), 0.0);
        assert_eq!(f(None, 0.0).wetness(0.0), 0.0);
        assert_eq!(f(None, 0.0).wetness(0.5 * MIN_EXPOSURE), 0.0);
        assert_eq!(f(None, 0.0).wetness(MIN_EXPOSURE), 1.0);
        // drying: monotone, dry after STORAGE / DRYING hours
        let mut last = f32::INFINITY;
        for k in 0..=40 {
            let w = f(None, f64::from(k) * 600.0).wetness(1.0);
            assert!(w <= last);
            last = w;
        }
        let dry_after = STORAGE_MM / DRYING_MM_H * 3600.0;
        assert!(f(None, dry_after - 60.0).wetness(1.0) > 0.0);
        assert_eq!(f(None, dry_after).wetness(1.0), 0.0);
        assert!(!f(None, dry_after).any());
    }

    #[test]
    fn open_ground_has_exposure_one_and_walls_only_in_a_wind() {
        let calm = RainDirections::new(5.0, [0.0; 3]);
        assert!((calm.exposure(Vec3::Y, |_| false) - 1.0).abs() < 1e-6);
        assert_eq!(calm.exposure(Vec3::Z, |_| false), 0.0);
        assert_eq!(calm.exposure(Vec3::Y, |_| true), 0.0);
        // In a 4 m/s wind along +x, a wall facing -x (into the wind) gets |v_h|/v_t of the
        // ground's rain per drop; the wall facing +x none.
        let windy = RainDirections::new(5.0, [4.0, 0.0, 0.0]);
        let law = FallSpeed::beard_standard();
        let lam = crate::physics::dsd::mp_slope_per_mm(5.0);
        let want: f64 = VOLUME_QUARTILES
            .iter()
            .map(|q| 4.0 / law.m_s(q / lam))
            .sum::<f64>()
            / 3.0;
        assert!((windy.exposure(-Vec3::X, |_| false) - want).abs() < 1e-4);
        assert_eq!(windy.exposure(Vec3::X, |_| false), 0.0);
        assert!((windy.exposure(Vec3::Y, |_| false) - 1.0).abs() < 1e-6);
    }
}
