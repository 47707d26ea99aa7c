//! Snowfall: how many flakes of which size fall how fast at a given snowfall rate.
//!
//! - Sizes: Gunn & Marshall (1958), N(D) = N0 e^(−Λ D) flakes per m³ per mm of *melted*
//!   diameter D, Λ = 2.55 R^−0.48 mm⁻¹ (R the liquid-water-equivalent rate, mm/h).
//! - Mass and fall speed: Locatelli & Hobbs (1974), aggregates of unrimed dendrites:
//!   m = 0.073 S^1.4 mg and v = 0.8 S^0.16 m/s, S the flake's maximum dimension in mm, fitted
//!   over S ∈ [2, 10] mm. A flake of melted diameter D has m = ρ_w π D³/6, so
//!   S = (m / 0.073)^(1/1.4).
//! - Projected area: Mitchell (1996), aggregates, A = 0.2285 S^1.88 in cm² for S in cm
//!   (= 0.3012 S^1.88 mm² for S in mm), about a third of the circumscribed disc.
//!
//! **The flux relation.** The mass of snow crossing a horizontal plane per unit area and time
//! is F = ∫ N(D) m(D) v(D) dD; the rate is that mass as a depth of water, R = F / ρ_w. Gunn &
//! Marshall's own N0 = 7.6·10³ R^−0.87 with Locatelli & Hobbs' masses and speeds does not
//! close it (their product carries 0.7–4× the rate over 0.1–5 mm/h, and its large-D tail holds
//! flakes of metres). So the distribution is truncated at S = [`FLAKE_SIZE_MAX_MM`] (the fit's
//! upper end, D = 1.52 mm melted), keeps Gunn & Marshall's slope Λ(R), and takes N0 from the
//! rate: N0 = R ρ_w / ∫₀^Dmax e^(−Λ D) m v dD. Then F = R ρ_w exactly, for every R.

use super::quadrature::integrate;

/// Flake size (maximum dimension) above which none are drawn, mm: Locatelli & Hobbs' fitted
/// range for aggregates of dendrites ends here.
pub const FLAKE_SIZE_MAX_MM: f64 = 10.0;
/// Density of liquid water, mg/mm³ (= 1000 kg/m³).
const WATER_MG_MM3: f64 = 1.0;
/// Density of liquid water, kg/m³.
pub const WATER_KG_M3: f64 = 1000.0;
/// Gauss–Legendre panels over [0, Dmax].
const PANELS: usize = 48;

/// Mass of a flake of melted diameter `melted_mm`, mg.
pub fn flake_mass_mg(melted_mm: f64) -> f64 {
    WATER_MG_MM3 * std::f64::consts::PI / 6.0 * melted_mm.powi(3)
}

/// Maximum dimension S of a flake of melted diameter `melted_mm`, mm (Locatelli & Hobbs'
/// mass–size relation inverted).
pub fn flake_size_mm(melted_mm: f64) -> f64 {
    (flake_mass_mg(melted_mm) / 0.073).powf(1.0 / 1.4)
}

/// Melted diameter of a flake of maximum dimension `size_mm`, mm (the inverse of
/// [`flake_size_mm`]).
pub fn flake_melted_mm(size_mm: f64) -> f64 {
    (0.073 * size_mm.powf(1.4) * 6.0 / (std::f64::consts::PI * WATER_MG_MM3)).cbrt()
}

/// Terminal fall speed of a flake of maximum dimension `size_mm` in still air, m/s.
pub fn flake_fall_speed_m_s(size_mm: f64) -> f64 {
    0.8 * size_mm.max(0.0).powf(0.16)
}

/// Projected area of a flake of maximum dimension `size_mm`, mm² (Mitchell 1996, aggregates).
pub fn flake_area_mm2(size_mm: f64) -> f64 {
    0.3012 * size_mm.max(0.0).powf(1.88)
}

/// Depth of snow that a liquid-equivalent rate lays per second on open flat ground, m/s:
/// R · ρ_w / ρ_snow.
pub fn snow_depth_rate_m_s(snow_rate_mm_h: f64, snow_density_kg_m3: f64) -> f64 {
    snow_rate_mm_h.max(0.0) * 1e-3 / 3600.0 * WATER_KG_M3 / snow_density_kg_m3
}

/// The flakes of one snowfall rate (see the module's flux relation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Snowfall {
    rate_mm_h: f64,
    /// Λ, per mm of melted diameter (infinite for no snow).
    slope_per_mm: f64,
    /// N0, flakes per m³ per mm of melted diameter.
    n0_per_m3_mm: f64,
}

impl Snowfall {
    /// The flakes of the liquid-equivalent rate `snow_rate_mm_h` (≤ 0: none).
    pub fn new(snow_rate_mm_h: f64) -> Self {
        if snow_rate_mm_h.is_nan() || snow_rate_mm_h <= 0.0 {
            return Snowfall {
                rate_mm_h: 0.0,
                slope_per_mm: f64::INFINITY,
                n0_per_m3_mm: 0.0,
            };
        }
        let slope_per_mm = 2.55 * snow_rate_mm_h.powf(-0.48);
        let unit = Snowfall {
            rate_mm_h: snow_rate_mm_h,
            slope_per_mm,
            n0_per_m3_mm: 1.0,
        };
        // R [mm/h] = F / ρ_w; F in mg m⁻² s⁻¹ for N0 = 1 is `unit.mass_flux`; 1 mm/h of water
        // is 1 kg m⁻² h⁻¹ = 1e6/3600 mg m⁻² s⁻¹.
        let want_mg_m2_s = snow_rate_mm_h * 1e6 / 3600.0;
        let n0_per_m3_mm = want_mg_m2_s / unit.mass_flux_mg_m2_s();
        if !n0_per_m3_mm.is_finite() {
            // A rate so small (1e-300 mm/h) that the unit flux underflows to 0: no snow (its
            // N0 would be inf, and the extinction inf · 0 = NaN).
            return Snowfall::new(0.0);
        }
        Snowfall {
            n0_per_m3_mm,
            ..unit
        }
    }

    /// The liquid-equivalent rate, mm/h.
    pub fn rate_mm_h(&self) -> f64 {
        self.rate_mm_h
    }

    /// Λ, per mm of melted diameter.
    pub fn slope_per_mm(&self) -> f64 {
        self.slope_per_mm
    }

    /// N0, flakes per m³ per mm of melted diameter.
    pub fn n0_per_m3_mm(&self) -> f64 {
        self.n0_per_m3_mm
    }

    /// The largest melted diameter drawn, mm (a flake of [`FLAKE_SIZE_MAX_MM`]).
    pub fn melted_max_mm(&self) -> f64 {
        flake_melted_mm(FLAKE_SIZE_MAX_MM)
    }

    /// N(D), flakes per m³ per mm of melted diameter (0 beyond the largest flake).
    pub fn density_per_m3_mm(&self, melted_mm: f64) -> f64 {
        if self.n0_per_m3_mm == 0.0 || melted_mm > self.melted_max_mm() || melted_mm < 0.0 {
            0.0
        } else {
            self.n0_per_m3_mm * (-self.slope_per_mm * melted_mm).exp()
        }
    }

    /// ∫ N(D) f(D) dD over the drawn melted diameters.
    fn moment(&self, f: impl Fn(f64) -> f64) -> f64 {
        if self.n0_per_m3_mm == 0.0 {
            return 0.0;
        }
        integrate(
            |d| self.density_per_m3_mm(d) * f(d),
            0.0,
            self.melted_max_mm(),
            &[],
            PANELS,
        )
    }

    /// Flakes per m³ with melted diameter in [`lo_mm`, `hi_mm`] (clipped to the drawn range).
    pub fn flakes_per_m3(&self, lo_mm: f64, hi_mm: f64) -> f64 {
        self.bin_sampler(lo_mm, hi_mm).expected_per_m3()
    }

    /// The sampler of one melted-diameter bin (clipped to the drawn range): its count per m³
    /// and its diameters, as the rain's bins draw.
    pub fn bin_sampler(&self, lo_mm: f64, hi_mm: f64) -> super::dsd::BinSampler {
        let hi = hi_mm.min(self.melted_max_mm());
        let lo = lo_mm.max(0.0);
        super::dsd::BinSampler::exponential(self.n0_per_m3_mm, self.slope_per_mm, lo, hi.max(lo))
    }

    /// Mass flux through a horizontal plane, mg m⁻² s⁻¹: ∫ N m v dD.
    pub fn mass_flux_mg_m2_s(&self) -> f64 {
        self.moment(|d| flake_mass_mg(d) * flake_fall_speed_m_s(flake_size_mm(d)))
    }

    /// The same flux as a depth of water per hour, mm/h (equals [`Snowfall::rate_mm_h`]).
    pub fn water_equivalent_mm_h(&self) -> f64 {
        self.mass_flux_mg_m2_s() * 3600.0 / 1e6
    }

    /// Mass of snow in the air, g/m³.
    pub fn mass_content_g_m3(&self) -> f64 {
        self.moment(flake_mass_mg) * 1e-3
    }

    /// The speed at which the snow's mass falls in still air, m/s: flux / content (the speed
    /// that carries the cover's snow down; a mass-weighted mean of the flakes' speeds).
    pub fn mean_fall_speed_m_s(&self) -> f64 {
        let content = self.moment(flake_mass_mg);
        if content > 0.0 {
            self.mass_flux_mg_m2_s() / content
        } else {
            0.0
        }
    }

    /// Extinction coefficient of the snow, 1/m: ∫ N · 2 · A dD (extinction efficiency 2, as
    /// for rain: flakes are far larger than the wavelength).
    pub fn extinction_per_m(&self) -> f64 {
        self.moment(|d| 2.0 * flake_area_mm2(flake_size_mm(d))) * 1e-6
    }

    /// The share of [`Self::extinction_per_m`] of the flakes of melted diameter in
    /// [`lo_mm`, `hi_mm`] (clipped to the drawn range), 1/m.
    pub fn extinction_between_per_m(&self, lo_mm: f64, hi_mm: f64) -> f64 {
        let (lo, hi) = (lo_mm.max(0.0), hi_mm.min(self.melted_max_mm()));
        if self.n0_per_m3_mm == 0.0 || hi <= lo {
            return 0.0;
        }
        integrate(
            |d| self.density_per_m3_mm(d) * 2.0 * flake_area_mm2(flake_size_mm(d)),
            lo,
            hi,
            &[],
            PANELS,
        ) * 1e-6
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn no_snow_has_no_flakes() {
        let s = Snowfall::new(0.0);
        assert_eq!(s.flakes_per_m3(0.0, 10.0), 0.0);
        assert_eq!(s.mass_flux_mg_m2_s(), 0.0);
        assert_eq!(s.extinction_per_m(), 0.0);
        assert_eq!(s.mean_fall_speed_m_s(), 0.0);
        assert_eq!(Snowfall::new(f64::NAN).rate_mm_h(), 0.0);
        // a rate whose unit flux underflows is no snow, not NaN (found by tests/test_fuzz.py)
        for r in [1e-300, 5e-324, 1e-200] {
            let s = Snowfall::new(r);
            assert_eq!(s.extinction_per_m(), 0.0, "{r}");
            assert!(s.flakes_per_m3(0.0, 10.0).is_finite());
        }
    }

    #[test]
    fn locatelli_hobbs_speeds_match_reference() {
        // snow.json, values_derived_m_s, dendrite_agg.
        for &(s, v) in &[
            (1.0, 0.8),
            (2.0, 0.894),
            (5.0, 1.035),
            (8.0, 1.116),
            (10.0, 1.156),
        ] {
            assert!((flake_fall_speed_m_s(s) - v).abs() < 1.5e-3, "S={s}");
        }
        for &d in &[0.1, 0.7, 1.5] {
            assert!((flake_melted_mm(flake_size_mm(d)) - d).abs() < 1e-12);
        }
    }

    #[test]
    fn sampled_flakes_carry_the_rate() {
        // Independent of the quadrature: draw the flakes of 200 m³ bin by bin and sum m·v.
        for &rate in &[0.3, 1.0, 5.0] {
            let s = Snowfall::new(rate);
            let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(7);
            let edges: Vec<f64> = (0..=40)
                .map(|k| k as f64 * s.melted_max_mm() / 40.0)
                .collect();
            let mut flux = 0.0;
            for w in edges.windows(2) {
                let bin = s.bin_sampler(w[0], w[1]);
                for _ in 0..200 {
                    for _ in 0..bin.count(&mut rng) {
                        let d = bin.diameter_mm(rng.random());
                        flux += flake_mass_mg(d) * flake_fall_speed_m_s(flake_size_mm(d));
                    }
                }
            }
            let got_mm_h = flux / 200.0 * 3600.0 / 1e6;
            assert!((got_mm_h / rate - 1.0).abs() < 0.03, "{rate}: {got_mm_h}");
            assert!((s.water_equivalent_mm_h() / rate - 1.0).abs() < 1e-9);
        }
    }

    #[test]
    fn fresh_snow_depth_rate() {
        // 1 mm/h of water at 100 kg/m³: 1 cm of snow per hour.
        assert!((snow_depth_rate_m_s(1.0, 100.0) * 3600.0 - 0.01).abs() < 1e-15);
    }

    #[test]
    fn flakes_fall_slower_than_rain_and_dim_the_air() {
        let s = Snowfall::new(1.0);
        let v = s.mean_fall_speed_m_s();
        assert!((0.8..1.2).contains(&v), "{v}");
        // σ = 3.912 / V: heavy snow (≥ 2.5 mm/h) is the NWS's "visibility ≤ 1/4 mile" class
        // (400 m); 1 mm/h lies between light and heavy.
        let vis = |r: f64| 3.912 / Snowfall::new(r).extinction_per_m();
        assert!(
            vis(2.5) < 400.0 && vis(0.1) > 1000.0,
            "{} {}",
            vis(2.5),
            vis(0.1)
        );
        assert!(s.extinction_per_m() > crate::physics::extinction::rain_extinction_per_m(1.0));
    }
}
