//! Particle clouds lit by the sun (Shimada, Shinya, Shiraishi & Harada, *Fast rendering of
//! dynamic clouds using GPU shaders*, IPSJ 2008, improving Harris & Lastra 2001).
//!
//! A cloud is a set of Gaussian particles: particle i has its centre, its 1/e radius r_i
//! (density ∝ exp(−d²/r_i²), cut at [`CUTOFF_RADII`] radii), its optical depth τ_i through
//! the centre (so its column at distance ρ from the axis is τ_i exp(−ρ²/r_i²)) and its
//! single-scattering albedo a_i.
//!
//! Sunlight crossing particle i keeps the share G_i = exp(−(1 − a_i f) τ_i): the paper's
//! G = a τ p(l,l)/4π + e^−τ to first order in τ, with p(l,l)/4π read as f = g², the share of
//! scattering in the forward peak that δ-M scaling (Wiscombe 1977) keeps on the direct
//! beam. The product form is ≤ 1 for every τ (the linear form exceeds 1 for thick
//! particles) and its logarithm is linear in τ, so log G splats exactly.
//!
//! - [`generate`]: procedural, seeded clouds (cumulus, stratocumulus, a broken field).
//! - [`optics`]: the droplets' optics from the Mie reference (β from liquid water content).
//! - [`light`]: the light-aligned frame both illumination methods work in.
//! - [`harris`]: Harris' sorted recurrence, the reference and the speed baseline.
//! - [`volume`]: the attenuation volume Γ, order-independent, built by splatting log G and
//!   a prefix sum along the light.
//! - [`reference`]: a brute-force Monte Carlo path tracer of a cloud under the sun, every
//!   order of scattering: what the frames' lighting is measured against.
//! - [`frame`]: clouds in frames: the cloud pass (camera-facing Gaussian splats composited
//!   back to front) and the sun's share through the clouds.

pub mod billows;
pub mod dome;
pub mod frame;
pub mod generate;
pub mod harris;
pub mod light;
pub mod optics;
pub mod reference;
pub mod stage;
pub mod volume;

use crate::error::{Error, Param, Result};
use crate::ranges;

/// A particle's support, in radii: exp(−6.25) ≈ 0.2 % of its centre's optical depth is left
/// out beyond it (both illumination methods cut it alike; 3 radii cost the volume 44 % more
/// footprint for 0.18 % more of each particle).
pub const CUTOFF_RADII: f64 = 2.5;

/// A cloud: Gaussian particles and their droplets' phase asymmetry.
#[derive(Debug, Clone, PartialEq)]
pub struct Cloud {
    /// Particle centres, world metres.
    pub positions_m: Vec<[f64; 3]>,
    /// Gaussian 1/e radii, m.
    pub radii_m: Vec<f64>,
    /// Optical depths through the centres.
    pub optical_depths: Vec<f64>,
    /// Single-scattering albedos.
    pub albedos: Vec<f64>,
    /// Henyey–Greenstein asymmetry g of the droplets.
    pub asymmetry_g: f64,
}

impl Cloud {
    /// A checked cloud: equal lengths, at least one particle, every value in its range.
    pub fn new(
        positions_m: Vec<[f64; 3]>,
        radii_m: Vec<f64>,
        optical_depths: Vec<f64>,
        albedos: Vec<f64>,
        asymmetry_g: f64,
    ) -> Result<Self> {
        let n = positions_m.len();
        if n == 0 {
            return Err(Error::Invalid {
                param: Param {
                    name: "positions_m",
                    index: None,
                },
                message: "a cloud needs at least one particle, got 0".into(),
            });
        }
        for (name, len) in [
            ("radii_m", radii_m.len()),
            ("optical_depths", optical_depths.len()),
            ("albedos", albedos.len()),
        ] {
            if len != n {
                return Err(Error::Length {
                    param: Param { name, index: None },
                    len,
                    expected: n,
                });
            }
        }
        for (i, p) in positions_m.iter().enumerate() {
            for &c in p {
                ranges::POSITIONS_M.check_at(Some(i), c)?;
            }
        }
        ranges::RADII_M.check_all(&radii_m)?;
        ranges::OPTICAL_DEPTHS.check_all(&optical_depths)?;
        ranges::ALBEDOS.check_all(&albedos)?;
        ranges::ASYMMETRY_G.check(asymmetry_g)?;
        Ok(Cloud {
            positions_m,
            radii_m,
            optical_depths,
            albedos,
            asymmetry_g,
        })
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.positions_m.len()
    }

    /// Whether the cloud has no particle (never, for a checked cloud).
    pub fn is_empty(&self) -> bool {
        self.positions_m.is_empty()
    }

    /// The forward-peak share f = g² of the droplets' scattering (see the module's notes).
    pub fn forward_share(&self) -> f64 {
        self.asymmetry_g * self.asymmetry_g
    }

    /// −log G_i / τ_i = 1 − a_i f: particle i's log-attenuation per unit optical depth.
    pub fn attenuation_per_depth(&self, i: usize) -> f64 {
        1.0 - self.albedos[i] * self.forward_share()
    }
}

/// A checked, normalised direction towards the sun.
pub fn sun_direction(d: [f64; 3]) -> Result<glam::DVec3> {
    let v = glam::DVec3::from_array(d);
    let len = v.length();
    if !len.is_finite() || !v.is_finite() || len < 1e-12 {
        return Err(Error::Invalid {
            param: Param {
                name: "sun_direction",
                index: None,
            },
            message: format!(
                "must be a finite non-zero vector towards the sun, got {:?}",
                d
            ),
        });
    }
    Ok(v / len)
}

/// e^x for x ≤ 0 (0 below −110): 2^(x log₂e) split into 2^k (exponent bits, k the nearest
/// integer) and 2^f, |f| ≤ ½, by its Taylor series to degree 8 (relative error below 3e-10).
/// Branch-free, so loops over it vectorise; plain arithmetic, so the same bits everywhere.
#[inline]
pub(crate) fn exp_fast(x: f64) -> f64 {
    let t = (x * std::f64::consts::LOG2_E).clamp(-160.0, 0.0);
    // The nearest integer below or at ½ from t ≤ 0, by truncation (an instruction, where
    // `round` is a libm call on baseline x86-64).
    let ki = (t - 0.5) as i64;
    let k = ki as f64;
    let y = (t - k) * std::f64::consts::LN_2;
    let mut p = 1.0 / 40320.0;
    for c in [
        1.0 / 5040.0,
        1.0 / 720.0,
        1.0 / 120.0,
        1.0 / 24.0,
        1.0 / 6.0,
        0.5,
        1.0,
        1.0,
    ] {
        p = p * y + c;
    }
    let scale = f64::from_bits(((ki + 1023) as u64) << 52);
    let v = p * scale;
    if t <= -159.0 { 0.0 } else { v }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one() -> Cloud {
        Cloud::new(vec![[0.0; 3]], vec![10.0], vec![1.0], vec![1.0], 0.86).unwrap()
    }

    #[test]
    fn fast_exp_is_exp() {
        for i in 0..2000 {
            let x = -(i as f64) * 0.0557;
            let (got, want) = (exp_fast(x), x.exp());
            assert!(
                (got - want).abs() <= want * 1e-9 + 1e-47,
                "{x}: {got} vs {want}"
            );
        }
        assert_eq!(exp_fast(0.0), 1.0);
        assert_eq!(exp_fast(-1e4), 0.0);
    }

    #[test]
    fn refuses_bad_clouds() {
        assert!(one().len() == 1);
        let e = Cloud::new(vec![], vec![], vec![], vec![], 0.86).unwrap_err();
        assert!(e.to_string().contains("at least one particle"));
        let e = Cloud::new(vec![[0.0; 3]], vec![-1.0], vec![1.0], vec![1.0], 0.86).unwrap_err();
        assert!(e.to_string().starts_with("radii_m = -1.0"), "{e}");
        let e = Cloud::new(
            vec![[f64::NAN, 0.0, 0.0]],
            vec![1.0],
            vec![1.0],
            vec![1.0],
            0.86,
        )
        .unwrap_err();
        assert!(e.to_string().starts_with("positions_m[0] = NaN"), "{e}");
        let e = Cloud::new(
            vec![[0.0; 3]; 2],
            vec![1.0],
            vec![1.0; 2],
            vec![1.0; 2],
            0.86,
        )
        .unwrap_err();
        assert!(e.to_string().contains("radii_m has length 1"), "{e}");
        assert!(sun_direction([0.0; 3]).is_err());
        assert!(sun_direction([0.0, f64::NAN, 1.0]).is_err());
        assert!((sun_direction([0.0, 2.0, 0.0]).unwrap().y - 1.0).abs() < 1e-15);
    }
}
