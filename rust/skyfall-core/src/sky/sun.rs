//! The sun's direct light: its normal illuminance at the ground under a clear sky.
//!
//! E_vsn = E_vo · exp(−a_v m T_il) (Navvab, Karayel, Ne'eman & Selkowitz, *Analysis of
//! atmospheric turbidity for daylight calculations*, 1984, as given in Tregenza & Sharples'
//! daylight algorithms): E_vo = 133.8 klx the mean extraterrestrial solar illuminance,
//! a_v = 1/(9.9 + 0.043 m) the luminous extinction coefficient of clean dry air, m the relative
//! optical air mass (Kasten & Young 1989), T_il the illuminance turbidity factor
//! ([`CLEAR_TURBIDITY`]).

/// The mean extraterrestrial solar illuminance, lux.
pub const EXTRATERRESTRIAL_LUX: f64 = 133_800.0;

/// Illuminance turbidity factor of a clear sky (2–3 for clean air, 3–4 in cities); with it a
/// sun 45° up gives 87 klx.
pub const CLEAR_TURBIDITY: f64 = 3.0;

/// Relative optical air mass at `elevation_deg` (Kasten & Young, *Revised optical air mass
/// tables and approximation formula*, 1989): 1 at the zenith, about 38 at the horizon.
pub fn air_mass(elevation_deg: f64) -> f64 {
    let h = elevation_deg.clamp(0.0, 90.0);
    1.0 / (h.to_radians().sin() + 0.50572 * (h + 6.07995).powf(-1.6364))
}

/// The clear sky's direct normal illuminance of a sun at `elevation_deg`, lux.
pub fn clear_sky_sun_lux(elevation_deg: f64) -> f64 {
    let m = air_mass(elevation_deg);
    let a_v = 1.0 / (9.9 + 0.043 * m);
    EXTRATERRESTRIAL_LUX * (-a_v * m * CLEAR_TURBIDITY).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn air_mass_is_the_secant_high_and_finite_at_the_horizon() {
        // Kasten & Young's table: 1.0 at the zenith, 38.09 at the horizon (their formula is
        // within 0.5 % of it), within 0.5 % of the secant above 30°.
        assert!((air_mass(90.0) - 1.0).abs() < 1e-3);
        assert!(
            (air_mass(0.0) / 38.09 - 1.0).abs() < 5e-3,
            "{}",
            air_mass(0.0)
        );
        for h in [30.0f64, 45.0, 60.0] {
            let sec = 1.0 / h.to_radians().sin();
            assert!((air_mass(h) / sec - 1.0).abs() < 5e-3, "{h}");
        }
    }

    #[test]
    fn clear_sky_sun_is_the_published_order_of_magnitude() {
        // A high summer sun gives about 100 klx at the ground; a low one a few klx.
        let high = clear_sky_sun_lux(60.0);
        assert!((85_000.0..110_000.0).contains(&high), "{high}");
        assert!(clear_sky_sun_lux(5.0) < 0.3 * high);
        assert!(clear_sky_sun_lux(30.0) < clear_sky_sun_lux(45.0));
    }
}
