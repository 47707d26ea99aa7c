//! Diameter bins: each texture diameter stands for the drops of a bin around it.
//!
//! Bin edges sit at the midpoints between neighbouring diameters; the outer bins are
//! symmetric about their diameter (half the neighbouring gap on the outside), and a single
//! diameter gets a bin of [`SINGLE_BIN_WIDTH_MM`]. Lower edges are clipped at 0.

use crate::error::{Error, Param, Range, Result};

/// Bin width used when only one diameter is given, mm (Yoshida, Dobashi & Yamamoto's 0.2 mm step).
pub const SINGLE_BIN_WIDTH_MM: f64 = 0.2;
/// Valid texture diameters, mm.
pub const TEXTURE_DIAMETER_MM: Range = crate::ranges::DIAMETERS_MM.range;

/// (lower, upper) bin edges in mm for strictly increasing `diameters_mm`.
pub fn diameter_bins(diameters_mm: &[f64]) -> Result<Vec<(f64, f64)>> {
    if diameters_mm.is_empty() {
        return Err(Error::Invalid {
            param: Param {
                name: "diameters_mm",
                index: None,
            },
            message: "needs at least one diameter".into(),
        });
    }
    TEXTURE_DIAMETER_MM.check_all("diameters_mm", diameters_mm)?;
    for (i, w) in diameters_mm.windows(2).enumerate() {
        if w[1] <= w[0] {
            return Err(Error::Invalid {
                param: Param {
                    name: "diameters_mm",
                    index: Some(i + 1),
                },
                message: format!(
                    "diameters must be strictly increasing, got {} after {}",
                    w[1], w[0]
                ),
            });
        }
    }
    let n = diameters_mm.len();
    let half_gap = |i: usize| 0.5 * (diameters_mm[i + 1] - diameters_mm[i]);
    Ok((0..n)
        .map(|i| {
            let d = diameters_mm[i];
            let (lo_half, hi_half) = if n == 1 {
                (0.5 * SINGLE_BIN_WIDTH_MM, 0.5 * SINGLE_BIN_WIDTH_MM)
            } else if i == 0 {
                (half_gap(0), half_gap(0))
            } else if i == n - 1 {
                (half_gap(n - 2), half_gap(n - 2))
            } else {
                (half_gap(i - 1), half_gap(i))
            };
            ((d - lo_half).max(0.0), d + hi_half)
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seed_grid_bins_tile_the_range() {
        let d = [1.0, 1.2, 1.4, 1.6, 1.8, 2.0];
        let b = diameter_bins(&d).unwrap_or_default();
        assert_eq!(b.len(), 6);
        assert!((b[0].0 - 0.9).abs() < 1e-12 && (b[5].1 - 2.1).abs() < 1e-12);
        for w in b.windows(2) {
            assert!((w[0].1 - w[1].0).abs() < 1e-12);
        }
        assert!(diameter_bins(&[1.0, 1.0]).is_err());
        assert!(diameter_bins(&[]).is_err());
        assert_eq!(
            diameter_bins(&[0.05]).unwrap_or_default(),
            vec![(0.0, 0.15000000000000002)]
        );
    }
}
