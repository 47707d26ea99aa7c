//! Moist air and liquid water: density, viscosity, mean free path, surface tension.
//!
//! Formulas as used with Beard (1976, 1977): Beard 1977 viscosity, Kell 1975 water density,
//! Pruppacher & Klett surface tension, Wexler/Hardy (ITS-90) saturation vapour pressure.

use crate::error::{Error, Param, Range, Result};

/// Valid air temperature, °C (Beard's viscosity law and the supercooled-water formulas).
pub const TEMPERATURE_C: Range = crate::ranges::TEMPERATURE_C.range;
/// Valid air pressure, hPa (sea level down to about 20 km altitude).
pub const PRESSURE_HPA: Range = crate::ranges::PRESSURE_HPA.range;
/// Valid relative humidity, as a fraction.
pub const RELATIVE_HUMIDITY: Range = crate::ranges::RELATIVE_HUMIDITY.range;

/// Specific gas constant of dry air, J/(kg·K).
const R_DRY_J_KG_K: f64 = 287.04;
const KELVIN: f64 = 273.15;

/// The state of the air a drop falls through.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Air {
    /// Temperature, °C.
    pub temperature_c: f64,
    /// Pressure, hPa.
    pub pressure_hpa: f64,
    /// Relative humidity, fraction in [0, 1].
    pub relative_humidity: f64,
}

/// Derived properties of [`Air`] and of liquid water at the same temperature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AirProps {
    /// Moist-air density, kg/m³.
    pub density_kg_m3: f64,
    /// Dynamic viscosity of air, Pa·s.
    pub viscosity_pa_s: f64,
    /// Mean free path of air molecules, m.
    pub mean_free_path_m: f64,
    /// Liquid-water density, kg/m³.
    pub water_density_kg_m3: f64,
    /// Water–air surface tension, N/m.
    pub surface_tension_n_m: f64,
}

impl Air {
    /// Gunn & Kinzer's laboratory air: 20 °C, 1013.25 hPa, 50 % relative humidity.
    pub const STANDARD: Air = Air {
        temperature_c: 20.0,
        pressure_hpa: 1013.25,
        relative_humidity: 0.5,
    };

    /// Validated air state.
    pub fn new(temperature_c: f64, pressure_hpa: f64, relative_humidity: f64) -> Result<Self> {
        Self::checked(temperature_c, pressure_hpa, relative_humidity, None)
    }

    /// Validated air state; `index` names the array element in messages.
    /// Besides the ranges, the water-vapour pressure RH·e_s(T) must stay below the total
    /// pressure (warm saturated air at high altitude does not exist: water boils).
    pub fn checked(
        temperature_c: f64,
        pressure_hpa: f64,
        relative_humidity: f64,
        index: Option<usize>,
    ) -> Result<Self> {
        let air = Air {
            temperature_c: TEMPERATURE_C.check("temperature_c", index, temperature_c)?,
            pressure_hpa: PRESSURE_HPA.check("pressure_hpa", index, pressure_hpa)?,
            relative_humidity: RELATIVE_HUMIDITY.check(
                "relative_humidity",
                index,
                relative_humidity,
            )?,
        };
        let e_hpa = relative_humidity * saturation_vapour_pressure_pa(temperature_c) / 100.0;
        if e_hpa >= pressure_hpa {
            return Err(Error::Invalid {
                param: Param {
                    name: "relative_humidity",
                    index,
                },
                message: format!(
                    "relative_humidity = {relative_humidity} at {temperature_c} °C means a vapour pressure of {e_hpa:.1} hPa, \
                     not below pressure_hpa = {pressure_hpa}: no such air"
                ),
            });
        }
        Ok(air)
    }

    /// Moist-air density, kg/m³: ρ = (p − 0.378 e) / (R_d T), e = RH · e_s(T).
    pub fn density_kg_m3(&self) -> f64 {
        let p_pa = self.pressure_hpa * 100.0;
        let e_pa = self.relative_humidity * saturation_vapour_pressure_pa(self.temperature_c);
        (p_pa - 0.378 * e_pa) / (R_DRY_J_KG_K * (self.temperature_c + KELVIN))
    }

    /// Dynamic viscosity of air, Pa·s (Beard 1977, as in Pruppacher & Klett).
    pub fn viscosity_pa_s(&self) -> f64 {
        air_viscosity_pa_s(self.temperature_c)
    }

    /// Mean free path, m: l = l0 (η/η0)(p0/p)(T/T0)^½ with l0 = 6.62e-8 m at 20 °C, 1013.25 hPa.
    pub fn mean_free_path_m(&self) -> f64 {
        let eta0 = air_viscosity_pa_s(20.0);
        6.62e-8
            * (self.viscosity_pa_s() / eta0)
            * (1013.25 / self.pressure_hpa)
            * ((self.temperature_c + KELVIN) / 293.15).sqrt()
    }

    /// Every derived property at once.
    pub fn props(&self) -> AirProps {
        AirProps {
            density_kg_m3: self.density_kg_m3(),
            viscosity_pa_s: self.viscosity_pa_s(),
            mean_free_path_m: self.mean_free_path_m(),
            water_density_kg_m3: water_density_kg_m3(self.temperature_c),
            surface_tension_n_m: water_surface_tension_n_m(self.temperature_c),
        }
    }
}

/// Dynamic viscosity of air, Pa·s, from temperature in °C (Beard 1977):
/// (1.721 + 0.00487 T)·1e-5 for T ≥ 0, (1.718 + 0.0049 T − 1.2e-5 T²)·1e-5 below.
pub fn air_viscosity_pa_s(temperature_c: f64) -> f64 {
    let t = temperature_c;
    if t >= 0.0 {
        (1.721 + 0.00487 * t) * 1e-5
    } else {
        (1.718 + 0.0049 * t - 1.2e-5 * t * t) * 1e-5
    }
}

/// Saturation vapour pressure over liquid water, Pa (Wexler 1976 in Hardy's ITS-90 form).
pub fn saturation_vapour_pressure_pa(temperature_c: f64) -> f64 {
    const G: [f64; 8] = [
        -2.8365744e3,
        -6.028076559e3,
        1.954263612e1,
        -2.737830188e-2,
        1.6261698e-5,
        7.0229056e-10,
        -1.8680009e-13,
        2.7150305,
    ];
    let t = temperature_c + KELVIN;
    let mut ln_es = G[7] * t.ln();
    let mut tp = t.powi(-2);
    for g in &G[..7] {
        ln_es += g * tp;
        tp *= t;
    }
    ln_es.exp()
}

/// Density of liquid water, kg/m³ (Kell 1975), valid for supercooled water too.
pub fn water_density_kg_m3(temperature_c: f64) -> f64 {
    let t = temperature_c;
    let num = 999.83952
        + t * (16.945176
            + t * (-7.9870401e-3 + t * (-46.170461e-6 + t * (105.56302e-9 + t * -280.54253e-12))));
    num / (1.0 + 16.879850e-3 * t)
}

/// Surface tension of water against air, N/m (Pruppacher & Klett: 0.0761 − 0.000155 T).
pub fn water_surface_tension_n_m(temperature_c: f64) -> f64 {
    0.0761 - 0.000155 * temperature_c
}

#[cfg(test)]
mod tests {
    use super::*;

    // Values at 20 °C, 1013.25 hPa, 50 % RH, derived from the same formulas in the
    // shared reference (drag_and_fluid_properties.json, fall_speed_fits.json).
    #[test]
    fn standard_air_matches_reference() {
        let p = Air::STANDARD.props();
        assert!(
            (p.density_kg_m3 - 1.19891).abs() < 2e-4,
            "{}",
            p.density_kg_m3
        );
        assert!((p.viscosity_pa_s - 1.8184e-5).abs() < 1e-9);
        assert!((p.water_density_kg_m3 - 998.204).abs() < 0.01);
        assert!((p.surface_tension_n_m - 0.0730).abs() < 1e-4);
        assert!((saturation_vapour_pressure_pa(20.0) - 2338.54).abs() < 2.0);
    }

    #[test]
    fn dry_air_is_ideal_gas() {
        let a = Air::new(20.0, 1013.25, 0.0).unwrap_or(Air::STANDARD);
        assert!((a.density_kg_m3() - 101325.0 / (287.04 * 293.15)).abs() < 1e-12);
    }

    #[test]
    fn rejects_bad_air() {
        assert!(Air::new(f64::NAN, 1000.0, 0.5).is_err());
        assert!(Air::new(20.0, 0.0, 0.5).is_err());
        assert!(Air::new(20.0, 1000.0, 1.5).is_err());
        // 50 °C saturated air holds 123 hPa of vapour: impossible at 50 hPa.
        assert!(Air::new(50.0, 50.0, 1.0).is_err() && Air::new(50.0, 150.0, 1.0).is_ok());
    }
}
