//! The Marshall–Palmer (1948) drop-size distribution and its moments.
//!
//! N(D) = N0 e^(−Λ D) drops per m³ per mm of diameter, N0 = 8000 m⁻³ mm⁻¹,
//! Λ = 4.1 R^−0.21 mm⁻¹ (R in mm/h, D in mm). R = 0 means no drops at all.

use super::air::AirProps;
use super::fall_speed::{AirArrays, DIAMETER_MM, FallSpeed, FallSpeedModel};
use super::quadrature::integrate;
use crate::error::{Error, Param, Range, Result, at, broadcast_len};

/// N0, drops per m³ per mm.
pub const MP_N0_PER_M3_MM: f64 = 8000.0;
/// Valid rain rates, mm/h (the heaviest recorded hourly rainfall is ~300 mm/h).
pub const RAIN_RATE_MM_H: Range = crate::ranges::RAIN_RATE_MM_H.range;
/// Valid bin edges for drop counts, mm (the upper edge may be infinite).
pub const EDGE_MM: Range = crate::ranges::D_MIN_MM.range;

/// Slope Λ, mm⁻¹ (infinite for R = 0).
pub fn mp_slope_per_mm(rain_rate_mm_h: f64) -> f64 {
    if rain_rate_mm_h > 0.0 {
        4.1 * rain_rate_mm_h.powf(-0.21)
    } else {
        f64::INFINITY
    }
}

/// N(D), drops per m³ per mm.
pub fn marshall_palmer(diameter_mm: f64, rain_rate_mm_h: f64) -> f64 {
    if rain_rate_mm_h > 0.0 {
        MP_N0_PER_M3_MM * (-mp_slope_per_mm(rain_rate_mm_h) * diameter_mm).exp()
    } else {
        0.0
    }
}

/// Drops per m³ with diameter in [d_min, d_max] mm: N0/Λ · (e^(−Λ d_min) − e^(−Λ d_max)),
/// written with expm1 so narrow bins keep their precision.
pub fn drops_per_m3(rain_rate_mm_h: f64, d_min_mm: f64, d_max_mm: f64) -> f64 {
    if rain_rate_mm_h <= 0.0 || d_max_mm <= d_min_mm {
        return 0.0;
    }
    let lam = mp_slope_per_mm(rain_rate_mm_h);
    MP_N0_PER_M3_MM / lam * (-lam * d_min_mm).exp() * -(-lam * (d_max_mm - d_min_mm)).exp_m1()
}

/// Marshall–Palmer drops of one diameter bin [lo, hi] mm in a unit volume, sampled: the count
/// is ⌊λ⌋ plus one with probability λ − ⌊λ⌋ (λ = [`drops_per_m3`] of the bin), each diameter
/// the inverse of the bin's truncated exponential at a uniform u. The rain textures and the
/// world's drops draw with it, in that order (count, then per drop its diameter first).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BinSampler {
    lo_mm: f64,
    hi_mm: f64,
    /// Λ, 1/mm.
    lam: f64,
    /// The bin's mass relative to e^(−Λ lo): 1 − e^(−Λ (hi − lo)).
    tail: f64,
    /// λ, drops per m³.
    expected: f64,
}

impl BinSampler {
    /// The bin [`lo_mm`, `hi_mm`] at `rain_rate_mm_h`.
    pub fn new(rain_rate_mm_h: f64, lo_mm: f64, hi_mm: f64) -> Self {
        let lam = mp_slope_per_mm(rain_rate_mm_h);
        BinSampler {
            lo_mm,
            hi_mm,
            lam,
            tail: -(-lam * (hi_mm - lo_mm)).exp_m1(),
            expected: drops_per_m3(rain_rate_mm_h, lo_mm, hi_mm),
        }
    }

    /// The bin [`lo_mm`, `hi_mm`] of any exponential distribution N(D) = N0 e^(−Λ D)
    /// (`n0_per_m3_mm`, `slope_per_mm`): the snowflakes' melted diameters draw with it.
    pub fn exponential(n0_per_m3_mm: f64, slope_per_mm: f64, lo_mm: f64, hi_mm: f64) -> Self {
        let lam = slope_per_mm;
        let tail = -(-lam * (hi_mm - lo_mm)).exp_m1();
        let expected = if n0_per_m3_mm > 0.0 && lam.is_finite() && hi_mm > lo_mm {
            n0_per_m3_mm / lam * (-lam * lo_mm).exp() * tail
        } else {
            0.0
        };
        BinSampler {
            lo_mm,
            hi_mm,
            lam,
            tail,
            expected,
        }
    }

    /// λ, the expected drops per m³ (0: none to draw).
    pub fn expected_per_m3(&self) -> f64 {
        self.expected
    }

    /// The number of drops in 1 m³: one uniform draw from `rng`.
    pub fn count(&self, rng: &mut impl rand::Rng) -> usize {
        self.count_in(1.0, rng)
    }

    /// The number of drops in `volume_m3`: ⌊λ⌋ plus one with probability λ − ⌊λ⌋ (λ the
    /// expected number), one uniform draw from `rng`.
    pub fn count_in(&self, volume_m3: f64, rng: &mut impl rand::Rng) -> usize {
        let expected = self.expected * volume_m3;
        let whole = expected.floor();
        whole as usize + usize::from(rng.random::<f64>() < expected - whole)
    }

    /// The diameter, mm, of a drop drawn at the uniform `u` in [0, 1).
    #[inline]
    pub fn diameter_mm(&self, u: f64) -> f64 {
        (self.lo_mm - (-u * self.tail).ln_1p() / self.lam).min(self.hi_mm)
    }
}

fn check_edges(d_min: &[f64], d_max: &[f64], n: usize, hi: Range) -> Result<()> {
    EDGE_MM.check_all("d_min_mm", d_min)?;
    hi.check_all("d_max_mm", d_max)?;
    for i in 0..n {
        let (lo, up) = (at(d_min, i), at(d_max, i));
        if lo >= up {
            let index = (n > 1).then_some(i);
            return Err(Error::Invalid {
                param: Param {
                    name: "d_max_mm",
                    index,
                },
                message: format!("d_max_mm = {up} must be greater than d_min_mm = {lo}"),
            });
        }
    }
    Ok(())
}

/// Vectorised [`marshall_palmer`]; arrays of length 1 or n.
pub fn marshall_palmer_many(diameter_mm: &[f64], rain_rate_mm_h: &[f64]) -> Result<Vec<f64>> {
    let n = broadcast_len(&[
        ("diameter_mm", diameter_mm.len()),
        ("rain_rate_mm_h", rain_rate_mm_h.len()),
    ])?;
    DIAMETER_MM.check_all("diameter_mm", diameter_mm)?;
    RAIN_RATE_MM_H.check_all("rain_rate_mm_h", rain_rate_mm_h)?;
    Ok((0..n)
        .map(|i| marshall_palmer(at(diameter_mm, i), at(rain_rate_mm_h, i)))
        .collect())
}

/// Vectorised [`drops_per_m3`]; arrays of length 1 or n.
pub fn drops_per_m3_many(
    rain_rate_mm_h: &[f64],
    d_min_mm: &[f64],
    d_max_mm: &[f64],
) -> Result<Vec<f64>> {
    let n = broadcast_len(&[
        ("rain_rate_mm_h", rain_rate_mm_h.len()),
        ("d_min_mm", d_min_mm.len()),
        ("d_max_mm", d_max_mm.len()),
    ])?;
    RAIN_RATE_MM_H.check_all("rain_rate_mm_h", rain_rate_mm_h)?;
    check_edges(d_min_mm, d_max_mm, n, EDGE_MM)?;
    Ok((0..n)
        .map(|i| drops_per_m3(at(rain_rate_mm_h, i), at(d_min_mm, i), at(d_max_mm, i)))
        .collect())
}

/// Panels per smooth piece of the rain-rate integral (8-point Gauss–Legendre each).
const PANELS: usize = 64;

/// Rain rate carried by the distribution, mm/h: R' = 6π·10⁻⁴ ∫ N(D) D³ v(D) dD
/// (D mm, v m/s, N m⁻³ mm⁻¹), integrated over [d_min, d_max] with the chosen fall-speed model.
/// For a consistent model R' ≈ R; Marshall–Palmer with measured speeds gives 5–18 % more.
pub fn rain_rate_from_dsd(
    rain_rate_mm_h: f64,
    model: FallSpeedModel,
    air: &AirProps,
    d_min_mm: f64,
    d_max_mm: f64,
) -> f64 {
    if rain_rate_mm_h <= 0.0 {
        return 0.0;
    }
    let lam = mp_slope_per_mm(rain_rate_mm_h);
    let law = FallSpeed::new(model, air);
    let f = |d: f64| d.powi(3) * (-lam * d).exp() * law.m_s(d);
    // Beard changes regime at 19 µm and 1.07 mm; split there so every piece is smooth.
    6.0 * std::f64::consts::PI
        * 1e-4
        * MP_N0_PER_M3_MM
        * integrate(f, d_min_mm, d_max_mm, &[0.019, 1.07], PANELS)
}

/// Vectorised [`rain_rate_from_dsd`]; arrays of length 1 or n.
pub fn rain_rate_from_dsd_many(
    rain_rate_mm_h: &[f64],
    model: FallSpeedModel,
    air: AirArrays<'_>,
    d_min_mm: &[f64],
    d_max_mm: &[f64],
) -> Result<Vec<f64>> {
    let n = air.broadcast_with(&[
        ("rain_rate_mm_h", rain_rate_mm_h.len()),
        ("d_min_mm", d_min_mm.len()),
        ("d_max_mm", d_max_mm.len()),
    ])?;
    RAIN_RATE_MM_H.check_all("rain_rate_mm_h", rain_rate_mm_h)?;
    check_edges(d_min_mm, d_max_mm, n, DIAMETER_MM)?;
    let fixed = air.validate(n)?;
    Ok((0..n)
        .map(|i| {
            let props = fixed.unwrap_or_else(|| air.props_at(i));
            rain_rate_from_dsd(
                at(rain_rate_mm_h, i),
                model,
                &props,
                at(d_min_mm, i),
                at(d_max_mm, i),
            )
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::air::Air;

    #[test]
    fn zero_rain_has_no_drops() {
        assert_eq!(marshall_palmer(0.0, 0.0), 0.0);
        assert_eq!(drops_per_m3(0.0, 0.0, f64::INFINITY), 0.0);
        assert_eq!(
            rain_rate_from_dsd(0.0, FallSpeedModel::Beard, &Air::STANDARD.props(), 0.0, 8.0),
            0.0
        );
    }

    #[test]
    fn total_count_is_n0_over_lambda() {
        let r = 10.0;
        let total = drops_per_m3(r, 0.0, f64::INFINITY);
        assert!((total - MP_N0_PER_M3_MM / mp_slope_per_mm(r)).abs() < 1e-9);
        // bins add up
        let parts: f64 = (0..80)
            .map(|k| drops_per_m3(r, k as f64 * 0.1, (k + 1) as f64 * 0.1))
            .sum();
        assert!((parts - drops_per_m3(r, 0.0, 8.0)).abs() < 1e-9 * total);
    }

    #[test]
    fn beard_rain_rate_matches_reference() {
        // marshall_palmer_rain_rate_check.csv, R_calc_Beard76_20C (integrated to infinity).
        let a = Air::STANDARD.props();
        for &(r, want) in &[(1.0, 1.18), (10.0, 11.642), (25.0, 28.286)] {
            let got = rain_rate_from_dsd(r, FallSpeedModel::Beard, &a, 0.0, 8.0);
            assert!((got / want - 1.0).abs() < 0.005, "R={r}: {got} vs {want}");
        }
    }
}
