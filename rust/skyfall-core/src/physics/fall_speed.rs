//! Terminal fall speed of raindrops: three models, vectorised.
//!
//! - [`FallSpeedModel::Sphere`]: Yoshida, Dobashi & Yamamoto's rigid-sphere force balance ([`super::drag`]).
//!   Good below ~1.4 mm; overestimates large drops, which flatten.
//! - [`FallSpeedModel::Beard`] (default): Beard 1976, three regimes (Table 1 of the paper,
//!   coefficients as in the shared reference), which follows drop deformation through the
//!   Bond and physical-property numbers; air enters through density, viscosity, mean free
//!   path and surface tension.
//! - [`FallSpeedModel::Atlas`]: Atlas, Srivastava & Sekhon 1973, v = 9.65 − 10.3 e^(−0.6 D)
//!   (clipped at 0 below 0.109 mm), a fit to Gunn & Kinzer at their laboratory air, scaled
//!   to other air by Foote & du Toit 1969: v · (ρ0 / ρ)^0.4.
//!
//! Valid diameters: [0, 8] mm ([`DIAMETER_MM`]). Drops above ~8 mm break up in air; Beard's
//! regime 3 is fitted to 7 mm and its formula is used unchanged from 7 to 8 mm, where it
//! stays within 0.6 % of 9.15 m/s. D = 0 gives 0.

use super::GRAVITY_M_S2;
use super::air::{Air, AirProps};
use super::drag::sphere_reynolds;
use crate::error::{Error, Param, Range, Result, at, broadcast_len};
use rayon::prelude::*;

/// Valid drop diameters, mm.
pub const DIAMETER_MM: Range = crate::ranges::DIAMETER_MM.range;

/// Which terminal-velocity law to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FallSpeedModel {
    /// Rigid sphere, piecewise Cd(Re) (Yoshida, Dobashi & Yamamoto).
    Sphere,
    /// Beard 1976 (deformation-aware; default).
    Beard,
    /// Atlas et al. 1973 fit with the Foote–du Toit density correction.
    Atlas,
}

impl FallSpeedModel {
    /// Names accepted by [`FallSpeedModel::parse`].
    pub const NAMES: [&'static str; 3] = ["beard", "sphere", "atlas"];

    /// Parses a model name.
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "beard" => Ok(Self::Beard),
            "sphere" => Ok(Self::Sphere),
            "atlas" => Ok(Self::Atlas),
            other => Err(Error::Invalid {
                param: Param {
                    name: "model",
                    index: None,
                },
                message: format!("unknown model {other:?}; expected one of {:?}", Self::NAMES),
            }),
        }
    }
}

/// Beard 1976 regime 2 coefficients (19 µm ≤ d < 1.07 mm): ln Re = Σ bₙ Xⁿ, X = ln(Cd Re²).
const BEARD_B2: [f64; 7] = [
    -3.18657,
    0.992696,
    -0.00153193,
    -0.000987059,
    -0.000578878,
    8.55176e-5,
    -3.27815e-6,
];
/// Beard 1976 regime 3 coefficients (1.07 mm ≤ d ≤ 7 mm): Y = Σ bₙ Xⁿ, X = ln(Bo · Np^(1/6)).
const BEARD_B3: [f64; 6] = [
    -5.00015, 5.23778, -2.04914, 0.475294, -0.0542819, 0.00238449,
];

fn poly(b: &[f64], x: f64) -> f64 {
    b.iter().rev().fold(0.0, |acc, &c| acc * x + c)
}

/// A fall-speed law bound to one air state, with every per-air constant computed once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FallSpeed {
    model: FallSpeedModel,
    /// η / ρa: turns Re·(1/d) into a speed, m²/s.
    nu: f64,
    /// Mean free path, m.
    mfp: f64,
    /// Δρ g / (18 η): Stokes speed per d², 1/(m·s).
    stokes: f64,
    /// Best number per d³: 4 ρa Δρ g / (3 η²), 1/m³.
    best_per_d3: f64,
    /// Bond number per d²: 4 Δρ g / (3 σ), 1/m².
    bond_per_d2: f64,
    /// Np^(1/6), the physical-property number of Beard's regime 3.
    np6: f64,
    /// Foote–du Toit factor (ρ0/ρ)^0.4 for the Atlas fit.
    atlas_factor: f64,
}

impl FallSpeed {
    /// Beard's law at standard air ([`crate::physics::air::Air::STANDARD`]), the law the
    /// rain is drawn with: built once per process.
    pub fn beard_standard() -> &'static FallSpeed {
        static LAW: std::sync::OnceLock<FallSpeed> = std::sync::OnceLock::new();
        LAW.get_or_init(|| {
            FallSpeed::new(
                FallSpeedModel::Beard,
                &crate::physics::air::Air::STANDARD.props(),
            )
        })
    }

    /// Binds `model` to the air described by `air`.
    pub fn new(model: FallSpeedModel, air: &AirProps) -> Self {
        let rho = air.density_kg_m3;
        let eta = air.viscosity_pa_s;
        let sigma = air.surface_tension_n_m;
        let drho = air.water_density_kg_m3 - rho;
        let np = sigma.powi(3) * rho * rho / (eta.powi(4) * drho * GRAVITY_M_S2);
        FallSpeed {
            model,
            nu: eta / rho,
            mfp: air.mean_free_path_m,
            stokes: drho * GRAVITY_M_S2 / (18.0 * eta),
            best_per_d3: 4.0 * rho * drho * GRAVITY_M_S2 / (3.0 * eta * eta),
            bond_per_d2: 4.0 * drho * GRAVITY_M_S2 / (3.0 * sigma),
            np6: np.powf(1.0 / 6.0),
            atlas_factor: (Air::STANDARD.density_kg_m3() / rho).powf(0.4),
        }
    }

    /// Terminal velocity, m/s, of a drop of `diameter_mm` (not validated; D ≤ 0 gives 0).
    pub fn m_s(&self, diameter_mm: f64) -> f64 {
        let d = diameter_mm * 1e-3;
        if d <= 0.0 {
            return 0.0;
        }
        match self.model {
            FallSpeedModel::Sphere => self.nu * sphere_reynolds(self.best_per_d3 * d.powi(3)).0 / d,
            FallSpeedModel::Beard => self.beard(d),
            FallSpeedModel::Atlas => {
                (9.65 - 10.3 * (-0.6 * diameter_mm).exp()).max(0.0) * self.atlas_factor
            }
        }
    }

    /// Beard 1976, diameter in metres.
    fn beard(&self, d: f64) -> f64 {
        if d < 19e-6 {
            // Regime 1: Stokes with slip correction, d² (1 + 2.51 l/d) written as d (d + 2.51 l)
            // so subnormal diameters neither overflow nor give NaN.
            self.stokes * d * (d + 2.51 * self.mfp)
        } else if d < 1.07e-3 {
            let slip = 1.0 + 2.51 * self.mfp / d;
            let re = slip * poly(&BEARD_B2, (self.best_per_d3 * d.powi(3)).ln()).exp();
            self.nu * re / d
        } else {
            let re = self.np6 * poly(&BEARD_B3, (self.bond_per_d2 * d * d * self.np6).ln()).exp();
            self.nu * re / d
        }
    }
}

/// Terminal velocity, m/s, of one drop of `diameter_mm` (not validated). For many drops in
/// the same air, build one [`FallSpeed`] instead.
pub fn terminal_velocity_m_s(diameter_mm: f64, model: FallSpeedModel, air: &AirProps) -> f64 {
    FallSpeed::new(model, air).m_s(diameter_mm)
}

/// Air given as broadcastable arrays (each of length 1 or n).
#[derive(Debug, Clone, Copy)]
pub struct AirArrays<'a> {
    /// °C.
    pub temperature_c: &'a [f64],
    /// hPa.
    pub pressure_hpa: &'a [f64],
    /// Fraction.
    pub relative_humidity: &'a [f64],
}

impl AirArrays<'_> {
    /// Length of the broadcast of these arrays with another of length `n`.
    pub fn broadcast_with(&self, others: &[(&'static str, usize)]) -> Result<usize> {
        let mut all = vec![
            ("temperature_c", self.temperature_c.len()),
            ("pressure_hpa", self.pressure_hpa.len()),
            ("relative_humidity", self.relative_humidity.len()),
        ];
        all.extend_from_slice(others);
        broadcast_len(&all)
    }

    fn is_scalar(&self) -> bool {
        self.temperature_c.len() == 1
            && self.pressure_hpa.len() == 1
            && self.relative_humidity.len() == 1
    }

    /// Validates every element; returns the properties when all three are scalars.
    pub fn validate(&self, n: usize) -> Result<Option<AirProps>> {
        if self.is_scalar() {
            return Ok(Some(
                Air::new(
                    self.temperature_c[0],
                    self.pressure_hpa[0],
                    self.relative_humidity[0],
                )?
                .props(),
            ));
        }
        for i in 0..n {
            Air::checked(
                at(self.temperature_c, i),
                at(self.pressure_hpa, i),
                at(self.relative_humidity, i),
                Some(i),
            )?;
        }
        Ok(None)
    }

    /// Properties at element `i` (after [`AirArrays::validate`]).
    pub fn props_at(&self, i: usize) -> AirProps {
        Air {
            temperature_c: at(self.temperature_c, i),
            pressure_hpa: at(self.pressure_hpa, i),
            relative_humidity: at(self.relative_humidity, i),
        }
        .props()
    }
}

/// Inputs above this length are split across threads.
pub const PARALLEL_MIN_LEN: usize = 1 << 14;

/// Terminal velocity, m/s, for arrays of length 1 or n (broadcast).
/// Validates everything first; elementwise, so the result does not depend on threading.
pub fn terminal_velocity_many(
    diameter_mm: &[f64],
    model: FallSpeedModel,
    air: AirArrays<'_>,
) -> Result<Vec<f64>> {
    let n = air.broadcast_with(&[("diameter_mm", diameter_mm.len())])?;
    DIAMETER_MM.check_all("diameter_mm", diameter_mm)?;
    let fixed = air.validate(n)?.map(|props| FallSpeed::new(model, &props));
    let one = |i: usize| {
        let law = fixed.unwrap_or_else(|| FallSpeed::new(model, &air.props_at(i)));
        law.m_s(at(diameter_mm, i))
    };
    let mut out = vec![0.0; n];
    if n >= PARALLEL_MIN_LEN {
        out.par_iter_mut()
            .enumerate()
            .for_each(|(i, o)| *o = one(i));
    } else {
        out.iter_mut().enumerate().for_each(|(i, o)| *o = one(i));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(d_mm: f64, m: FallSpeedModel) -> f64 {
        terminal_velocity_m_s(d_mm, m, &Air::STANDARD.props())
    }

    #[test]
    fn beard_matches_gunn_kinzer_spot_values() {
        // Gunn & Kinzer 1949 Table 2 (tests/data/gunn_kinzer_1949_fall_speed.csv).
        for &(d, gk) in &[
            (0.5, 2.06),
            (1.0, 4.03),
            (2.0, 6.49),
            (3.0, 8.06),
            (4.0, 8.83),
            (5.8, 9.17),
        ] {
            let rel = (v(d, FallSpeedModel::Beard) - gk) / gk;
            assert!(rel.abs() < 0.025, "D={d} rel={rel}");
        }
    }

    #[test]
    fn every_model_is_finite_monotone_and_bounded() {
        for m in [
            FallSpeedModel::Sphere,
            FallSpeedModel::Beard,
            FallSpeedModel::Atlas,
        ] {
            let mut prev = 0.0;
            for k in 0..=8000 {
                let d = k as f64 * 1e-3;
                let s = v(d, m);
                assert!(
                    s.is_finite() && (0.0..20.0).contains(&s),
                    "{m:?} D={d} v={s}"
                );
                assert!(
                    s >= prev - 0.05 * prev,
                    "{m:?} not monotone at D={d}: {prev} -> {s}"
                );
                prev = s;
            }
        }
    }

    #[test]
    fn thinner_air_falls_faster() {
        let high = Air::new(0.0, 700.0, 0.5)
            .map(|a| a.props())
            .unwrap_or(Air::STANDARD.props());
        for m in [
            FallSpeedModel::Sphere,
            FallSpeedModel::Beard,
            FallSpeedModel::Atlas,
        ] {
            assert!(terminal_velocity_m_s(2.0, m, &high) > v(2.0, m));
        }
    }

    #[test]
    fn broadcasting_and_validation() {
        let d = [1.0, 2.0, 3.0];
        let air = AirArrays {
            temperature_c: &[20.0],
            pressure_hpa: &[1013.25, 900.0, 800.0],
            relative_humidity: &[0.5],
        };
        let out = terminal_velocity_many(&d, FallSpeedModel::Beard, air);
        assert!(matches!(out, Ok(ref o) if o.len() == 3));
        let bad = terminal_velocity_many(
            &[1.0, -1.0],
            FallSpeedModel::Beard,
            AirArrays {
                temperature_c: &[20.0],
                pressure_hpa: &[1013.25],
                relative_humidity: &[0.5],
            },
        );
        let msg = bad.err().map(|e| e.to_string()).unwrap_or_default();
        assert!(
            msg.contains("diameter_mm[1]") && msg.contains("[0, 8] mm"),
            "{msg}"
        );
        assert!(FallSpeedModel::parse("nope").is_err());
    }
}
