//! Composite Gauss–Legendre quadrature with breakpoints at known kinks.

/// 8-point Gauss–Legendre nodes (positive half) on [-1, 1].
const NODES: [f64; 4] = [
    0.183_434_642_495_649_8,
    0.525_532_409_916_329,
    0.796_666_477_413_626_7,
    0.960_289_856_497_536_3,
];
/// Matching weights.
const WEIGHTS: [f64; 4] = [
    0.362_683_783_378_362,
    0.313_706_645_877_887_3,
    0.222_381_034_453_374_5,
    0.101_228_536_290_376_3,
];

/// ∫ f over [a, b], split at the `breaks` that fall inside, each piece into `panels` panels.
pub(crate) fn integrate<F: Fn(f64) -> f64>(
    f: F,
    a: f64,
    b: f64,
    breaks: &[f64],
    panels: usize,
) -> f64 {
    let mut edges: Vec<f64> = std::iter::once(a)
        .chain(breaks.iter().copied().filter(|&x| x > a && x < b))
        .chain(std::iter::once(b))
        .collect();
    edges.sort_by(f64::total_cmp);
    let mut total = 0.0;
    for w in edges.windows(2) {
        let (lo, hi) = (w[0], w[1]);
        let h = (hi - lo) / panels as f64;
        for k in 0..panels {
            let mid = lo + (k as f64 + 0.5) * h;
            let half = 0.5 * h;
            let mut s = 0.0;
            for (x, wt) in NODES.iter().zip(WEIGHTS) {
                s += wt * (f(mid - half * x) + f(mid + half * x));
            }
            total += s * half;
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_for_polynomials_and_exponentials() {
        let p = integrate(|x| x.powi(7) - 3.0 * x * x, 0.0, 2.0, &[], 1);
        assert!((p - (256.0 / 8.0 - 8.0)).abs() < 1e-12);
        let e = integrate(|x| (-2.0 * x).exp(), 0.0, 5.0, &[1.0], 20);
        assert!((e - (1.0 - (-10.0f64).exp()) / 2.0).abs() < 1e-14);
    }
}
