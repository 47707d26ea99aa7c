//! A sky that is the same at every azimuth (the CIE overcast sky, the general types without a
//! sun; rain and haze only change how it varies with elevation): a point's illuminance is then
//! a fixed linear form in the sky's cumulative integrals at a few elevations.
//!
//! Along every azimuth the sky's cumulative integrals C(γ) of [`super::illuminance`] are the
//! same function of elevation (times Δφ/π). A point's five illuminances are sums of ±C at the
//! edges of its visible elevations (weighted by n·ω/cos γ for the vertical normals). Here C is
//! read not from its 512-step table but by cubic (4-point Lagrange) interpolation between
//! [`NODES`] elevations, so each sum is Σ_b W_b·C(γ_b): the weights W (five channels × NODES)
//! depend on the boxes alone and the C(γ_b) on the sky alone. A horizon keeps each node's W
//! ([`super::horizon::Horizon`]), and a map under a new rain rate or visibility costs one short
//! dot product per node.
//!
//! Error, against the sky tabulated along every azimuth at 512 elevations
//! ([`super::illuminance::SkyTable::per_azimuth`]) at every open node: within 1e-3 of the
//! node's light, tested on a canyon (`horizon::tests`, worst 1.0e-4 from clear air to fog) and
//! on the bundled street (`tests/test_sky.py`, worst 3.0e-4, in a 0.1 mm/h drizzle).

use super::illuminance::{CHANNELS, CODES_PER_STEP};

/// Elevations at which a symmetric sky's cumulative integrals are kept.
pub const NODES: usize = 24;
/// Steps of the 512-step table at which the elevations lie: b/23 of the way up, rounded (evenly
/// spaced: against spacings closer near the horizon, (b/23)^1.25 and (b/23)^1.5, the worst
/// node of the bundled street was 3.0e-4 against 4.0e-4 and 8.4e-4 off the full tables).
pub const AT_STEP: [u16; NODES] = [
    0, 22, 45, 67, 89, 111, 134, 156, 178, 200, 223, 245, 267, 289, 312, 334, 356, 378, 401, 423,
    445, 467, 490, 512,
];
/// Steps of the fine table (`illuminance::STEPS`).
const STEPS: f64 = 512.0;

/// A symmetric sky's cumulative integrals at the [`AT_STEP`] elevations, one azimuth's (each
/// already times Δφ/π): the horizontal surfaces' and the vertical ones'.
#[derive(Debug, Clone, PartialEq)]
pub struct Coarse {
    /// ∫₀^γ_b L τ sin γ cos γ dγ / π · Δφ.
    pub up: [f64; NODES],
    /// ∫₀^γ_b L τ cos² γ dγ / π · Δφ.
    pub side: [f64; NODES],
}

/// One point's weights: channel c's illuminance is Σ_b `w[c][b]`·C(γ_b), C the up column for
/// channel 0 and the side column for the others.
pub type Weights = [[f32; NODES]; CHANNELS];

/// The Lagrange weights of the four nodes around the elevation `x` steps of the fine table up
/// (in [0, 512]): the first node's index and the weights.
#[inline]
fn lagrange(x: f64) -> (usize, [f64; 4]) {
    let x = x.clamp(0.0, STEPS);
    // The interval [AT_STEP[i], AT_STEP[i + 1]) holding x (i ≤ NODES − 2), from the even
    // spacing's guess moved by the rounding, then the stencil i-1..i+2 kept inside.
    let mut i = ((x * (NODES - 1) as f64 / STEPS) as usize).min(NODES - 2);
    while i > 0 && f64::from(AT_STEP[i]) > x {
        i -= 1;
    }
    while i < NODES - 2 && f64::from(AT_STEP[i + 1]) <= x {
        i += 1;
    }
    let s = i.saturating_sub(1).min(NODES - 4);
    let d = [0, 1, 2, 3].map(|b| x - f64::from(AT_STEP[s + b]));
    let inv = &inverse_denominators()[s];
    let w = [
        d[1] * d[2] * d[3] * inv[0],
        d[0] * d[2] * d[3] * inv[1],
        d[0] * d[1] * d[3] * inv[2],
        d[0] * d[1] * d[2] * inv[3],
    ];
    (s, w)
}

/// Per stencil start s, the Lagrange weights' 1 / ∏_{b≠a} (n_a − n_b) over its four nodes.
fn inverse_denominators() -> &'static [[f64; 4]; NODES - 3] {
    static TABLE: std::sync::OnceLock<[[f64; 4]; NODES - 3]> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|s| {
            let n = [0, 1, 2, 3].map(|a| f64::from(AT_STEP[s + a]));
            std::array::from_fn(|a| {
                1.0 / (0..4)
                    .filter(|&b| b != a)
                    .map(|b| n[a] - n[b])
                    .product::<f64>()
            })
        })
    })
}

/// A point's weights as they are summed, azimuth after azimuth ([`add_azimuth`]).
pub type Sums = [[f64; NODES]; CHANNELS];

/// The weights of a point whose visible elevations along `dirs` (unit horizontal directions)
/// are `counts` and `edges` (as [`super::illuminance::VisibleSky`] holds them: codes of
/// [`CODES_PER_STEP`] per fine step).
pub fn weights(dirs: &[(f64, f64)], counts: &[u16], edges: &[u16]) -> Weights {
    let mut acc = [[0.0f64; NODES]; CHANNELS];
    let mut at_edge = 0;
    for (&dir, &n) in dirs.iter().zip(counts) {
        let n = usize::from(n);
        add_azimuth(&mut acc, dir, &edges[at_edge..at_edge + n]);
        at_edge += n;
    }
    finish(&acc)
}

/// The weights of summed `acc`.
pub fn finish(acc: &Sums) -> Weights {
    acc.map(|row| row.map(|v| v as f32))
}

/// Adds to `acc` the weights of the visible elevations `e` (codes) along horizontal direction
/// (dx, dz).
#[inline]
pub fn add_azimuth(acc: &mut Sums, (dx, dz): (f64, f64), e: &[u16]) {
    if e.is_empty() {
        return;
    }
    // This azimuth's share of each channel: all of up, and n·ω / cos γ of the one vertical
    // normal of ±X and of ±Z it faces (+X, −X, +Z, −Z are channels 1 to 4).
    let (cx, fx) = if dx >= 0.0 { (1, dx) } else { (2, -dx) };
    let (cz, fz) = if dz >= 0.0 { (3, dz) } else { (4, -dz) };
    let mut add = |b: usize, v: f64| {
        acc[0][b] += v;
        acc[cx][b] += v * fx;
        acc[cz][b] += v * fz;
    };
    // Visible from a to b: +C(b) − C(a); an odd last edge's interval ends at the zenith,
    // the last node exactly.
    for (j, &g) in e.iter().enumerate() {
        let sign = if j % 2 == 0 { -1.0 } else { 1.0 };
        let (s, w) = lagrange(f64::from(g) / f64::from(CODES_PER_STEP));
        for (a, wa) in w.into_iter().enumerate() {
            add(s + a, sign * wa);
        }
    }
    if e.len() % 2 == 1 {
        add(NODES - 1, 1.0);
    }
}

/// The illuminance on the five normals relative to E of a point with weights `w` under the
/// symmetric sky `c`, at least 0 (where a point sees no sky on a normal, its weights' sum
/// rounds to about ±1e-7 rather than 0; light is never negative).
#[inline]
pub fn light(w: &Weights, c: &Coarse) -> [f32; CHANNELS] {
    let mut out = [0.0f32; CHANNELS];
    for (ch, (o, row)) in out.iter_mut().zip(w).enumerate() {
        let col = if ch == 0 { &c.up } else { &c.side };
        *o = (row
            .iter()
            .zip(col)
            .map(|(&wb, &cb)| f64::from(wb) * cb)
            .sum::<f64>() as f32)
            .max(0.0);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn the_nodes_are_evenly_spaced_steps() {
        for (b, &s) in AT_STEP.iter().enumerate() {
            let want = (STEPS * b as f64 / (NODES - 1) as f64).round();
            assert_eq!(f64::from(s), want, "{b}");
        }
    }

    #[test]
    fn the_interval_is_the_one_holding_the_elevation() {
        for i in 0..=4096 {
            let x = STEPS * f64::from(i) / 4096.0;
            let (s, _) = lagrange(x);
            let want = AT_STEP[1..NODES - 1]
                .iter()
                .take_while(|&&a| f64::from(a) <= x)
                .count();
            assert_eq!(s, want.saturating_sub(1).min(NODES - 4), "{x}");
        }
    }

    #[test]
    fn lagrange_weights_reproduce_cubics_exactly() {
        // Cubic Lagrange interpolation is exact for polynomials of degree 3 (an independent
        // check of the stencil and the weights, everywhere including both ends).
        let p = |x: f64| 0.3 - 1.2 * x + 0.7 * x * x + 0.25 * x * x * x;
        let node_g = |b: usize| f64::from(AT_STEP[b]) / STEPS * FRAC_PI_2;
        for i in 0..=1000 {
            let g = FRAC_PI_2 * f64::from(i) / 1000.0;
            let (s, w) = lagrange(g / FRAC_PI_2 * STEPS);
            let got: f64 = (0..4).map(|a| w[a] * p(node_g(s + a))).sum();
            assert!((got - p(g)).abs() < 1e-12, "{g}: {got} vs {}", p(g));
            assert!(w.iter().sum::<f64>() - 1.0 < 1e-12);
        }
        // at a node, its weight is 1
        let (s, w) = lagrange(f64::from(AT_STEP[7]));
        assert!((w[7 - s] - 1.0).abs() < 1e-12, "{s} {w:?}");
    }
}
