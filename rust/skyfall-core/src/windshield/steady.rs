//! A glass in its steady state, drawn statistically instead of stepped there.
//!
//! A preset's glass settles only after tens of wiper periods of rain (the unswept glass fills
//! until its drops grow large enough to slide), minutes of stepping. Its state at the start of
//! a period is, statistically, the same from then on: a [`SteadyTable`] holds it, measured
//! from long simulations (`benches/windshield_steady.py`): for each kind of drop (mesh, trail,
//! particle) the expected number in each `cell_mm` square of the glass, and the distribution of
//! their masses over `block` × `block` squares, in log-spaced bins.
//!
//! A draw takes, per square and kind, a Poisson number of drops at uniform points of the square,
//! each with a mass from its block's distribution (log-uniform within a bin). Mesh and trail
//! drops are placed largest first and only where they keep the simulation's own invariants: one
//! drop per cell of the mesh, and no two mesh drops whose base discs touch (they would merge at
//! once); a drop that finds no such point in [`PLACE_TRIES`] tries in its square tries twice as
//! many in the 3 × 3 squares around it, and is left out after those. Particles are placed as
//! drawn, then spaced by [`RELAX_PASSES`] passes of the wipers' push-apart (a step
//! makes two).

use super::sim::{
    EMPTY, MAX_SUBSTEP_S, MeshDrop, ParticleDrop, SUB_METABALL_S, Windshield, WindshieldConfig,
    WindshieldState,
};
use crate::error::{Error, Param, Result};
use rand::{Rng, SeedableRng};

/// How many points a mesh or trail drop tries in its square (then twice as many around it).
pub const PLACE_TRIES: usize = 12;
/// Push-apart passes over the drawn particles (the simulation makes two a step).
pub const RELAX_PASSES: usize = 8;
/// The kinds of a table, in its order: mesh drops, trail drops, particles.
pub const KINDS: usize = 3;
const KEY_STEADY: u64 = 0x5749_4e44_0003;

/// A glass's steady state at the start of a wiper period, as statistics.
#[derive(Debug, Clone, PartialEq)]
pub struct SteadyTable {
    /// The squares' side, mm.
    pub cell_mm: f64,
    /// Squares across the glass (the last column and row of squares may overhang its edges).
    pub nx: usize,
    /// Squares down the glass.
    pub ny: usize,
    /// Squares per side of a block that shares one mass distribution.
    pub block: usize,
    /// The mass bins' edges, kg, increasing and positive (bins + 1 of them).
    pub mass_edges_kg: Vec<f64>,
    /// Expected drops per square, `[kind][y][x]`.
    pub counts: Vec<f64>,
    /// Mass distribution (weights, any scale) per block, `[kind][by][bx][bin]`.
    pub mass_weights: Vec<f64>,
}

/// What a draw left out.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DrawReport {
    /// Mesh and trail drops drawn but not placed (no free point in 3 × [`PLACE_TRIES`] tries).
    pub left_out: usize,
    /// Their water, kg.
    pub left_out_kg: f64,
    /// Drops placed, particles included.
    pub placed: usize,
}

fn invalid(name: &'static str, message: String) -> Error {
    Error::Invalid {
        param: Param { name, index: None },
        message,
    }
}

impl SteadyTable {
    fn blocks(&self) -> (usize, usize) {
        (self.nx.div_ceil(self.block), self.ny.div_ceil(self.block))
    }

    fn bins(&self) -> usize {
        self.mass_edges_kg.len().saturating_sub(1)
    }

    /// Checks the table's shape and values, and that it covers `config`'s glass.
    pub fn validate(&self, config: &WindshieldConfig) -> Result<()> {
        if !(self.cell_mm.is_finite() && self.cell_mm > 0.0) {
            return Err(invalid(
                "cell_mm",
                format!("{} is not a positive size", self.cell_mm),
            ));
        }
        if self.block == 0 || self.nx == 0 || self.ny == 0 {
            return Err(invalid("table", "has no squares or blocks".into()));
        }
        let (want_x, want_y) = (
            (config.width_mm / self.cell_mm).ceil() as usize,
            (config.height_mm / self.cell_mm).ceil() as usize,
        );
        if (self.nx, self.ny) != (want_x, want_y) {
            return Err(invalid(
                "table",
                format!(
                    "has {} x {} squares of {} mm; the {} x {} mm glass needs {want_x} x {want_y}",
                    self.nx, self.ny, self.cell_mm, config.width_mm, config.height_mm
                ),
            ));
        }
        let e = &self.mass_edges_kg;
        if e.len() < 2
            || !e.iter().all(|m| m.is_finite() && *m > 0.0)
            || e.windows(2).any(|w| w[1] <= w[0])
        {
            return Err(invalid(
                "mass_edges_kg",
                "must be at least two increasing positive masses".into(),
            ));
        }
        if self.counts.len() != KINDS * self.nx * self.ny {
            return Err(invalid(
                "counts",
                format!(
                    "has {} values, not {KINDS} x {} x {}",
                    self.counts.len(),
                    self.ny,
                    self.nx
                ),
            ));
        }
        let (bx, by) = self.blocks();
        if self.mass_weights.len() != KINDS * bx * by * self.bins() {
            return Err(invalid(
                "mass_weights",
                format!(
                    "has {} values, not {KINDS} x {by} x {bx} x {}",
                    self.mass_weights.len(),
                    self.bins()
                ),
            ));
        }
        if !self
            .counts
            .iter()
            .chain(&self.mass_weights)
            .all(|v| v.is_finite() && *v >= 0.0)
        {
            return Err(invalid(
                "table",
                "has a negative or non-finite count or weight".into(),
            ));
        }
        Ok(())
    }

    /// The cumulative mass distribution of each block and kind, and each kind's over the whole
    /// glass (for a block whose own is empty).
    fn cdfs(&self) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        let (bx, by) = self.blocks();
        let nb = self.bins();
        let cum = |w: &[f64]| -> Vec<f64> {
            let mut acc = 0.0;
            w.iter()
                .map(|v| {
                    acc += v;
                    acc
                })
                .collect()
        };
        let mut blocks = Vec::with_capacity(KINDS * bx * by);
        let mut whole = Vec::with_capacity(KINDS);
        for k in 0..KINDS {
            let mut sum = vec![0.0; nb];
            for b in 0..bx * by {
                let w = &self.mass_weights[(k * bx * by + b) * nb..][..nb];
                for (s, v) in sum.iter_mut().zip(w) {
                    *s += v;
                }
                blocks.push(cum(w));
            }
            whole.push(cum(&sum));
        }
        (blocks, whole)
    }
}

/// A Poisson draw of mean `lambda` (Knuth's product of uniforms, in parts of mean ≤ 20).
fn poisson(lambda: f64, rng: &mut rand_pcg::Pcg64Mcg) -> usize {
    let parts = (lambda / 20.0).ceil().max(1.0) as usize;
    let limit = (-lambda / parts as f64).exp();
    let mut n = 0;
    for _ in 0..parts {
        let mut p = rng.random::<f64>();
        while p > limit {
            n += 1;
            p *= rng.random::<f64>();
        }
    }
    n
}

/// A mass from a cumulative distribution over the bins of `edges`, log-uniform within its bin;
/// `None` when the distribution is empty.
fn mass_from(cdf: &[f64], edges: &[f64], rng: &mut rand_pcg::Pcg64Mcg) -> Option<f64> {
    let total = *cdf.last()?;
    if total <= 0.0 {
        return None;
    }
    let u = rng.random::<f64>() * total;
    let b = cdf.partition_point(|&c| c <= u).min(cdf.len() - 1);
    let (lo, hi) = (edges[b].ln(), edges[b + 1].ln());
    Some((lo + rng.random::<f64>() * (hi - lo)).exp())
}

/// A drop drawn, before it is placed.
struct Drawn {
    kind: usize,
    square: usize,
    mass_kg: f64,
}

impl Windshield {
    /// A glass of `config` in the steady state `table` describes, at `t_s` (a whole number of
    /// wiper periods into the rain: the table's phase), drawn from `config.seed`; with what the
    /// draw left out. Its step count (each step's draws are seeded by it) is that of a glass
    /// stepped to `t_s` at [`MAX_SUBSTEP_S`].
    pub fn drawn_steady(
        config: WindshieldConfig,
        table: &SteadyTable,
        t_s: f64,
    ) -> Result<(Self, DrawReport)> {
        table.validate(&config)?;
        let state = WindshieldState {
            t_s,
            steps: (t_s / MAX_SUBSTEP_S).round().max(0.0) as u64,
            ..WindshieldState::default()
        };
        let mut w = Windshield::from_state(config, state)?;
        let mut rng =
            rand_pcg::Pcg64Mcg::seed_from_u64(crate::seed::derive(w.config.seed, &[KEY_STEADY]));
        let (blocks, whole) = table.cdfs();
        let (bx, by) = table.blocks();
        let (nx, ny) = (table.nx, table.ny);
        let mut drawn: Vec<Drawn> = Vec::new();
        for kind in 0..KINDS {
            for square in 0..nx * ny {
                let n = poisson(table.counts[kind * nx * ny + square], &mut rng);
                let block = (square / nx / table.block) * bx + (square % nx) / table.block;
                let cdf = &blocks[kind * bx * by + block];
                for _ in 0..n {
                    let m = mass_from(cdf, &table.mass_edges_kg, &mut rng)
                        .or_else(|| mass_from(&whole[kind], &table.mass_edges_kg, &mut rng));
                    if let Some(mass_kg) = m {
                        drawn.push(Drawn {
                            kind,
                            square,
                            mass_kg,
                        });
                    }
                }
            }
        }
        // the largest first: they find room, the small fill in around them
        drawn.sort_by(|a, b| {
            b.mass_kg
                .total_cmp(&a.mass_kg)
                .then(a.kind.cmp(&b.kind))
                .then(a.square.cmp(&b.square))
        });
        w.a_max_mm = drawn
            .iter()
            .filter(|d| d.kind == 0)
            .map(|d| w.base_radius_mm(d.mass_kg))
            .fold(0.0, f64::max);
        let mut report = DrawReport::default();
        let s = table.cell_mm;
        for d in &drawn {
            let (x0, y0) = ((d.square % nx) as f64 * s, (d.square / nx) as f64 * s);
            let (width, height) = (w.config.width_mm, w.config.height_mm);
            // a point of the square, or (from try PLACE_TRIES on) of the 3 × 3 squares around it
            let point = |rng: &mut rand_pcg::Pcg64Mcg, wide: bool| {
                let (lo_x, lo_y, side) = if wide {
                    (x0 - s, y0 - s, 3.0 * s)
                } else {
                    (x0, y0, s)
                };
                let x = (lo_x + rng.random::<f64>() * side).min(width);
                let y = (lo_y + rng.random::<f64>() * side).min(height);
                (x.max(0.0), y.max(0.0))
            };
            if d.kind == 2 {
                let (x, y) = point(&mut rng, false);
                w.state.particles.push(ParticleDrop {
                    x_mm: x,
                    y_mm: y,
                    mass_kg: d.mass_kg,
                });
                report.placed += 1;
                continue;
            }
            let a = w.base_radius_mm(d.mass_kg);
            let mut placed = false;
            for t in 0..3 * PLACE_TRIES {
                let (x, y) = point(&mut rng, t >= PLACE_TRIES);
                let Some(c) = w.cell_of(x, y) else { continue };
                if w.grid[c] != EMPTY
                    || (d.kind == 0 && !w.touching(usize::MAX, x, y, a).is_empty())
                {
                    continue;
                }
                w.grid[c] = w.state.drops.len() as u32;
                w.state.drops.push(MeshDrop {
                    x_mm: x,
                    y_mm: y,
                    mass_kg: d.mass_kg,
                    budget_mm: 0.0,
                    trail: d.kind == 1,
                    age_s: SUB_METABALL_S,
                    sub_angle_rad: 0.0,
                });
                placed = true;
                break;
            }
            if placed {
                report.placed += 1;
            } else {
                report.left_out += 1;
                report.left_out_kg += d.mass_kg;
            }
        }
        // drawn particles overlap; the sim's have been pushed apart step after step
        for _ in 0..RELAX_PASSES {
            w.push_apart();
        }
        // the water on the glass arrived; none has left yet on this account
        w.state.arrived_kg = w.on_glass_kg();
        w.a_max_mm = w.largest_base_radius_mm();
        Ok((w, report))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn glass() -> WindshieldConfig {
        let mut c = WindshieldConfig::car(100.0, 60.0, 0);
        c.seed = 4;
        c
    }

    /// A table of `per_square` mesh drops a square, all in one mass bin around `mass_kg`.
    fn table(c: &WindshieldConfig, per_square: f64, mass_kg: f64) -> SteadyTable {
        let s = 10.0;
        let (nx, ny) = (
            (c.width_mm / s).ceil() as usize,
            (c.height_mm / s).ceil() as usize,
        );
        let block = 2;
        let (bx, by) = (nx.div_ceil(block), ny.div_ceil(block));
        let edges = vec![mass_kg / 1.1, mass_kg * 1.1];
        let mut counts = vec![0.0; KINDS * nx * ny];
        counts[..nx * ny].fill(per_square);
        SteadyTable {
            cell_mm: s,
            nx,
            ny,
            block,
            mass_edges_kg: edges,
            counts,
            mass_weights: vec![1.0; KINDS * bx * by],
        }
    }

    #[test]
    fn poisson_draws_have_their_mean_and_variance() {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(9);
        for lambda in [0.3, 4.0, 37.0] {
            let n = 40_000;
            let xs: Vec<f64> = (0..n).map(|_| poisson(lambda, &mut rng) as f64).collect();
            let mean = xs.iter().sum::<f64>() / n as f64;
            let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
            // 5 sigma of the sample mean; the variance within 5 %
            assert!(
                (mean - lambda).abs() < 5.0 * (lambda / n as f64).sqrt(),
                "{lambda}: {mean}"
            );
            assert!((var / lambda - 1.0).abs() < 0.05, "{lambda}: {var}");
        }
    }

    #[test]
    fn a_draw_has_the_tables_drops_and_none_touch() {
        let c = glass();
        // 1 mg drops (base radius ~0.9 mm on 40/20 glass): 3 a square, 180 expected
        let t = table(&c, 3.0, 1e-6);
        let (w, report) = Windshield::drawn_steady(c.clone(), &t, 60.0).unwrap();
        let n = w.state().drops.len();
        assert_eq!(report.left_out, 0);
        assert_eq!(report.placed, n);
        // Poisson of mean 180: within 5 sigma
        assert!((n as f64 - 180.0).abs() < 5.0 * 180f64.sqrt(), "{n}");
        let d = &w.state().drops;
        for (i, a) in d.iter().enumerate() {
            assert!(a.mass_kg > 1e-6 / 1.1 && a.mass_kg < 1e-6 * 1.1);
            for b in &d[i + 1..] {
                let sum = w.base_radius_mm(a.mass_kg) + w.base_radius_mm(b.mass_kg);
                assert!((a.x_mm - b.x_mm).hypot(a.y_mm - b.y_mm) >= sum);
            }
        }
        let s = w.state();
        assert_eq!((s.t_s, s.steps), (60.0, 3600));
        assert!((s.arrived_kg - w.on_glass_kg()).abs() <= 1e-15);
        // the same seed, the same bits
        let again = Windshield::drawn_steady(c, &t, 60.0).unwrap().0;
        assert_eq!(again.state(), w.state());
    }

    #[test]
    fn a_crowded_table_leaves_out_what_finds_no_room_and_says_so() {
        let c = glass();
        // 20 drops of 10 mg (base radius ~2 mm) a 10 mm square cannot all lie apart
        let t = table(&c, 20.0, 1e-5);
        let (w, report) = Windshield::drawn_steady(c, &t, 0.0).unwrap();
        assert!(report.left_out > 0);
        let placed: f64 = w.state().drops.iter().map(|d| d.mass_kg).sum();
        assert!(report.left_out_kg > 0.0 && placed > 0.0);
        assert_eq!(report.placed, w.state().drops.len());
    }

    #[test]
    fn a_table_of_another_shape_is_refused_by_name() {
        let c = glass();
        let mut t = table(&c, 1.0, 1e-6);
        t.nx += 1;
        let e = Windshield::drawn_steady(c.clone(), &t, 0.0).unwrap_err();
        assert!(e.to_string().contains("squares"), "{e}");
        let mut t = table(&c, 1.0, 1e-6);
        t.mass_edges_kg = vec![1e-6, 1e-7];
        assert!(Windshield::drawn_steady(c.clone(), &t, 0.0).is_err());
        let mut t = table(&c, 1.0, 1e-6);
        t.counts[0] = f64::NAN;
        assert!(Windshield::drawn_steady(c.clone(), &t, 0.0).is_err());
        let mut t = table(&c, 1.0, 1e-6);
        t.mass_weights.pop();
        assert!(Windshield::drawn_steady(c, &t, 0.0).is_err());
    }
}
