//! The drops on the glass: Gotou, Tanaka & Sagawa's mesh model away from the wipers and their
//! particle model near them, with the conversions between the two, the wipers, and the rain's
//! arrival.
//!
//! Glass coordinates are millimetres: x across the glass (0 at its left edge), y **down** the
//! slope (0 at the top edge, `height_mm` at the bottom), as an image's rows run.
//!
//! One step of `dt`:
//! 1. **arrival**: Marshall–Palmer drops in thin diameter bins (`physics::dsd::BinSampler`)
//!    times the flux through the glass, N(D)·(v(D) cos α + v_car sin α)·A·dt (v(D) Beard's fall
//!    speed, α the tilt from the horizontal, the car driving into the rain), over
//!    [`min_diameter_mm`, 6 mm]; the water of the drops below and above arrives as drops of
//!    those end sizes with the same mass flux, so the whole distribution's water arrives; each
//!    lands at a uniform point as a mesh drop with three sub-metaballs, or fuses with the drop
//!    there; then it merges with every drop its base touches (`merge.rs`).
//! 2. **mesh model**: trail drops shrink (e-folding `trail_lifetime_s`) and vanish below
//!    [`TRAIL_VANISH_KG`] (the mass evaporated); other drops feel gravity along the slope
//!    (m g sin α, down) and the airflow (½ ρ_air C_d (κ v_car)² A_front, up the slope) against
//!    the contact line's retention (Furmidge); above it they slide at the quasi-steady speed
//!    (F − F_ret)/b, with the contact line's viscous friction b = 3π η a ln(a/λ)/θ (de Gennes'
//!    wedge, λ = 1 nm), cell by cell to the cell ahead or a side neighbour, drawn with weights
//!    affinity × cos(step angle), leaving a trail drop in the cell left (probability
//!    `trail_probability`, a `trail_fraction` of the mass); one drop per cell, entering an
//!    occupied cell fuses the two, and at each cell it enters the slider merges with every drop
//!    its base touches. A drop slides up the glass where the airflow beats gravity and the
//!    retention, and down where gravity beats both; across an edge it runs off.
//! 3. **wipers**: a mesh drop the wiper touches or sweeps over becomes round(m/m_p) ≥ 1
//!    equal particles (jittered by a particle radius); a particle the wiper sweeps over is
//!    put in front of it, touching its edge; overlapping particles are pushed apart by half the
//!    overlap each, plus `penalty` times that; a particle outside every wiper's region (the
//!    wiper's rectangle widened by four particle diameters on each side) becomes a mesh drop,
//!    unless a drop of base radius ≥ `hold_radius_mm` lies within the `hold_cells`² cells
//!    around its destination (then it waits).
//!
//! **Merging** (`merge.rs`): a mesh drop whose base disc touches another's (centres closer
//! than the sum of their base radii; trail drops and particles aside) merges with it, the
//! summed mass at the mass-weighted centre, again until it touches none, for every drop that
//! changed (arrived, fused, converted from particles, or entered a cell), so no two mesh drops
//! on the glass overlap after a step.
//!
//! Water leaving the glass across an edge (run off or swept off) is counted in
//! `swept_off_kg`, so on glass + swept off + evaporated = arrived, to rounding.

use super::furmidge::{WATER_DENSITY_KG_M3, Wetting};
use crate::error::{Error, Param, Result};
use crate::physics::GRAVITY_M_S2;
use crate::physics::dsd::BinSampler;
use crate::physics::fall_speed::FallSpeed;
use crate::ranges;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;

/// A trail drop lighter than this has evaporated, kg (a 0.1 mm cap).
pub const TRAIL_VANISH_KG: f64 = 1e-10;
/// How long an impact's three sub-metaballs take to drift into the main one, s.
pub const SUB_METABALL_S: f64 = 0.4;
/// The sub-metaballs' radius relative to the main one.
pub const SUB_RADIUS: f64 = 0.45;
/// Air density at the glass, kg/m³.
const AIR_DENSITY_KG_M3: f64 = 1.2;
/// Water's dynamic viscosity at 20 °C, Pa·s.
const WATER_VISCOSITY_PA_S: f64 = 1.0e-3;
/// The contact line's molecular cut-off λ, m (friction's ln(a/λ)).
const SLIP_LENGTH_M: f64 = 1e-9;
/// Drag coefficient of a drop in the airflow.
const DRAG_COEFFICIENT: f64 = 1.0;
/// The airflow at a drop's height relative to the car's speed (the glass's boundary layer).
const AIRFLOW_FRACTION: f64 = 0.5;
/// Sliding speeds are capped here, m/s.
const MAX_SPEED_M_S: f64 = 2.0;
/// The longest internal step, s: a longer `dt` is split (the wipers move ≤ a few mm a step).
pub const MAX_SUBSTEP_S: f64 = 1.0 / 60.0;
/// Width of the arrival's diameter bins, mm.
const BIN_MM: f64 = 0.1;
/// The largest raindrop that arrives, mm.
const MAX_DIAMETER_MM: f64 = 6.0;
/// Push-apart passes over the particles per step.
const PUSH_PASSES: usize = 2;
/// A particle is pushed by at most this many overlapping neighbours a pass (in the order of
/// their cells and indices): a pile in front of a blade costs O(n), not O(n²).
const MAX_NEIGHBOURS: usize = 12;

/// Ranges of the values that Python leaves at their defaults (no public path, so not in
/// [`ranges::ALL`]); a Rust caller that sets them is checked the same way.
mod local {
    use crate::error::Range;
    pub const AFFINITY_SPREAD: Range = Range::closed(0.0, 0.99, "");
    pub const WIPER_LENGTH_MM: Range = Range::open_closed(0.0, 4000.0, "mm");
    pub const WIPER_WIDTH_MM: Range = Range::open_closed(0.0, 100.0, "mm");
    pub const PIVOT_MM: Range = Range::closed(-1e5, 1e5, "mm");
    pub const PENALTY: Range = Range::closed(0.0, 1.0, "");
    pub const TRAIL_PROBABILITY: Range = Range::closed(0.0, 1.0, "");
    pub const TRAIL_FRACTION: Range = Range::closed(0.0, 0.5, "");
    pub const TRAIL_LIFETIME_S: Range = Range::open_closed(0.0, 1e4, "s");
    pub const HOLD_RADIUS_MM: Range = Range::open_closed(0.0, 100.0, "mm");
    pub const HOLD_CELLS: Range = Range::closed(1.0, 99.0, "").integers();
    pub const MIN_DIAMETER_MM: Range = Range::closed(0.05, 5.0, "mm");
    pub const DROP_MASS_KG: Range = Range::open_closed(0.0, 1e-2, "kg");
}

const KEY_AFFINITY: u64 = 0x5749_4e44_0001;
const KEY_STEP: u64 = 0x5749_4e44_0002;

/// One wiper: a thin rectangle turning about its pivot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wiper {
    /// The pivot, glass mm (x, y); usually just below the bottom edge.
    pub pivot_mm: [f64; 2],
    /// The blade's length from the pivot, mm.
    pub length_mm: f64,
    /// The blade's width, mm.
    pub width_mm: f64,
}

/// Everything that defines a windshield's simulation.
#[derive(Debug, Clone, PartialEq)]
pub struct WindshieldConfig {
    /// Glass width, mm.
    pub width_mm: f64,
    /// Glass height along the slope, mm.
    pub height_mm: f64,
    /// Inclination from the horizontal, deg.
    pub tilt_deg: f64,
    /// The car's speed, m/s (airflow up the glass, and more rain swept into it).
    pub car_speed_m_s: f64,
    /// Rain rate, mm/h.
    pub rain_rate_mm_h: f64,
    /// Grid cell, mm.
    pub cell_mm: f64,
    /// Affinities are uniform in [1 − s, 1 + s].
    pub affinity_spread: f64,
    /// Advancing contact angle, deg.
    pub advancing_deg: f64,
    /// Receding contact angle, deg.
    pub receding_deg: f64,
    /// The wipers (none, one or two).
    pub wipers: Vec<Wiper>,
    /// The wipers' period (there and back), s.
    pub wiper_period_s: f64,
    /// The wipers' angle range from the glass's horizontal (x axis, towards the top), deg.
    pub wiper_angles_deg: [f64; 2],
    /// The particle model's particle base radius, mm.
    pub particle_radius_mm: f64,
    /// The push-apart's penalty coefficient.
    pub penalty: f64,
    /// Probability that a moving drop leaves a trail drop in the cell it leaves.
    pub trail_probability: f64,
    /// The share of the mover's mass a trail drop takes.
    pub trail_fraction: f64,
    /// Trail drops' e-folding lifetime, s.
    pub trail_lifetime_s: f64,
    /// Particles wait while a drop of at least this base radius is near, mm.
    pub hold_radius_mm: f64,
    /// The side of the square of cells searched for such a drop (odd).
    pub hold_cells: usize,
    /// Raindrops smaller than this are not drawn one by one, mm: their water arrives as drops
    /// of this diameter (the same mass flux), so the whole distribution's water arrives.
    pub min_diameter_mm: f64,
    /// The seed of the affinities and of every step's draws.
    pub seed: u64,
}

impl WindshieldConfig {
    /// A car windshield of `width_mm` × `height_mm` with `wipers` (0, 1 or 2) placed as on a
    /// left-hand-drive car: pivots 30 mm below the bottom edge, blades of 0.8 and 0.7 of the
    /// height (one wiper: centred, 0.9), 12 mm wide.
    pub fn car(width_mm: f64, height_mm: f64, wipers: usize) -> Self {
        let below = height_mm + 30.0;
        let wipers = match wipers {
            0 => vec![],
            1 => vec![Wiper {
                pivot_mm: [0.5 * width_mm, below],
                length_mm: 0.9 * height_mm,
                width_mm: 12.0,
            }],
            _ => vec![
                Wiper {
                    pivot_mm: [0.22 * width_mm, below],
                    length_mm: 0.8 * height_mm,
                    width_mm: 12.0,
                },
                Wiper {
                    pivot_mm: [0.62 * width_mm, below],
                    length_mm: 0.7 * height_mm,
                    width_mm: 12.0,
                },
            ],
        };
        WindshieldConfig {
            width_mm,
            height_mm,
            tilt_deg: 30.0,
            car_speed_m_s: 0.0,
            rain_rate_mm_h: 10.0,
            cell_mm: 2.0,
            affinity_spread: 0.5,
            advancing_deg: 40.0,
            receding_deg: 20.0,
            wipers,
            wiper_period_s: 1.5,
            wiper_angles_deg: [5.0, 120.0],
            particle_radius_mm: 1.0,
            penalty: 0.2,
            trail_probability: 0.5,
            trail_fraction: 0.03,
            trail_lifetime_s: 3.0,
            hold_radius_mm: 2.2,
            hold_cells: 7,
            min_diameter_mm: 0.5,
            seed: 0,
        }
    }

    /// Checks every value against its range in [`ranges`].
    pub fn validate(&self) -> Result<()> {
        ranges::GLASS_WIDTH_MM.check(self.width_mm)?;
        ranges::GLASS_HEIGHT_MM.check(self.height_mm)?;
        ranges::GLASS_TILT_DEG.check(self.tilt_deg)?;
        ranges::CAR_SPEED_M_S.check(self.car_speed_m_s)?;
        ranges::RAIN_RATE_MM_H.check(self.rain_rate_mm_h)?;
        ranges::CELL_MM.check(self.cell_mm)?;
        local::AFFINITY_SPREAD.check("affinity_spread", None, self.affinity_spread)?;
        ranges::ADVANCING_DEG.check(self.advancing_deg)?;
        ranges::RECEDING_DEG.check(self.receding_deg)?;
        if self.receding_deg >= self.advancing_deg {
            return Err(Error::Invalid {
                param: Param {
                    name: "receding_deg",
                    index: None,
                },
                message: format!(
                    "receding_deg = {} must be below advancing_deg = {} (a drop with no hysteresis never stays)",
                    self.receding_deg, self.advancing_deg
                ),
            });
        }
        if self.wipers.len() > 2 {
            return Err(Error::Invalid {
                param: Param {
                    name: "wipers",
                    index: None,
                },
                message: format!("{} wipers: 0, 1 or 2 are supported", self.wipers.len()),
            });
        }
        for (i, w) in self.wipers.iter().enumerate() {
            let many = Some(i);
            local::WIPER_LENGTH_MM.check("length_mm", many, w.length_mm)?;
            local::WIPER_WIDTH_MM.check("width_mm", many, w.width_mm)?;
            local::PIVOT_MM.check("pivot_mm", many, w.pivot_mm[0])?;
            local::PIVOT_MM.check("pivot_mm", many, w.pivot_mm[1])?;
        }
        ranges::WIPER_PERIOD_S.check(self.wiper_period_s)?;
        ranges::WIPER_ANGLES_DEG.check_at(Some(0), self.wiper_angles_deg[0])?;
        ranges::WIPER_ANGLES_DEG.check_at(Some(1), self.wiper_angles_deg[1])?;
        if self.wiper_angles_deg[0] >= self.wiper_angles_deg[1] {
            return Err(Error::Invalid {
                param: Param {
                    name: "wiper_angles_deg",
                    index: None,
                },
                message: format!(
                    "({}, {}) must be increasing",
                    self.wiper_angles_deg[0], self.wiper_angles_deg[1]
                ),
            });
        }
        ranges::PARTICLE_RADIUS_MM.check(self.particle_radius_mm)?;
        local::PENALTY.check("penalty", None, self.penalty)?;
        local::TRAIL_PROBABILITY.check("trail_probability", None, self.trail_probability)?;
        local::TRAIL_FRACTION.check("trail_fraction", None, self.trail_fraction)?;
        local::TRAIL_LIFETIME_S.check("trail_lifetime_s", None, self.trail_lifetime_s)?;
        local::HOLD_RADIUS_MM.check("hold_radius_mm", None, self.hold_radius_mm)?;
        local::HOLD_CELLS.check("hold_cells", None, self.hold_cells as f64)?;
        if self.hold_cells.is_multiple_of(2) {
            return Err(Error::Invalid {
                param: Param {
                    name: "hold_cells",
                    index: None,
                },
                message: format!(
                    "{} must be odd (a square centred on a cell)",
                    self.hold_cells
                ),
            });
        }
        local::MIN_DIAMETER_MM.check("min_diameter_mm", None, self.min_diameter_mm)?;
        let (nx, ny) = self.grid();
        let cells = nx as u128 * ny as u128;
        if cells > MAX_CELLS as u128 {
            // The ranges of the glass and of cell_mm each allow it; their product is the limit.
            let least =
                ((self.width_mm * self.height_mm / MAX_CELLS as f64).sqrt() * 100.0).ceil() / 100.0;
            return Err(Error::Unusable {
                param: Param {
                    name: "cell_mm",
                    index: None,
                },
                value: self.cell_mm,
                message: format!(
                    "mm makes a glass of {nx} × {ny} = {cells} cells, over the limit of {MAX_CELLS} cells \
                     (glass_width_mm / cell_mm × glass_height_mm / cell_mm): use cell_mm ≥ {least} mm for \
                     this glass, or a smaller glass"
                ),
            });
        }
        Ok(())
    }

    /// The grid's columns and rows.
    pub fn grid(&self) -> (usize, usize) {
        (
            (self.width_mm / self.cell_mm).ceil().max(1.0) as usize,
            (self.height_mm / self.cell_mm).ceil().max(1.0) as usize,
        )
    }

    /// The glass's wetting.
    pub fn wetting(&self) -> Wetting {
        Wetting::from_deg(self.advancing_deg, self.receding_deg)
    }

    /// The wipers' angle at time `t_s`, rad: lo + (hi − lo)(1 − cos 2πt/T)/2.
    pub fn wiper_angle_rad(&self, t_s: f64) -> f64 {
        let [lo, hi] = self.wiper_angles_deg;
        let phase = std::f64::consts::TAU * t_s / self.wiper_period_s;
        (lo + (hi - lo) * 0.5 * (1.0 - phase.cos())).to_radians()
    }

    /// The glass's area, m².
    pub fn area_m2(&self) -> f64 {
        self.width_mm * self.height_mm * 1e-6
    }

    /// Expected raindrops arriving per second on the whole glass (those under
    /// `min_diameter_mm` and over 6 mm counted as the drops their water arrives as).
    pub fn arrivals_per_s(&self) -> f64 {
        (self
            .bins()
            .iter()
            .map(|(b, flux)| b.expected_per_m3() * flux)
            .sum::<f64>()
            + self.lumps().iter().map(|l| l.per_m2_s).sum::<f64>())
            * self.area_m2()
    }

    /// Expected water arriving per second, kg/s (the bins' mean masses).
    pub fn arrival_kg_per_s(&self) -> f64 {
        let mut total = 0.0;
        for (b, flux) in self.bins() {
            // the bin's mean mass by a 16-point midpoint rule over its quantiles
            let mut m = 0.0;
            for k in 0..16 {
                let d = b.diameter_mm((k as f64 + 0.5) / 16.0) * 1e-3;
                m += WATER_DENSITY_KG_M3 * std::f64::consts::PI * d * d * d / 6.0 / 16.0;
            }
            total += b.expected_per_m3() * flux * m;
        }
        for l in self.lumps() {
            total += l.per_m2_s * drop_mass_kg(l.diameter_mm);
        }
        total * self.area_m2()
    }

    /// The drops outside the bins' [`min_diameter_mm`, 6 mm]: their water's flux through the
    /// glass, ∫ N(D)·ρ_w πD³/6·(v(D) cos α + v_car sin α) dD below and above, arrives as drops
    /// of the bins' end diameters (a 6 mm drop's fall speed for the larger ones, which break
    /// up in real rain). Marshall–Palmer's drops under 0.5 mm hold 1.3–7.8 % of the water that
    /// reaches the glass (2 mm/h at 10 m/s: 7.7 %); drawn one by one they would be 5× the drops.
    fn lumps(&self) -> Vec<Lump> {
        if self.rain_rate_mm_h <= 0.0 {
            return vec![];
        }
        let tilt = self.tilt_deg.to_radians();
        let law = FallSpeed::beard_standard();
        let lam = crate::physics::dsd::mp_slope_per_mm(self.rain_rate_mm_h);
        let flux = |d: f64| {
            let v = law.m_s(d.min(MAX_DIAMETER_MM));
            crate::physics::dsd::marshall_palmer(d, self.rain_rate_mm_h)
                * drop_mass_kg(d)
                * (v * tilt.cos() + self.car_speed_m_s * tilt.sin())
        };
        let min = self.min_diameter_mm;
        // (e^(−40) of the tail is left beyond the upper end)
        let top = MAX_DIAMETER_MM + 40.0 / lam;
        [(0.0, min, min), (MAX_DIAMETER_MM, top, MAX_DIAMETER_MM)]
            .iter()
            .map(|&(lo, hi, d)| Lump {
                diameter_mm: d,
                per_m2_s: crate::physics::quadrature::integrate(flux, lo, hi, &[], 64)
                    / drop_mass_kg(d),
            })
            .collect()
    }

    /// The arrival's bins with their flux factor, m/s (drops per m² per s = λ · flux).
    fn bins(&self) -> Vec<(BinSampler, f64)> {
        if self.rain_rate_mm_h <= 0.0 {
            return vec![];
        }
        let tilt = self.tilt_deg.to_radians();
        let law = FallSpeed::beard_standard();
        let mut out = vec![];
        let mut lo = self.min_diameter_mm;
        while lo < MAX_DIAMETER_MM - 1e-9 {
            let hi = (lo + BIN_MM).min(MAX_DIAMETER_MM);
            let b = BinSampler::new(self.rain_rate_mm_h, lo, hi);
            let v = law.m_s(0.5 * (lo + hi));
            out.push((b, v * tilt.cos() + self.car_speed_m_s * tilt.sin()));
            lo = hi;
        }
        out
    }
}

/// The most cells a glass may have (a 4 × 4 m glass of 2 mm cells): glass_width_mm / cell_mm
/// × glass_height_mm / cell_mm, a limit beyond the three ranges, which each say so.
pub const MAX_CELLS: u64 = 4_000_000;

/// What a drop is, for plots and the layers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum DropKind {
    /// A mesh-model drop.
    Mesh = 0,
    /// A mesh-model trail drop (shrinking).
    Trail = 1,
    /// A particle-model drop (near a wiper).
    Particle = 2,
}

/// A mesh-model drop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshDrop {
    /// Position, glass mm.
    pub x_mm: f64,
    /// Position, glass mm (down the slope).
    pub y_mm: f64,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Distance still to travel this step, mm.
    pub budget_mm: f64,
    /// Whether it is a trail drop.
    pub trail: bool,
    /// Time since it landed, s (its sub-metaballs drift in over [`SUB_METABALL_S`]).
    pub age_s: f64,
    /// The sub-metaballs' orientation, rad.
    pub sub_angle_rad: f64,
}

/// A particle-model drop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParticleDrop {
    /// Position, glass mm.
    pub x_mm: f64,
    /// Position, glass mm.
    pub y_mm: f64,
    /// Mass, kg (the mesh drop's mass shared equally among its particles).
    pub mass_kg: f64,
}

/// What a windshield is at one time: everything a resumed run needs besides its config.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct WindshieldState {
    /// Simulated time, s.
    pub t_s: f64,
    /// Internal steps taken (each step's draws are seeded by it).
    pub steps: u64,
    /// The mesh drops.
    pub drops: Vec<MeshDrop>,
    /// The particles.
    pub particles: Vec<ParticleDrop>,
    /// Water that arrived, kg.
    pub arrived_kg: f64,
    /// Water that left across an edge, kg.
    pub swept_off_kg: f64,
    /// Water evaporated from trails, kg.
    pub evaporated_kg: f64,
}

/// A drop (main metaball) or sub-metaball, for rendering.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Metaball {
    /// Centre, glass mm.
    pub x_mm: f64,
    /// Centre, glass mm.
    pub y_mm: f64,
    /// Radius R, mm (the thresholded shape's radius).
    pub radius_mm: f64,
}

/// A simulated windshield.
#[derive(Debug, Clone)]
pub struct Windshield {
    pub(super) config: WindshieldConfig,
    wetting: Wetting,
    /// `wetting.volume_per_a3()`, kept: a drop's base radius is asked for per drop and step.
    volume_per_a3: f64,
    pub(super) nx: usize,
    pub(super) ny: usize,
    affinity: Vec<f32>,
    /// Index into `state.drops` per cell; `EMPTY` where none.
    pub(super) grid: Vec<u32>,
    bins: Vec<(BinSampler, f64)>,
    lumps: Vec<Lump>,
    pub(super) state: WindshieldState,
    /// An upper bound on every mesh drop's base radius, mm (the merge's search reach).
    pub(super) a_max_mm: f64,
    /// No drop lighter than this slides, kg ([`Self::least_sliding_mass_kg`]).
    slide_min_kg: f64,
}

/// Drops of one diameter that carry the water of those outside the arrival's bins.
#[derive(Debug, Clone, Copy)]
struct Lump {
    diameter_mm: f64,
    /// Drops per m² of glass per s.
    per_m2_s: f64,
}

/// A drop's mass, kg.
fn drop_mass_kg(diameter_mm: f64) -> f64 {
    let d = diameter_mm * 1e-3;
    WATER_DENSITY_KG_M3 * std::f64::consts::PI * d * d * d / 6.0
}

/// A cell without a drop.
pub(super) const EMPTY: u32 = u32::MAX;

impl Windshield {
    /// A dry windshield at t = 0.
    pub fn new(config: WindshieldConfig) -> Result<Self> {
        Self::from_state(config, WindshieldState::default())
    }

    /// A windshield resumed from `state` (as [`Windshield::state`] gave it).
    pub fn from_state(config: WindshieldConfig, state: WindshieldState) -> Result<Self> {
        config.validate()?;
        ranges::TIME_S.check(state.t_s)?;
        let (nx, ny) = config.grid();
        let mut rng =
            rand_pcg::Pcg64Mcg::seed_from_u64(crate::seed::derive(config.seed, &[KEY_AFFINITY]));
        let s = config.affinity_spread;
        let affinity = (0..nx * ny)
            .map(|_| (1.0 - s + 2.0 * s * rng.random::<f64>()).max(1e-3) as f32)
            .collect();
        let mut w = Windshield {
            wetting: config.wetting(),
            volume_per_a3: config.wetting().volume_per_a3(),
            bins: config.bins(),
            lumps: config.lumps(),
            nx,
            ny,
            affinity,
            grid: crate::error::try_filled("the windshield's grid", nx * ny, EMPTY)?,
            config,
            state,
            a_max_mm: 0.0,
            slide_min_kg: 0.0,
        };
        w.slide_min_kg = w.least_sliding_mass_kg();
        for (i, d) in w.state.drops.iter().enumerate() {
            let fine = d.mass_kg.is_finite() && d.mass_kg > 0.0;
            let c = w.cell_of(d.x_mm, d.y_mm);
            match (fine, c) {
                (true, Some(c)) if w.grid[c] == EMPTY => w.grid[c] = i as u32,
                _ => {
                    return Err(Error::Invalid {
                        param: Param {
                            name: "state",
                            index: Some(i),
                        },
                        message: format!(
                            "drop at ({}, {}) mm of {} kg is off the glass, not positive or shares its cell",
                            d.x_mm, d.y_mm, d.mass_kg
                        ),
                    });
                }
            }
        }
        w.a_max_mm = w.largest_base_radius_mm();
        Ok(w)
    }

    /// The configuration.
    pub fn config(&self) -> &WindshieldConfig {
        &self.config
    }

    /// The state (to save, and to resume with [`Windshield::from_state`]).
    pub fn state(&self) -> &WindshieldState {
        &self.state
    }

    /// Water on the glass, kg.
    pub fn on_glass_kg(&self) -> f64 {
        self.state.drops.iter().map(|d| d.mass_kg).sum::<f64>()
            + self.state.particles.iter().map(|p| p.mass_kg).sum::<f64>()
    }

    /// The cell under (x, y) mm, None off the glass.
    pub(super) fn cell_of(&self, x_mm: f64, y_mm: f64) -> Option<usize> {
        let (i, j) = (x_mm / self.config.cell_mm, y_mm / self.config.cell_mm);
        if i >= 0.0 && j >= 0.0 && (i as usize) < self.nx && (j as usize) < self.ny {
            Some(j as usize * self.nx + i as usize)
        } else {
            None
        }
    }

    fn cell_centre(&self, c: usize) -> (f64, f64) {
        let s = self.config.cell_mm;
        (
            ((c % self.nx) as f64 + 0.5) * s,
            ((c / self.nx) as f64 + 0.5) * s,
        )
    }

    /// A drop's base radius, mm.
    pub fn base_radius_mm(&self, mass_kg: f64) -> f64 {
        self.base_radius_m(mass_kg / WATER_DENSITY_KG_M3) * 1e3
    }

    /// The base radius a, m, of a cap of volume `volume_m3` ([`Wetting::base_radius_m`] from
    /// the kept volume per a³).
    fn base_radius_m(&self, volume_m3: f64) -> f64 {
        super::furmidge::cap_base_radius_m(volume_m3, self.volume_per_a3)
    }

    /// The largest mesh drop's base radius, mm (0 on dry glass).
    pub(super) fn largest_base_radius_mm(&self) -> f64 {
        let m = self
            .state
            .drops
            .par_iter()
            .map(|d| d.mass_kg)
            .reduce(|| 0.0, f64::max);
        if m > 0.0 { self.base_radius_mm(m) } else { 0.0 }
    }

    fn particle_mass_kg(&self) -> f64 {
        WATER_DENSITY_KG_M3
            * self
                .wetting
                .volume_m3(self.config.particle_radius_mm * 1e-3)
    }

    /// Every drop: (x mm, y mm, base radius mm, kind), mesh drops first, then particles.
    pub fn drops(&self) -> Vec<(f64, f64, f64, DropKind)> {
        let mut out: Vec<_> = self
            .state
            .drops
            .iter()
            .map(|d| {
                let kind = if d.trail {
                    DropKind::Trail
                } else {
                    DropKind::Mesh
                };
                (d.x_mm, d.y_mm, self.base_radius_mm(d.mass_kg), kind)
            })
            .collect();
        out.extend(self.state.particles.iter().map(|p| {
            (
                p.x_mm,
                p.y_mm,
                self.base_radius_mm(p.mass_kg),
                DropKind::Particle,
            )
        }));
        out
    }

    /// Every metaball: each drop's main one (radius = its base radius) and, for
    /// [`SUB_METABALL_S`] after an impact, three sub-metaballs drifting into it.
    pub fn metaballs(&self) -> Vec<Metaball> {
        let mut out = Vec::with_capacity(self.state.drops.len() + self.state.particles.len());
        for (x_mm, y_mm, radius_mm, _) in self.drops() {
            out.push(Metaball {
                x_mm,
                y_mm,
                radius_mm,
            });
        }
        for d in &self.state.drops {
            if d.trail || d.age_s >= SUB_METABALL_S {
                continue;
            }
            let a = self.base_radius_mm(d.mass_kg);
            let reach = a * (1.0 - d.age_s / SUB_METABALL_S);
            for k in 0..3 {
                let phi = d.sub_angle_rad + k as f64 * std::f64::consts::TAU / 3.0;
                out.push(Metaball {
                    x_mm: d.x_mm + reach * phi.cos(),
                    y_mm: d.y_mm + reach * phi.sin(),
                    radius_mm: SUB_RADIUS * a,
                });
            }
        }
        out
    }

    /// The wipers' angle now, rad.
    pub fn wiper_angle_rad(&self) -> f64 {
        self.config.wiper_angle_rad(self.state.t_s)
    }

    /// Advances by `dt_s` (split into steps of at most [`MAX_SUBSTEP_S`]).
    pub fn step(&mut self, dt_s: f64) -> Result<()> {
        ranges::DT_S.check(dt_s)?;
        let n = (dt_s / MAX_SUBSTEP_S).ceil().max(1.0) as usize;
        let h = dt_s / n as f64;
        for _ in 0..n {
            self.substep(h);
        }
        Ok(())
    }

    /// Advances by one internal step of `dt_s`, in (0, [`MAX_SUBSTEP_S`]] (a clock that keeps
    /// its own grid of steps, [`super::clock::GlassClock`]).
    pub fn step_once(&mut self, dt_s: f64) -> Result<()> {
        if !(dt_s > 0.0 && dt_s <= MAX_SUBSTEP_S) {
            return Err(crate::error::Error::OutOfRange {
                param: crate::error::Param {
                    name: "dt_s",
                    index: None,
                },
                value: dt_s,
                range: format!("(0, {MAX_SUBSTEP_S}] s"),
                integer: false,
            });
        }
        self.substep(dt_s);
        Ok(())
    }

    fn substep(&mut self, dt: f64) {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(crate::seed::derive(
            self.config.seed,
            &[KEY_STEP, self.state.steps],
        ));
        let theta0 = self.config.wiper_angle_rad(self.state.t_s);
        let theta1 = self.config.wiper_angle_rad(self.state.t_s + dt);
        self.arrive(dt, &mut rng);
        self.mesh_step(dt, &mut rng);
        if !self.config.wipers.is_empty() {
            self.wipe(theta0, theta1, &mut rng);
        }
        self.compact();
        self.state.t_s += dt;
        self.state.steps += 1;
    }

    fn arrive(&mut self, dt: f64, rng: &mut rand_pcg::Pcg64Mcg) {
        let volume = self.config.area_m2() * dt;
        for k in 0..self.bins.len() {
            let (bin, flux) = self.bins[k];
            let expected = bin.expected_per_m3() * flux * volume;
            let whole = expected.floor();
            let count = whole as usize + usize::from(rng.random::<f64>() < expected - whole);
            for _ in 0..count {
                let d_m = bin.diameter_mm(rng.random::<f64>()) * 1e-3;
                let x = rng.random::<f64>() * self.config.width_mm;
                let y = rng.random::<f64>() * self.config.height_mm;
                let angle = rng.random::<f64>() * std::f64::consts::TAU;
                let mass = WATER_DENSITY_KG_M3 * std::f64::consts::PI * d_m * d_m * d_m / 6.0;
                self.state.arrived_kg += mass;
                self.add_drop(x, y, mass, 0.0, angle);
            }
        }
        let area = self.config.area_m2() * dt;
        for k in 0..self.lumps.len() {
            let lump = self.lumps[k];
            let expected = lump.per_m2_s * area;
            let whole = expected.floor();
            let count = whole as usize + usize::from(rng.random::<f64>() < expected - whole);
            let mass = drop_mass_kg(lump.diameter_mm);
            for _ in 0..count {
                let x = rng.random::<f64>() * self.config.width_mm;
                let y = rng.random::<f64>() * self.config.height_mm;
                let angle = rng.random::<f64>() * std::f64::consts::TAU;
                self.state.arrived_kg += mass;
                self.add_drop(x, y, mass, 0.0, angle);
            }
        }
    }

    /// Puts `mass` at (x, y): a new drop, or fused into the drop of that cell; then it merges
    /// with the drops it touches. Off the glass it is swept off.
    fn add_drop(&mut self, x: f64, y: f64, mass: f64, age_s: f64, angle: f64) {
        let Some(c) = self.cell_of(x, y) else {
            self.state.swept_off_kg += mass;
            return;
        };
        let at = self.grid[c];
        let i = if at == EMPTY {
            self.state.drops.len()
        } else {
            at as usize
        };
        if at == EMPTY {
            self.grid[c] = self.state.drops.len() as u32;
            self.state.drops.push(MeshDrop {
                x_mm: x,
                y_mm: y,
                mass_kg: mass,
                budget_mm: 0.0,
                trail: false,
                age_s,
                sub_angle_rad: angle,
            });
        } else {
            // fused at the mass-weighted centre (in the same cell: a cell is convex)
            let d = &mut self.state.drops[at as usize];
            let m = d.mass_kg + mass;
            d.x_mm = (d.mass_kg * d.x_mm + mass * x) / m;
            d.y_mm = (d.mass_kg * d.y_mm + mass * y) / m;
            d.mass_kg = m;
            d.trail = false;
        }
        self.a_max_mm = self
            .a_max_mm
            .max(self.base_radius_mm(self.state.drops[i].mass_kg));
        self.merge_touching(i);
    }

    /// The driving force along y (down the slope), N, on a drop of `mass` and base radius `a_m`.
    fn drive_n(&self, mass: f64, a_m: f64) -> f64 {
        let tilt = self.config.tilt_deg.to_radians();
        let gravity = mass * GRAVITY_M_S2 * tilt.sin();
        let theta = self.wetting.mean_rad();
        let r_sphere = a_m / theta.sin();
        let front = r_sphere * r_sphere * (theta - theta.sin() * theta.cos());
        let v = AIRFLOW_FRACTION * self.config.car_speed_m_s;
        let air = 0.5 * AIR_DENSITY_KG_M3 * DRAG_COEFFICIENT * v * v * front;
        gravity - air
    }

    /// A mass below which no drop slides, kg: the excess of the driving force over the
    /// retention, per base radius, |g a² − c a| − k (gravity ∝ a³, the airflow ∝ a², the
    /// retention ∝ a), is below 0 from a = 0 up to its first root, so the largest mass of a
    /// log scan from 1 ng (steps of 1 %, about 2 000 of them) below the first one that slides,
    /// less 1 %, is such a mass.
    fn least_sliding_mass_kg(&self) -> f64 {
        let mut m = 1e-12;
        let mut last = 0.0;
        while m < 1.0 {
            if self.slide_speed_m_s(m) != 0.0 {
                return last * 0.99;
            }
            last = m;
            m *= 1.01;
        }
        last * 0.99
    }

    /// The quasi-steady sliding speed, m/s (signed along y), of a drop of `mass`.
    pub fn slide_speed_m_s(&self, mass: f64) -> f64 {
        let a = self.base_radius_m(mass / WATER_DENSITY_KG_M3);
        let f = self.drive_n(mass, a);
        let excess = f.abs() - self.wetting.retention_n(a);
        if excess <= 0.0 || a <= SLIP_LENGTH_M {
            return 0.0;
        }
        let b = 3.0 * std::f64::consts::PI * WATER_VISCOSITY_PA_S * a * (a / SLIP_LENGTH_M).ln()
            / self.wetting.mean_rad();
        (excess / b).min(MAX_SPEED_M_S).copysign(f)
    }

    fn mesh_step(&mut self, dt: f64, rng: &mut rand_pcg::Pcg64Mcg) {
        let decay = (-dt / self.config.trail_lifetime_s).exp();
        let n = self.state.drops.len();
        // the merge's reach, exact again (merges only raise it within a step)
        self.a_max_mm = self.largest_base_radius_mm();
        // speeds first, in parallel (they read only each drop's own mass)
        let speeds: Vec<f64> = self
            .state
            .drops
            .par_iter()
            .map(|d| {
                if d.trail || d.mass_kg < self.slide_min_kg {
                    0.0
                } else {
                    self.slide_speed_m_s(d.mass_kg)
                }
            })
            .collect();
        for (i, &u) in speeds.iter().enumerate().take(n) {
            let d = self.state.drops[i];
            if d.mass_kg <= 0.0 {
                continue;
            }
            self.state.drops[i].age_s += dt;
            if d.trail {
                let m = d.mass_kg * decay;
                if m < TRAIL_VANISH_KG {
                    self.state.evaporated_kg += d.mass_kg;
                    self.kill(i);
                } else {
                    self.state.evaporated_kg += d.mass_kg - m;
                    self.state.drops[i].mass_kg = m;
                }
                continue;
            }
            if u == 0.0 {
                self.state.drops[i].budget_mm = 0.0;
                continue;
            }
            self.state.drops[i].budget_mm += u.abs() * dt * 1e3;
            self.walk(i, u.signum() as i64, rng);
        }
    }

    /// Moves drop `i` cell by cell along `dir` (±1 in y) while its budget lasts.
    fn walk(&mut self, i: usize, dir: i64, rng: &mut rand_pcg::Pcg64Mcg) {
        let s = self.config.cell_mm;
        loop {
            let d = self.state.drops[i];
            if d.budget_mm < s || d.mass_kg <= 0.0 {
                return;
            }
            let Some(c) = self.cell_of(d.x_mm, d.y_mm) else {
                return;
            };
            let (cx, cy) = ((c % self.nx) as i64, (c / self.nx) as i64);
            let ty = cy + dir;
            // the cell ahead and its two side neighbours, weighted by affinity × cos(angle)
            let mut w = [0.0f64; 3];
            for (k, dx) in [-1i64, 0, 1].into_iter().enumerate() {
                let tx = cx + dx;
                let cosine = if dx == 0 {
                    1.0
                } else {
                    std::f64::consts::FRAC_1_SQRT_2
                };
                let aff =
                    if tx >= 0 && ty >= 0 && (tx as usize) < self.nx && (ty as usize) < self.ny {
                        self.affinity[ty as usize * self.nx + tx as usize] as f64
                    } else {
                        1.0
                    };
                w[k] = aff * cosine;
            }
            let total = w[0] + w[1] + w[2];
            let u = rng.random::<f64>() * total;
            let k = if u < w[0] {
                0
            } else if u < w[0] + w[1] {
                1
            } else {
                2
            };
            let dx = k as i64 - 1;
            let tx = cx + dx;
            let step = if dx == 0 {
                s
            } else {
                s * std::f64::consts::SQRT_2
            };
            self.state.drops[i].budget_mm -= step;
            // leave a trail drop behind
            let leave_trail = rng.random::<f64>() < self.config.trail_probability;
            let mut mass = d.mass_kg;
            self.grid[c] = EMPTY;
            if leave_trail {
                let m = self.config.trail_fraction * mass;
                if m >= TRAIL_VANISH_KG {
                    mass -= m;
                    self.grid[c] = self.state.drops.len() as u32;
                    self.state.drops.push(MeshDrop {
                        x_mm: d.x_mm,
                        y_mm: d.y_mm,
                        mass_kg: m,
                        budget_mm: 0.0,
                        trail: true,
                        age_s: SUB_METABALL_S,
                        sub_angle_rad: 0.0,
                    });
                }
            }
            self.state.drops[i].mass_kg = mass;
            if tx < 0 || ty < 0 || tx as usize >= self.nx || ty as usize >= self.ny {
                // off the glass: run off
                self.state.swept_off_kg += mass;
                self.state.drops[i].mass_kg = 0.0;
                return;
            }
            let t = ty as usize * self.nx + tx as usize;
            let (x, y) = self.cell_centre(t);
            self.state.drops[i].x_mm = x;
            self.state.drops[i].y_mm = y;
            let at = self.grid[t];
            if at == EMPTY {
                self.grid[t] = i as u32;
            } else {
                // fusion: the mover takes the occupant's mass and place
                let j = at as usize;
                let absorbed = self.state.drops[j].mass_kg;
                self.state.drops[j].mass_kg = 0.0;
                self.state.drops[i].mass_kg += absorbed;
                self.grid[t] = i as u32;
                self.a_max_mm = self
                    .a_max_mm
                    .max(self.base_radius_mm(self.state.drops[i].mass_kg));
            }
            // and with every drop it now touches
            self.merge_touching(i);
        }
    }

    pub(super) fn kill(&mut self, i: usize) {
        let d = self.state.drops[i];
        if let Some(c) = self.cell_of(d.x_mm, d.y_mm)
            && self.grid[c] == i as u32
        {
            self.grid[c] = EMPTY;
        }
        self.state.drops[i].mass_kg = 0.0;
    }

    /// Drops the dead (mass 0) and renumbers the grid.
    fn compact(&mut self) {
        let drops = std::mem::take(&mut self.state.drops);
        let mut kept = Vec::with_capacity(drops.len());
        for d in drops {
            if d.mass_kg > 0.0 {
                kept.push(d);
            }
        }
        for (i, d) in kept.iter().enumerate() {
            if let Some(c) = self.cell_of(d.x_mm, d.y_mm) {
                self.grid[c] = i as u32;
            }
        }
        self.state.drops = kept;
        self.state.particles.retain(|p| p.mass_kg > 0.0);
    }

    /// (x, y) relative to wiper `w`'s pivot: (dx, dy, ρ) mm, dy towards the top, ρ the
    /// distance.
    #[inline]
    fn offset(w: &Wiper, x: f64, y: f64) -> (f64, f64, f64) {
        let (dx, dy) = (x - w.pivot_mm[0], w.pivot_mm[1] - y);
        (dx, dy, (dx * dx + dy * dy).sqrt())
    }

    /// Polar coordinates (ρ mm, φ rad) of (x, y) about wiper `w`'s pivot (φ from the glass's
    /// x axis towards the top).
    fn polar(w: &Wiper, x: f64, y: f64) -> (f64, f64) {
        let (dx, dy, rho) = Self::offset(w, x, y);
        (rho, dy.atan2(dx))
    }

    fn from_polar(w: &Wiper, rho: f64, phi: f64) -> (f64, f64) {
        (
            w.pivot_mm[0] + rho * phi.cos(),
            w.pivot_mm[1] - rho * phi.sin(),
        )
    }

    /// Whether a point at distance `rho` mm from wiper `w`'s pivot lies within `margin` mm of
    /// its reach: outside it a point is never swept with that margin or a smaller one.
    fn within_reach(w: &Wiper, rho: f64, margin: f64) -> bool {
        rho <= w.length_mm + margin && rho > 1e-9
    }

    /// Whether (x, y) lies within `margin` mm of wiper `w`'s blade at `theta`, or was swept
    /// over between `theta0` and `theta1`.
    fn swept(w: &Wiper, x: f64, y: f64, theta0: f64, theta1: f64, margin: f64) -> bool {
        // ρ first: most drops lie beyond a blade's reach, and the angle costs an atan2.
        let (dx, dy, rho) = Self::offset(w, x, y);
        if !Self::within_reach(w, rho, margin) {
            return false;
        }
        let phi = dy.atan2(dx);
        let m = ((0.5 * w.width_mm + margin) / rho).min(std::f64::consts::PI);
        let (lo, hi) = (theta0.min(theta1) - m, theta0.max(theta1) + m);
        phi >= lo && phi <= hi
    }

    fn in_region(&self, w: &Wiper, x: f64, y: f64, theta: f64) -> bool {
        let half = 0.5 * w.width_mm + 8.0 * self.config.particle_radius_mm;
        let (dx, dy, _) = Self::offset(w, x, y);
        let (c, s) = (theta.cos(), theta.sin());
        let along = dx * c + dy * s;
        let across = -dx * s + dy * c;
        along >= 0.0 && along <= w.length_mm && across.abs() <= half
    }

    fn wipe(&mut self, theta0: f64, theta1: f64, rng: &mut rand_pcg::Pcg64Mcg) {
        let r = self.config.particle_radius_mm;
        let m_p = self.particle_mass_kg();
        let wipers = self.config.wipers.clone();
        // mesh -> particles: drops the blades touch or sweep over (found in parallel); a drop
        // beyond every blade's reach by the largest drop's radius is passed over before its
        // own radius (a cube root) is computed
        let a_max = self.largest_base_radius_mm();
        let touched: Vec<bool> = self
            .state
            .drops
            .par_iter()
            .map(|d| {
                d.mass_kg > 0.0
                    && wipers
                        .iter()
                        .any(|w| Self::within_reach(w, Self::offset(w, d.x_mm, d.y_mm).2, a_max))
                    && {
                        let a = self.base_radius_mm(d.mass_kg);
                        wipers
                            .iter()
                            .any(|w| Self::swept(w, d.x_mm, d.y_mm, theta0, theta1, a))
                    }
            })
            .collect();
        for (i, &hit) in touched.iter().enumerate() {
            if !hit {
                continue;
            }
            let d = self.state.drops[i];
            let n = ((d.mass_kg / m_p).round() as usize).clamp(1, 4096);
            let share = d.mass_kg / n as f64;
            for _ in 0..n {
                let (jx, jy) = if n == 1 {
                    (0.0, 0.0)
                } else {
                    (
                        (2.0 * rng.random::<f64>() - 1.0) * r,
                        (2.0 * rng.random::<f64>() - 1.0) * r,
                    )
                };
                self.state.particles.push(ParticleDrop {
                    x_mm: d.x_mm + jx,
                    y_mm: d.y_mm + jy,
                    mass_kg: share,
                });
            }
            self.kill(i);
        }
        // the blades push the particles they swept over in front of them
        let dir = if theta1 >= theta0 { 1.0 } else { -1.0 };
        let blade = |p: &mut ParticleDrop| {
            for w in &wipers {
                if Self::swept(w, p.x_mm, p.y_mm, theta0, theta1, r) {
                    let (rho, _) = Self::polar(w, p.x_mm, p.y_mm);
                    let m = (0.5 * w.width_mm + r) / rho.max(1e-6);
                    let (x, y) = Self::from_polar(w, rho, theta1 + dir * m);
                    p.x_mm = x;
                    p.y_mm = y;
                }
            }
        };
        self.state.particles.par_iter_mut().for_each(blade);
        for _ in 0..PUSH_PASSES {
            self.push_apart();
            // a push must not put a particle under a blade: out in front again
            self.state.particles.par_iter_mut().for_each(|p| {
                for w in &wipers {
                    if Self::swept(w, p.x_mm, p.y_mm, theta1, theta1, r) {
                        let (rho, _) = Self::polar(w, p.x_mm, p.y_mm);
                        let m = (0.5 * w.width_mm + r) / rho.max(1e-6);
                        let (x, y) = Self::from_polar(w, rho, theta1 + dir * m);
                        p.x_mm = x;
                        p.y_mm = y;
                    }
                }
            });
        }
        // off the glass: swept off; outside every region: back to the mesh, unless held
        let hold_m = self.least_mass_of_radius(self.config.hold_radius_mm);
        let half = (self.config.hold_cells / 2) as i64;
        // each particle's fate against the mesh as it stands, found in parallel: 0 off the
        // glass, 1 kept (in a region, or held), 2 back to the mesh
        let fate: Vec<u8> = self
            .state
            .particles
            .par_iter()
            .map(|p| match self.cell_of(p.x_mm, p.y_mm) {
                None => 0,
                Some(c) => {
                    if wipers
                        .iter()
                        .any(|w| self.in_region(w, p.x_mm, p.y_mm, theta1))
                        || self.big_drop_near(c, half, hold_m)
                    {
                        1
                    } else {
                        2
                    }
                }
            })
            .collect();
        let particles = std::mem::take(&mut self.state.particles);
        let mut kept = Vec::with_capacity(particles.len());
        for (p, f) in particles.into_iter().zip(fate) {
            match f {
                0 => self.state.swept_off_kg += p.mass_kg,
                1 => kept.push(p),
                _ => {
                    // a drop made by an earlier particle of this step holds this one too
                    let held = self
                        .cell_of(p.x_mm, p.y_mm)
                        .is_some_and(|c| self.big_drop_near(c, half, hold_m));
                    if held {
                        kept.push(p);
                    } else {
                        self.add_drop(p.x_mm, p.y_mm, p.mass_kg, SUB_METABALL_S, 0.0);
                    }
                }
            }
        }
        self.state.particles = kept;
    }

    /// Whether a mesh drop of mass ≥ `m_min` (a base radius ≥ `a_mm` when `m_min` is
    /// [`Self::least_mass_of_radius`]`(a_mm)`) lies in the (2·half + 1)² cells around `c`.
    pub fn big_drop_near(&self, c: usize, half: i64, m_min: f64) -> bool {
        let (cx, cy) = ((c % self.nx) as i64, (c / self.nx) as i64);
        for ty in (cy - half).max(0)..=(cy + half).min(self.ny as i64 - 1) {
            for tx in (cx - half).max(0)..=(cx + half).min(self.nx as i64 - 1) {
                let at = self.grid[ty as usize * self.nx + tx as usize];
                if at != EMPTY {
                    let d = &self.state.drops[at as usize];
                    if d.mass_kg > 0.0 && d.mass_kg >= m_min {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// The least mass whose base radius is at least `a_mm`: as the base radius grows with the
    /// mass, `base_radius_mm(m) >= a_mm` exactly where `m >=` this (a bisection over the
    /// positive f64s, which order as their bits), without a cube root per drop.
    pub fn least_mass_of_radius(&self, a_mm: f64) -> f64 {
        if self.base_radius_mm(f64::MAX) < a_mm {
            return f64::INFINITY;
        }
        let (mut lo, mut hi) = (0u64, f64::MAX.to_bits());
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            if self.base_radius_mm(f64::from_bits(mid)) >= a_mm {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        f64::from_bits(lo)
    }

    /// One Jacobi pass of the push-apart: every overlapping pair moves apart along its centre
    /// line by half the overlap each, times (1 + penalty); displacements from the old positions.
    pub(super) fn push_apart(&mut self) {
        let r = self.config.particle_radius_mm;
        let d0 = 2.0 * r;
        let ps = &self.state.particles;
        if ps.len() < 2 {
            return;
        }
        // bucket by cells of one diameter
        let key = |p: &ParticleDrop| ((p.x_mm / d0).floor() as i64, (p.y_mm / d0).floor() as i64);
        let order = sorted_by_cell(ps.iter().map(key).collect());
        // Each row of cells' run of `order` (its first entry), so that a particle finds its
        // three rows with one search among the rows, then its three cells within each row:
        // the same entries, in the same order, as a search of the whole list per cell.
        let mut rows: Vec<(i64, usize)> = Vec::new();
        for (n, &(y, _, _)) in order.iter().enumerate() {
            if rows.last().is_none_or(|r| r.0 != y) {
                rows.push((y, n));
            }
        }
        // The particles' positions in `order`'s order: a particle's candidates are read from
        // contiguous memory, the same values in the same order as from the particle list.
        let at: Vec<(f64, f64, u32)> = order
            .iter()
            .map(|&(_, _, j)| {
                let q = &ps[j as usize];
                (q.x_mm, q.y_mm, j)
            })
            .collect();
        // Per row by − 1 ..= by + 1, cells bx − 1 ..= bx + 1: contiguous in `order`, sorted by
        // (y, x, index).
        let near = |bx: i64, by: i64| -> [&[(f64, f64, u32)]; 3] {
            let mut out: [&[(f64, f64, u32)]; 3] = [&[]; 3];
            let mut k = rows.partition_point(|r| r.0 < by - 1);
            for (o, y) in (by - 1..=by + 1).enumerate() {
                if k < rows.len() && rows[k].0 == y {
                    let (start, end) = (rows[k].1, rows.get(k + 1).map_or(order.len(), |r| r.1));
                    let run = &order[start..end];
                    let lo = run.partition_point(|&(_, x, _)| x < bx - 1);
                    let hi = lo + run[lo..].partition_point(|&(_, x, _)| x <= bx + 1);
                    out[o] = &at[start + lo..start + hi];
                    k += 1;
                }
            }
            out
        };
        let gain = 0.5 * (1.0 + self.config.penalty);
        // One particle's move from its cell's neighbourhood.
        let one = |nb: &[&[(f64, f64, u32)]; 3], (px, py, i): (f64, f64, u32)| {
            let i = i as usize;
            let (mut mx, mut my) = (0.0, 0.0);
            let mut met = 0usize;
            'cells: for run in nb {
                for &(qx, qy, j) in *run {
                    let j = j as usize;
                    if j == i {
                        continue;
                    }
                    let (dx, dy) = (px - qx, py - qy);
                    let d2 = dx * dx + dy * dy;
                    if d2 >= d0 * d0 {
                        continue;
                    }
                    met += 1;
                    if met > MAX_NEIGHBOURS {
                        break 'cells;
                    }
                    let dist = d2.sqrt();
                    let overlap = d0 - dist;
                    let (ux, uy) = if dist > 1e-9 {
                        (dx / dist, dy / dist)
                    } else {
                        // coincident: apart along a direction fixed by the pair
                        let a = if i < j { 0.0 } else { std::f64::consts::PI };
                        (a.cos(), a.sin())
                    };
                    mx += gain * overlap * ux;
                    my += gain * overlap * uy;
                }
            }
            (mx, my)
        };
        // each particle's move, computed in `order`'s order (a cell's particles in turn find
        // its neighbourhood once), then put back in the particles' order
        type Near<'a> = [&'a [(f64, f64, u32)]; 3];
        let sorted: Vec<(f64, f64)> = order
            .par_iter()
            .zip(at.par_iter())
            .map_init(
                || None::<((i64, i64), Near<'_>)>,
                |cache, (&(by, bx, _), &p)| {
                    let nb = match cache {
                        Some((cell, nb)) if *cell == (bx, by) => *nb,
                        _ => {
                            let nb = near(bx, by);
                            *cache = Some(((bx, by), nb));
                            nb
                        }
                    };
                    one(&nb, p)
                },
            )
            .collect();
        let mut moves = vec![(0.0, 0.0); ps.len()];
        for (&(_, _, i), m) in at.iter().zip(sorted) {
            moves[i as usize] = m;
        }
        for (p, (mx, my)) in self.state.particles.iter_mut().zip(moves) {
            p.x_mm += mx;
            p.y_mm += my;
        }
    }

    /// Places a mesh drop (tests and tools): fused as an arrival would be, counted as arrived.
    pub fn place_drop(&mut self, x_mm: f64, y_mm: f64, mass_kg: f64) -> Result<()> {
        local::DROP_MASS_KG.check("mass_kg", None, mass_kg)?;
        if self.cell_of(x_mm, y_mm).is_none() {
            return Err(Error::Invalid {
                param: Param {
                    name: "position_mm",
                    index: None,
                },
                message: format!(
                    "({x_mm}, {y_mm}) is off the glass [0, {}] × [0, {}] mm",
                    self.config.width_mm, self.config.height_mm
                ),
            });
        }
        self.state.arrived_kg += mass_kg;
        self.add_drop(x_mm, y_mm, mass_kg, SUB_METABALL_S, 0.0);
        // the drops it merged with leave the list
        self.compact();
        Ok(())
    }

    /// Places a particle (tests and tools), counted as arrived.
    pub fn place_particle(&mut self, x_mm: f64, y_mm: f64, mass_kg: f64) -> Result<()> {
        local::DROP_MASS_KG.check("mass_kg", None, mass_kg)?;
        self.state.arrived_kg += mass_kg;
        self.state.particles.push(ParticleDrop {
            x_mm,
            y_mm,
            mass_kg,
        });
        Ok(())
    }
}

/// The particles' (cell y, cell x, index) for their cells `keys` (x, y), sorted as sorting the
/// triples would: where their cells' bounding box holds at most 16 cells a particle, counted
/// into those cells in index order; else, where its rows are few, counted into their rows and
/// each row sorted; else sorted whole.
fn sorted_by_cell(keys: Vec<(i64, i64)>) -> Vec<(i64, i64, u32)> {
    let mut out: Vec<(i64, i64, u32)> = keys
        .iter()
        .enumerate()
        .map(|(i, &(x, y))| (y, x, i as u32))
        .collect();
    let n = out.len() as u128;
    let (Some(y0), Some(y1)) = (out.iter().map(|t| t.0).min(), out.iter().map(|t| t.0).max())
    else {
        return out;
    };
    let x0 = out.iter().map(|t| t.1).min().unwrap_or(0);
    let x1 = out.iter().map(|t| t.1).max().unwrap_or(0);
    let (w, rows) = ((x1 - x0) as u128 + 1, (y1 - y0) as u128 + 1);
    // (bucket of a triple, buckets, whether a bucket is one cell)
    let (buckets, cells) = if w * rows <= 16 * n {
        (w * rows, true)
    } else if rows <= 4 * n + 1024 {
        (rows, false)
    } else {
        out.sort_unstable();
        return out;
    };
    let bucket = |t: &(i64, i64, u32)| {
        let r = (t.0 - y0) as usize;
        if cells {
            r * w as usize + (t.1 - x0) as usize
        } else {
            r
        }
    };
    let mut start = vec![0usize; buckets as usize + 1];
    for t in &out {
        start[bucket(t) + 1] += 1;
    }
    for b in 1..start.len() {
        start[b] += start[b - 1];
    }
    let bounds = if cells { Vec::new() } else { start.clone() };
    let mut sorted = vec![(0i64, 0i64, 0u32); out.len()];
    for t in &out {
        let b = bucket(t);
        sorted[start[b]] = *t;
        start[b] += 1;
    }
    for r in bounds.windows(2) {
        sorted[r[0]..r[1]].sort_unstable();
    }
    sorted
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dry(wipers: usize) -> WindshieldConfig {
        let mut c = WindshieldConfig::car(400.0, 300.0, wipers);
        c.rain_rate_mm_h = 0.0;
        c
    }

    fn balance(w: &Windshield) -> (f64, f64) {
        let s = w.state();
        (
            w.on_glass_kg() + s.swept_off_kg + s.evaporated_kg,
            s.arrived_kg,
        )
    }

    #[test]
    fn mass_is_conserved_through_rain_sliding_trails_and_wipers() {
        let mut c = WindshieldConfig::car(500.0, 400.0, 2);
        c.rain_rate_mm_h = 30.0;
        c.wiper_period_s = 1.0;
        let mut w = Windshield::new(c).unwrap();
        // big drops that slide and leave trails
        for k in 0..20 {
            w.place_drop(20.0 + 23.0 * k as f64, 30.0, 6e-5).unwrap();
        }
        for _ in 0..90 {
            w.step(1.0 / 30.0).unwrap();
        }
        let (out, arrived) = balance(&w);
        let s = w.state();
        assert!(
            arrived > 0.0 && s.swept_off_kg > 0.0 && s.evaporated_kg > 0.0,
            "{s:?}"
        );
        assert!(!s.particles.is_empty());
        assert!(
            (out - arrived).abs() <= 1e-9 * arrived,
            "{out} vs {arrived}"
        );
    }

    #[test]
    fn arrivals_match_the_expected_flux() {
        let mut c = dry(0);
        c.rain_rate_mm_h = 20.0;
        c.tilt_deg = 20.0;
        let expected = c.arrival_kg_per_s() * 3.0;
        let mut w = Windshield::new(c).unwrap();
        w.step(1.0).unwrap();
        w.step(1.0).unwrap();
        w.step(1.0).unwrap();
        let got = w.state().arrived_kg;
        assert!((got / expected - 1.0).abs() < 0.1, "{got} vs {expected}");
    }

    #[test]
    fn faster_cars_and_heavier_rain_collect_more() {
        let mut a = dry(0);
        a.rain_rate_mm_h = 2.0;
        let mut b = a.clone();
        b.rain_rate_mm_h = 30.0;
        let mut c = a.clone();
        c.car_speed_m_s = 25.0;
        assert!(b.arrival_kg_per_s() > 5.0 * a.arrival_kg_per_s());
        assert!(c.arrival_kg_per_s() > 3.0 * a.arrival_kg_per_s());
        assert_eq!(dry(0).arrivals_per_s(), 0.0);
    }

    #[test]
    fn two_drops_entering_one_cell_fuse_with_the_summed_mass() {
        let mut w = Windshield::new(dry(0)).unwrap();
        w.place_drop(101.0, 101.0, 2e-6).unwrap();
        w.place_drop(100.5, 100.5, 3e-6).unwrap();
        assert_eq!(w.state().drops.len(), 1);
        assert!((w.state().drops[0].mass_kg - 5e-6).abs() < 1e-18);
        // a sliding drop absorbs a resting one in its path
        let mut w = Windshield::new(dry(0)).unwrap();
        w.config.affinity_spread = 0.0;
        w.place_drop(201.0, 21.0, 5e-5).unwrap();
        w.place_drop(201.0, 31.0, 1e-7).unwrap();
        w.config.trail_probability = 0.0;
        for _ in 0..30 {
            w.step(1.0 / 30.0).unwrap();
        }
        let (out, arrived) = balance(&w);
        assert!((out - arrived).abs() < 1e-15);
        let big: Vec<_> = w
            .state()
            .drops
            .iter()
            .filter(|d| d.mass_kg > 4e-5)
            .collect();
        if let Some(d) = big.first() {
            assert!(d.y_mm > 31.0);
        }
    }

    #[test]
    fn drops_below_the_critical_size_stay_and_above_it_slide() {
        let c = dry(0);
        let wet = c.wetting();
        let a_c = wet.critical_base_radius_m(c.tilt_deg.to_radians());
        let m_c = WATER_DENSITY_KG_M3 * wet.volume_m3(a_c);
        let w = Windshield::new(c).unwrap();
        assert_eq!(w.slide_speed_m_s(0.98 * m_c), 0.0);
        assert!(w.slide_speed_m_s(1.05 * m_c) > 0.0);
    }

    #[test]
    fn counting_particles_into_their_cells_sorts_them_as_sorting_does() {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
        // dense and repeated cells, negative ones, and a spread too wide to count
        for (n, spread) in [(5000, 40i64), (3000, 700), (50, 1_000_000), (1, 3), (0, 3)] {
            let keys: Vec<(i64, i64)> = (0..n)
                .map(|_| {
                    (
                        rng.random_range(-spread / 4..spread),
                        rng.random_range(-3..spread / 2 + 1),
                    )
                })
                .collect();
            let mut want: Vec<(i64, i64, u32)> = keys
                .iter()
                .enumerate()
                .map(|(i, &(x, y))| (y, x, i as u32))
                .collect();
            want.sort_unstable();
            assert_eq!(sorted_by_cell(keys), want, "{n}, {spread}");
        }
    }

    #[test]
    fn no_drop_below_the_least_sliding_mass_slides_and_the_hold_mass_is_the_radius() {
        // still and at 14 m/s (the airflow nearly cancels gravity for mid-sized drops), on
        // 30 and 60 degree glass and level glass: 20 000 masses up to the least sliding mass,
        // each computed in full, stay; just above it, or above Furmidge's size without wind,
        // drops slide
        for (speed, tilt) in [(0.0, 30.0), (14.0, 30.0), (30.0, 60.0), (0.0, 0.0)] {
            let mut c = dry(0);
            c.car_speed_m_s = speed;
            c.tilt_deg = tilt;
            let w = Windshield::new(c).unwrap();
            let m0 = w.slide_min_kg;
            assert!(m0 > 0.0);
            for k in 0..20_000 {
                let m = m0 * (k as f64 / 20_000.0).powi(3);
                assert_eq!(w.slide_speed_m_s(m), 0.0, "{speed} m/s, {tilt} deg, {m} kg");
            }
            if tilt > 0.0 {
                assert!(
                    w.slide_speed_m_s(m0 * 1.03) != 0.0,
                    "{speed} m/s, {tilt} deg"
                );
            }
        }
        // the hold's mass: the least mass whose base radius reaches the hold radius
        let w = Windshield::new(dry(0)).unwrap();
        for a in [0.3, 2.2, 7.5] {
            let m = w.least_mass_of_radius(a);
            assert!(w.base_radius_mm(m) >= a);
            assert!(w.base_radius_mm(f64::from_bits(m.to_bits() - 1)) < a);
        }
    }

    #[test]
    fn a_particle_waits_while_a_big_drop_is_near_its_destination() {
        let mut c = dry(0);
        c.wipers = vec![Wiper {
            pivot_mm: [-1000.0, -1000.0],
            length_mm: 10.0,
            width_mm: 10.0,
        }];
        c.tilt_deg = 0.5; // nothing slides
        let mut w = Windshield::new(c).unwrap();
        // a drop of base radius ≥ 2.2 mm three cells away
        let m_big = WATER_DENSITY_KG_M3 * w.wetting.volume_m3(2.4e-3);
        w.place_drop(107.0, 101.0, m_big).unwrap();
        w.place_particle(101.0, 101.0, 1e-7).unwrap();
        w.step(0.01).unwrap();
        assert_eq!(w.state().particles.len(), 1, "held");
        // five cells away it converts
        let mut w2 = Windshield::new(w.config.clone()).unwrap();
        w2.place_drop(111.0, 101.0, m_big).unwrap();
        w2.place_particle(101.0, 101.0, 1e-7).unwrap();
        w2.step(0.01).unwrap();
        assert!(w2.state().particles.is_empty());
        assert_eq!(w2.state().drops.len(), 2);
    }

    #[test]
    fn the_wiper_turns_drops_into_particles_and_pushes_them() {
        let mut c = dry(1);
        c.tilt_deg = 1.0;
        c.wiper_angles_deg = [10.0, 170.0];
        c.wiper_period_s = 2.0;
        let mut w = Windshield::new(c).unwrap();
        let piv = w.config.wipers[0].pivot_mm;
        // a drop up and to the left of the pivot, at 60 deg: swept at ~t = 0.4 s
        let (x, y) = (piv[0] + 100.0, piv[1] - 173.2);
        w.place_drop(x, y, 5e-6).unwrap();
        for _ in 0..30 {
            w.step(1.0 / 60.0).unwrap();
        }
        let ps = &w.state().particles;
        assert!(!ps.is_empty());
        let total: f64 = ps.iter().map(|p| p.mass_kg).sum();
        assert!((total - 5e-6).abs() < 1e-15);
        // all in front of the blade
        let theta = w.wiper_angle_rad();
        for p in ps {
            let (_, phi) = Windshield::polar(&w.config.wipers[0], p.x_mm, p.y_mm);
            assert!(phi > theta, "{phi} <= {theta}");
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_bits_and_resume_continues_them() {
        let mut c = WindshieldConfig::car(300.0, 250.0, 2);
        c.rain_rate_mm_h = 25.0;
        c.seed = 7;
        let mut a = Windshield::new(c.clone()).unwrap();
        let mut b = Windshield::new(c.clone()).unwrap();
        for _ in 0..20 {
            a.step(0.05).unwrap();
            b.step(0.05).unwrap();
        }
        assert_eq!(a.state(), b.state());
        let mut r = Windshield::from_state(c.clone(), a.state().clone()).unwrap();
        a.step(0.05).unwrap();
        r.step(0.05).unwrap();
        assert_eq!(a.state(), r.state());
        c.seed = 8;
        let mut d = Windshield::new(c).unwrap();
        for _ in 0..21 {
            d.step(0.05).unwrap();
        }
        assert_ne!(a.state(), d.state());
    }

    #[test]
    fn no_rain_no_water() {
        let mut w = Windshield::new(dry(2)).unwrap();
        w.step(1.0).unwrap();
        assert_eq!(w.state().arrived_kg, 0.0);
        assert!(w.drops().is_empty());
    }

    #[test]
    fn bad_values_are_refused_by_name() {
        let mut c = dry(1);
        c.tilt_deg = 91.0;
        let e = Windshield::new(c).unwrap_err().to_string();
        assert!(e.starts_with("glass_tilt_deg = 91.0"), "{e}");
        let mut c = dry(1);
        c.receding_deg = 50.0;
        assert!(
            Windshield::new(c)
                .unwrap_err()
                .to_string()
                .contains("receding_deg")
        );
        let mut w = Windshield::new(dry(0)).unwrap();
        assert!(
            w.step(0.0)
                .unwrap_err()
                .to_string()
                .starts_with("dt_s = 0.0")
        );
        assert!(w.step(f64::NAN).is_err());
    }
}
