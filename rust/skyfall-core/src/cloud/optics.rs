//! Droplet optics of the cloud kinds, from Mie theory at 550 nm (miepython 3.3 over a
//! modified-gamma size distribution, v_eff = 0.1; `tests/data/cloud_optics.json` holds the
//! table with its source), and the Henyey–Greenstein phase function.

use std::f64::consts::PI;

/// Density of liquid water, kg/m³.
pub const WATER_DENSITY_KG_M3: f64 = 1000.0;

/// One droplet population: its effective radius, liquid water content and Mie properties.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Droplets {
    /// Effective radius r_eff, µm.
    pub reff_um: f64,
    /// Liquid water content, g/m³.
    pub lwc_g_m3: f64,
    /// Extinction efficiency Q_ext.
    pub q_ext: f64,
    /// Single-scattering albedo.
    pub albedo: f64,
    /// Asymmetry parameter g.
    pub g: f64,
}

impl Droplets {
    /// Extinction coefficient β = 3 Q_ext LWC / (4 ρ_w r_eff), 1/m (Stephens 1978's
    /// β = 3 LWC/(2 ρ_w r_eff) with Q_ext = 2 made general).
    pub fn extinction_per_m(&self) -> f64 {
        let lwc_kg_m3 = self.lwc_g_m3 * 1e-3;
        let reff_m = self.reff_um * 1e-6;
        0.75 * self.q_ext * lwc_kg_m3 / (WATER_DENSITY_KG_M3 * reff_m)
    }
}

/// Stratocumulus: small droplets, little water (r_eff 5 µm, LWC 0.1 g/m³).
pub const STRATOCUMULUS: Droplets = Droplets {
    reff_um: 5.0,
    lwc_g_m3: 0.1,
    q_ext: 2.1433,
    albedo: 0.999_999_766_200_044,
    g: 0.8494,
};
/// A broken field of fair-weather cumulus (r_eff 15 µm, LWC 0.5 g/m³).
pub const BROKEN: Droplets = Droplets {
    reff_um: 15.0,
    lwc_g_m3: 0.5,
    q_ext: 2.0687,
    albedo: 0.999_999_352_030_438_1,
    g: 0.8697,
};
/// A cumulus congestus (r_eff 10 µm, LWC 1 g/m³).
pub const CUMULUS: Droplets = Droplets {
    reff_um: 10.0,
    lwc_g_m3: 1.0,
    q_ext: 2.0896,
    albedo: 0.999_999_578_139_004_3,
    g: 0.8641,
};

/// Henyey–Greenstein phase function p(cos θ) = (1 − g²) / (4π (1 + g² − 2 g cos θ)^1.5),
/// 1/sr (its integral over the sphere is 1).
pub fn henyey_greenstein(cos_theta: f64, g: f64) -> f64 {
    let d = 1.0 + g * g - 2.0 * g * cos_theta;
    (1.0 - g * g) / (4.0 * PI * d * d.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extinction_matches_the_reference_table() {
        // beta_ext_m-1 of the table's cases (tests/data/cloud_optics.json).
        assert!((STRATOCUMULUS.extinction_per_m() - 0.0321).abs() < 1e-4);
        assert!((BROKEN.extinction_per_m() - 0.0517).abs() < 1e-4);
        assert!((CUMULUS.extinction_per_m() - 0.1567).abs() < 1e-4);
    }

    #[test]
    fn phase_is_normalised() {
        let n = 20_000;
        let s: f64 = (0..n)
            .map(|i| {
                let mu = -1.0 + (i as f64 + 0.5) * 2.0 / n as f64;
                henyey_greenstein(mu, 0.86) * 2.0 * PI * 2.0 / n as f64
            })
            .sum();
        assert!((s - 1.0).abs() < 1e-3, "{s}");
    }
}
