//! The paths the snow falls along: the wind slowed among the buildings, and a spread of fall
//! directions from the flakes' sizes and the wind's gusts.
//!
//! **The wind among the buildings.** `wind_m_s` is the wind above the roofs. Below the canopy's
//! top it follows Macdonald's exponential profile (R. W. Macdonald, *Modelling the mean velocity
//! profile in the urban canopy layer*, Boundary-Layer Meteorology 97, 2000):
//! u(z) = u_h · exp(a (z/h − 1)), z above the ground, h the canopy's height, a = 9.6 λ_f with
//! λ_f the frontal area of the surfaces facing the wind per unit of plan area. Here h is the
//! plan-area mean height of the cells standing [`BUILT_M`] or more above the lowest surface (no
//! such cells: no canopy, the wind is the same at every height), λ_f counts every rise of the
//! height field's bases toward the wind over the grid's surface cells, and a is held at most
//! [`ATTENUATION_MAX`] (there the ground's wind is e^−5 < 1 % of the roofs').
//!
//! A flake that falls at v_f through a wind u(z)·ŵ drifts by u(z)/v_f per metre of fall, so its
//! path is x(z) = x₀ + s·G(z), s = u_h ŵ / v_f, with G(z) = ∫₀^z u(z′)/u_h dz′ (the lift, in
//! metres: z itself above the canopy's top, less below it). Paths through different points are
//! the same curve shifted, so the shadow buffer stays a projection: it projects each point along
//! its path (by G instead of z) and keeps the highest (the highest G is the highest point).
//!
//! **A spread of directions.** What lands falls with the flux-weighted distribution of flake
//! sizes ([`crate::physics::snow::Snowfall`]: N(D)·m(D)·v(D)), each at its own fall speed, and
//! through gusts: each horizontal component of the wind above the roofs varies about its mean
//! with a standard deviation of `turbulence` times the mean speed (default 0.4: over cities
//! σ_u ≈ 2.4 u* and σ_v ≈ 1.9 u* (M. Roth, *Review of atmospheric turbulence over cities*,
//! QJRMS 126, 2000), and u* ≈ 0.17 of the wind 10 m above a town's displacement height
//! (κ / ln(10 m / z₀) for z₀ = 1 m), so σ ≈ 0.3–0.4 of the mean). A gust is taken as lasting
//! the whole fall (its path is straight in G), so the spread is an upper bound for long falls.
//! Each step draws [`DIRECTIONS`] paths, equal in weight: the sizes at stratified quantiles of
//! the flux, the gusts from a 2-D low-discrepancy sequence through Box–Muller, both rotated from
//! step to step so a run's steps together sample the spread finely. Deterministic: the same
//! step gives the same paths, with no seed.

use super::heightfield::HeightField;
use crate::physics::snow::{Snowfall, flake_fall_speed_m_s, flake_mass_mg, flake_size_mm};

/// Paths drawn per step in wind (in still air: one, straight down).
pub const DIRECTIONS: usize = 8;
/// A cell stands in the canopy when its base is this far above the lowest surface, m.
pub const BUILT_M: f64 = 2.0;
/// Macdonald's a = 9.6 λ_f, held at most this.
pub const ATTENUATION_MAX: f64 = 5.0;
/// Macdonald's a per unit of λ_f.
const ATTENUATION_PER_FRONTAL: f64 = 9.6;
/// The slowest a flake's path may descend, m/s (an updraft stronger than a small flake's fall
/// speed would otherwise hold it up forever; the mean's fall is checked to be downward).
const MIN_DESCENT_M_S: f64 = 0.1;
/// Bins of the flux-weighted size distribution's table.
const SIZE_BINS: usize = 512;

/// Macdonald's canopy over a height field, for one wind direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Canopy {
    /// The lowest surface, m: heights are measured from it.
    pub ground_m: f64,
    /// The canopy's height h above the ground, m (0: no canopy).
    pub height_m: f64,
    /// Macdonald's a (0: no canopy).
    pub attenuation: f64,
    /// λ_f, the frontal area facing the wind per unit of plan area.
    pub frontal_area_index: f64,
}

impl Canopy {
    /// No canopy: the wind is the same at every height.
    pub fn none(ground_m: f64) -> Self {
        Canopy {
            ground_m,
            height_m: 0.0,
            attenuation: 0.0,
            frontal_area_index: 0.0,
        }
    }

    /// The canopy of `field` for a wind along `direction` (horizontal; need not be a unit).
    pub fn of(field: &HeightField, direction: [f64; 2]) -> Self {
        let base = &field.base_m;
        let ground = base
            .iter()
            .filter(|b| !b.is_nan())
            .fold(f64::INFINITY, |m, &b| m.min(b));
        if !ground.is_finite() {
            return Canopy::none(0.0);
        }
        let len = direction[0].hypot(direction[1]);
        if len == 0.0 || !len.is_finite() {
            return Canopy::none(ground);
        }
        let d = [direction[0] / len, direction[1] / len];
        let g = field.grid;
        let (nx, nz, sp) = (g.nx, g.nz, g.spacing_m);
        let (mut built, mut built_height, mut surface, mut frontal) = (0usize, 0.0, 0usize, 0.0);
        let at = |i: isize, k: isize| -> f64 {
            if i < 0 || k < 0 || i >= nx as isize || k >= nz as isize {
                ground
            } else {
                base[k as usize * nx + i as usize]
            }
        };
        let (sx, sz) = (
            if d[0] >= 0.0 { -1 } else { 1 },
            if d[1] >= 0.0 { -1 } else { 1 },
        );
        for k in 0..nz {
            for i in 0..nx {
                let b = base[k * nx + i];
                if b.is_nan() {
                    continue;
                }
                surface += 1;
                if b - ground >= BUILT_M {
                    built += 1;
                    built_height += b - ground;
                }
                let (ii, kk) = (i as isize, k as isize);
                // The rise from the upwind neighbour along each axis, seen across the cell's side.
                for (up, w) in [(at(ii + sx, kk), d[0].abs()), (at(ii, kk + sz), d[1].abs())] {
                    if !up.is_nan() && b > up {
                        frontal += (b - up) * sp * w;
                    }
                }
            }
        }
        if built == 0 || surface == 0 {
            return Canopy::none(ground);
        }
        let lambda_f = frontal / (surface as f64 * sp * sp);
        Canopy {
            ground_m: ground,
            height_m: built_height / built as f64,
            attenuation: (ATTENUATION_PER_FRONTAL * lambda_f).min(ATTENUATION_MAX),
            frontal_area_index: lambda_f,
        }
    }

    fn on(&self) -> bool {
        self.attenuation > 1e-9 && self.height_m > 0.0
    }

    /// The wind at height `y_m` as a share of the wind above the roofs, u(z)/u_h.
    #[inline]
    pub fn wind_share(&self, y_m: f64) -> f64 {
        let z = y_m - self.ground_m;
        if !self.on() || z >= self.height_m {
            1.0
        } else {
            (self.attenuation * (z.max(0.0) / self.height_m - 1.0)).exp()
        }
    }

    /// The lift G at height `y_m`, m: ∫ from the ground of u(z)/u_h dz (z − z_ground with no
    /// canopy; increasing with height).
    #[inline]
    pub fn lift_m(&self, y_m: f64) -> f64 {
        let z = y_m - self.ground_m;
        if !self.on() {
            return z;
        }
        let (a, h) = (self.attenuation, self.height_m);
        let e0 = (-a).exp();
        if z <= 0.0 {
            z * e0
        } else if z < h {
            h / a * ((a * (z / h - 1.0)).exp() - e0)
        } else {
            h / a * (1.0 - e0) + (z - h)
        }
    }
}

/// One path: the horizontal drift per metre of lift, and its share of the snow.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Path {
    /// Horizontal metres per metre of lift (above the roofs: per metre of fall).
    pub drift: [f64; 2],
    /// Share of the step's snow falling along it.
    pub weight: f64,
}

/// The spread of fall directions of one weather: its flakes' fall speeds (a table of the
/// flux-weighted size distribution's quantiles) and its wind.
#[derive(Debug, Clone)]
pub struct FallPaths {
    wind_m_s: [f64; 3],
    turbulence: f64,
    /// The flux share of the flakes smaller than each bin edge (0 to 1).
    cdf: Vec<f64>,
    /// The fall speed of a flake at each bin edge, m/s.
    speed_m_s: Vec<f64>,
}

impl FallPaths {
    /// The paths of `snow_rate_mm_h`'s flakes in `wind_m_s` with gusts of `turbulence`.
    pub fn new(snow_rate_mm_h: f64, wind_m_s: [f64; 3], turbulence: f64) -> Self {
        let fall = Snowfall::new(snow_rate_mm_h);
        let dmax = fall.melted_max_mm();
        let (mut cdf, mut speed) = (Vec::with_capacity(SIZE_BINS + 1), Vec::new());
        let mut acc = 0.0;
        cdf.push(0.0);
        speed.push(flake_fall_speed_m_s(flake_size_mm(0.0)));
        for b in 0..SIZE_BINS {
            let d = (b as f64 + 0.5) / SIZE_BINS as f64 * dmax;
            let v = flake_fall_speed_m_s(flake_size_mm(d));
            acc += fall.density_per_m3_mm(d) * flake_mass_mg(d) * v;
            cdf.push(acc);
            speed.push(flake_fall_speed_m_s(flake_size_mm(
                (b as f64 + 1.0) / SIZE_BINS as f64 * dmax,
            )));
        }
        if acc > 0.0 {
            cdf.iter_mut().for_each(|c| *c /= acc);
        }
        FallPaths {
            wind_m_s,
            turbulence,
            cdf,
            speed_m_s: speed,
        }
    }

    /// Whether the wind blows horizontally (else one path, straight down).
    pub fn windy(&self) -> bool {
        self.wind_m_s[0] != 0.0 || self.wind_m_s[2] != 0.0
    }

    /// The fall speed below which the flux share `u` of the snow falls, m/s.
    pub fn fall_speed_at(&self, u: f64) -> f64 {
        let u = u.clamp(0.0, 1.0);
        let j = self
            .cdf
            .partition_point(|&c| c < u)
            .clamp(1, self.cdf.len() - 1);
        let (c0, c1) = (self.cdf[j - 1], self.cdf[j]);
        let t = if c1 > c0 { (u - c0) / (c1 - c0) } else { 1.0 };
        self.speed_m_s[j - 1] + t * (self.speed_m_s[j] - self.speed_m_s[j - 1])
    }

    /// The paths of step `step`: [`DIRECTIONS`] of equal weight in wind, one in still air.
    pub fn step(&self, step: usize) -> Vec<Path> {
        if !self.windy() {
            return vec![Path {
                drift: [0.0, 0.0],
                weight: 1.0,
            }];
        }
        let w = self.wind_m_s;
        let speed = w[0].hypot(w[2]);
        let sigma = self.turbulence * speed;
        let frac = |x: f64| x - x.floor();
        (0..DIRECTIONS)
            .map(|j| {
                let n = (step * DIRECTIONS + j) as f64;
                let u_size = frac(
                    (j as f64 + 0.5) / DIRECTIONS as f64 + step as f64 * 0.618_033_988_749_894_8,
                );
                let vf = self.fall_speed_at(u_size);
                // R2 sequence (Roberts 2018) through Box–Muller: a Gaussian gust per component.
                let u1 = frac(0.5 + n * 0.754_877_666_246_692_7);
                let u2 = frac(0.5 + n * 0.569_840_290_998_053_3);
                let r = (-2.0 * (1.0 - u1).ln()).sqrt();
                let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
                let gust = [sigma * r * c, sigma * r * s];
                let descent = (vf - w[1]).max(MIN_DESCENT_M_S);
                Path {
                    drift: [(w[0] + gust[0]) / descent, (w[2] + gust[1]) / descent],
                    weight: 1.0 / DIRECTIONS as f64,
                }
            })
            .collect()
    }
}
