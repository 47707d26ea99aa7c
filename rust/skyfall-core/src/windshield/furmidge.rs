//! When a drop on inclined glass slides: Furmidge's criterion (1962) for a spherical-cap drop.
//!
//! A drop of volume V on a plane tilted α from the horizontal stays pinned while its weight
//! along the plane is below the contact line's retention, ρ g V sin α < k σ w (cos θ_R − cos θ_A),
//! with w = 2a the contact width (a the base radius), k the shape factor (1 here), θ_A and θ_R
//! the advancing and receding contact angles. The drop's shape is the spherical cap of the mean
//! angle θ = (θ_A + θ_R)/2 on its base radius a: V = π a³ (2 − 3 cos θ + cos³ θ) / (3 sin³ θ).

use crate::physics::GRAVITY_M_S2;

/// Water's density at 20 °C, kg/m³ (the windshield's drops).
pub const WATER_DENSITY_KG_M3: f64 = 998.2;
/// Water's surface tension at 20 °C, N/m.
pub const SURFACE_TENSION_N_M: f64 = 0.073;
/// Furmidge's shape factor k (order one; the criterion's usual k = 1).
pub const SHAPE_FACTOR_K: f64 = 1.0;

/// The glass's wetting: advancing and receding contact angles, radians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wetting {
    /// Advancing contact angle θ_A, rad.
    pub advancing_rad: f64,
    /// Receding contact angle θ_R, rad (≤ θ_A).
    pub receding_rad: f64,
}

/// The base radius a, m, of a cap of volume `volume_m3` whose volume per a³ is
/// `volume_per_a3` ([`Wetting::volume_per_a3`]; a caller asking per drop keeps it).
#[inline]
pub fn cap_base_radius_m(volume_m3: f64, volume_per_a3: f64) -> f64 {
    (volume_m3.max(0.0) / volume_per_a3).cbrt()
}

impl Wetting {
    /// From angles in degrees.
    pub fn from_deg(advancing_deg: f64, receding_deg: f64) -> Self {
        Wetting {
            advancing_rad: advancing_deg.to_radians(),
            receding_rad: receding_deg.to_radians(),
        }
    }

    /// The cap's contact angle θ: the mean of advancing and receding, rad.
    pub fn mean_rad(&self) -> f64 {
        0.5 * (self.advancing_rad + self.receding_rad)
    }

    /// cos θ_R − cos θ_A (≥ 0).
    pub fn hysteresis(&self) -> f64 {
        self.receding_rad.cos() - self.advancing_rad.cos()
    }

    /// The volume, m³, per a³ (m³) of a cap at the mean angle: π (2 − 3c + c³)/(3 s³).
    pub fn volume_per_a3(&self) -> f64 {
        let t = self.mean_rad();
        let (s, c) = t.sin_cos();
        std::f64::consts::PI * (2.0 - 3.0 * c + c * c * c) / (3.0 * s * s * s)
    }

    /// The base radius a, m, of a cap of volume `volume_m3`.
    pub fn base_radius_m(&self, volume_m3: f64) -> f64 {
        cap_base_radius_m(volume_m3, self.volume_per_a3())
    }

    /// The volume, m³, of a cap of base radius `a_m`.
    pub fn volume_m3(&self, a_m: f64) -> f64 {
        self.volume_per_a3() * a_m.powi(3)
    }

    /// The contact line's retention force, N, on a drop of base radius `a_m`: k σ 2a (cos θ_R − cos θ_A).
    pub fn retention_n(&self, a_m: f64) -> f64 {
        SHAPE_FACTOR_K * SURFACE_TENSION_N_M * 2.0 * a_m * self.hysteresis()
    }

    /// The critical base radius, m, above which a drop slides on glass tilted `tilt_rad` from
    /// the horizontal: ρ g (V/a³) a³ sin α = k σ 2a Δcos, so a² = 2kσΔcos / (ρ g (V/a³) sin α).
    /// Infinite on level glass.
    pub fn critical_base_radius_m(&self, tilt_rad: f64) -> f64 {
        let drive = WATER_DENSITY_KG_M3 * GRAVITY_M_S2 * self.volume_per_a3() * tilt_rad.sin();
        if drive <= 0.0 {
            return f64::INFINITY;
        }
        (2.0 * SHAPE_FACTOR_K * SURFACE_TENSION_N_M * self.hysteresis() / drive).sqrt()
    }

    /// The apex height, m, of a cap of base radius `a_m`: a tan(θ/2).
    pub fn apex_height_m(&self, a_m: f64) -> f64 {
        a_m * (0.5 * self.mean_rad()).tan()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cases derived in the project's reference table (k = 1, θ the mean angle):
    /// (θ_A, θ_R, tilt, critical base radius mm, critical volume µL).
    const CASES: [(f64, f64, f64, f64, f64); 9] = [
        (40.0, 20.0, 30.0, 3.467, 17.96),
        (40.0, 20.0, 60.0, 2.634, 7.88),
        (40.0, 20.0, 90.0, 2.451, 6.35),
        (110.0, 90.0, 30.0, 1.923, 19.62),
        (110.0, 90.0, 60.0, 1.461, 8.61),
        (110.0, 90.0, 90.0, 1.36, 6.94),
        (110.0, 100.0, 30.0, 1.252, 6.29),
        (110.0, 100.0, 60.0, 0.951, 2.76),
        (110.0, 100.0, 90.0, 0.885, 2.22),
    ];

    #[test]
    fn furmidge_matches_the_reference_cases() {
        for (adv, rec, tilt, a_mm, v_ul) in CASES {
            let w = Wetting::from_deg(adv, rec);
            let a = w.critical_base_radius_m(tilt.to_radians());
            let v = w.volume_m3(a);
            assert!(
                (a * 1e3 - a_mm).abs() < 0.0015,
                "{adv}/{rec} at {tilt}: a = {}",
                a * 1e3
            );
            assert!(
                (v * 1e9 - v_ul).abs() < 0.006,
                "{adv}/{rec} at {tilt}: V = {}",
                v * 1e9
            );
        }
    }

    #[test]
    fn a_hemisphere_is_two_thirds_pi_a_cubed() {
        let w = Wetting::from_deg(90.0, 90.0);
        let a = 2e-3;
        let v = w.volume_m3(a);
        assert!((v - 2.0 / 3.0 * std::f64::consts::PI * a.powi(3)).abs() < 1e-15);
        assert!((w.base_radius_m(v) - a).abs() < 1e-12);
        assert!(w.critical_base_radius_m(0.0).is_infinite());
    }
}
