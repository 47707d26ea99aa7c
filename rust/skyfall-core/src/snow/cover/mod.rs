//! The snow cover: where the snow lies after it has fallen with the wind, after Koitabashi,
//! Matsubara, Moriya & Takahashi, *Snowfall and snow-cover scenes with wind*, made physical.
//!
//! **The surface.** A height field over a horizontal grid of square cells (x, z; the user's
//! `resolution_m`): each cell's base is the highest surface over its centre (the ground y = 0
//! and the box tops for a box scene, [`HeightField::from_boxes`]; the points a photo's depth map
//! shows, through its camera, for a photo, [`HeightField::from_depth_map`]), and the snow
//! lying on it adds its own depth, so the surface the next step's snow meets is base + depth:
//! drifts build on drifts.
//!
//! **Each step** (the paper's §4.2, [`accumulate`]):
//! 1. the snow falls along a spread of paths ([`wind`]): each flake size at its own fall speed
//!    v_f(D) ([`crate::physics::snow`]), through the wind's gusts, and slowed among the
//!    buildings by Macdonald's canopy profile, so each path drifts s = u/v_f per metre of
//!    *lift* G (the height, shortened below the roofs where the wind is weaker). Per path a
//!    shadow buffer is rendered ([`shadow::ShadowBuffer`]): every surface point is projected
//!    along the path onto the plane G = G₀ and the buffer keeps, per texel, the highest point
//!    that projects there; a cell lower than what its texel holds is in the shadow of
//!    something upstream and that path's snow does not reach it. [`wind::DIRECTIONS`] paths per
//!    step share the snow equally (in still air one, straight down: every cell is reached), so
//!    shadows have soft edges and a narrow street is not shaded whole by a breeze;
//! 2. a lit cell grows by the paper's d(t) = w·k(t)·(v·n) made physical: k(t)·w, the flakes'
//!    number times a conversion factor, is the snow's mass flux, the rate R as a depth of water
//!    per second, turned into a depth of snow by ρ_w/ρ_snow; (v·n) is the flux through the
//!    cell's own surface. The flux through a horizontal plane is R by the rate's definition;
//!    through a surface of normal n it is R·(v·n)/(v·ŷ), and per unit of *horizontal* area of
//!    a height field H(x, z) (n ∝ (−∂H/∂x, 1, −∂H/∂z)) that is
//!    R · f with f = 1 + (v_x ∂H/∂x + v_z ∂H/∂z)/|v_y|: 1 on level ground and box tops,
//!    more on faces turned to the wind, less on faces turned from it (clamped to [0, 1 + s],
//!    s = |v_h|/|v_y|, the slope of 45°). So Δd = R·dt·(ρ_w/ρ_snow)·f per lit cell;
//! 3. the paper's random factor r (D(t) = D(t−1) + r·d(t)): a seeded field per cell,
//!    r = 1 + `roughness`·u, u uniform in [−1, 1], fixed over the run (so the cover's
//!    roughness does not depend on dt), scaled each step so that Σ r·Δd = Σ Δd: r moves snow
//!    between cells, it does not make any;
//! 4. the paper's 4-neighbour smoothing, of the step's increment: each cell keeps 1/5 of it
//!    and hands 1/5 to each neighbour on the same surface (bases within one cell's width),
//!    keeping the shares of the others; mass is moved, never made or lost;
//! 5. above fresh snow's threshold (about 4.3 m/s at 10 m) the wind moves what lies
//!    ([`drift`]): saltation at Pomeroy & Gray's flux, from where the wind is strong to where
//!    it is sheltered (Werner's 15° shadow behind every crest), so roofs are scoured and drifts
//!    form in the lee of walls and boxes.
//!
//! **Mass bookkeeping.** What falls on the catchment (the lit cells' R·dt·f·ρ_w per unit of
//! horizontal area, summed over the steps: [`SnowCover::fallen_kg`]) equals what lies on it
//! (Σ depth·ρ_snow·cell area: [`SnowCover::lying_kg`]) exactly, once the snow the wind carried
//! across the grid's edges is counted ([`SnowCover::blown_in_kg`], [`SnowCover::blown_out_kg`]):
//! r, the smoothing and the drift only move snow. The open sky's share (R·ρ_w·area·duration: [`SnowCover::open_sky_kg`]) differs from
//! it by what the wind blew in and out of the catchment across its sides and what the
//! shadows of its edges hold back: in still air over level ground the three are equal.

pub mod accumulate;
pub mod drift;
pub mod heightfield;
pub mod look;
pub mod photo;
pub mod render;
pub mod shadow;
pub mod sparkle;
pub mod wind;

pub use accumulate::{CoverParams, CoverWeather, accumulate, fall_velocity_m_s};
pub use heightfield::{Grid, HeightField};
pub use render::SnowRender;

/// The cover a run left: the height field it lay on, the depth of snow per cell and its
/// bookkeeping.
#[derive(Debug, Clone, PartialEq)]
pub struct SnowCover {
    /// The surface the snow lay on (its grid and bases).
    pub field: HeightField,
    /// Depth of snow per cell, m (row-major, z rows of x cells; 0 where none or no surface).
    pub depth_m: Vec<f64>,
    /// Snow that fell on the catchment's lit cells, kg.
    pub fallen_kg: f64,
    /// Snow lying on the catchment at the end, kg (Σ depth · ρ_snow · cell area): fallen +
    /// blown in − blown out.
    pub lying_kg: f64,
    /// Snow the wind blew in across the grid's upwind edge, kg ([`drift`]).
    pub blown_in_kg: f64,
    /// Snow the wind blew out across the grid's downwind edge, kg.
    pub blown_out_kg: f64,
    /// The canopy the wind blew through ([`wind::Canopy`]; none in still air).
    pub canopy: wind::Canopy,
    /// Snow that fell through the horizontal plane over the catchment, R·ρ_w·area·duration, kg.
    pub open_sky_kg: f64,
    /// The depth the run lays on level open ground, m: R·duration·ρ_w/ρ_snow.
    pub open_depth_m: f64,
    /// Steps run.
    pub steps: usize,
    /// The step used, s (duration / steps).
    pub dt_s: f64,
    /// The snow's mean fall velocity, m/s (wind plus fall speed).
    pub fall_velocity_m_s: [f64; 3],
}

#[cfg(test)]
mod tests;
