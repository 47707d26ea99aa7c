//! The ambient-light map in two parts: what the scene fixes and what the weather changes.
//!
//! A node's five illuminances are, per azimuth, the sky's cumulative integrals read at the
//! edges of the elevations the boxes leave visible ([`super::illuminance`]). The edges depend
//! only on the boxes, the grid and the azimuths, and finding them (every box above a node, on
//! every azimuth) is nearly all of a map's cost; reading the sky's tables at them is a small
//! part. [`Horizon`] keeps the edges of every open node, so [`Horizon::light`] makes the map
//! under any sky (another rain rate, visibility, sky type or sun) by the table reads alone.
//! The map it makes is [`AmbientMap::build`]'s bit for bit: the same edges, read in the same
//! order with the same arithmetic.
//!
//! A sky the same at every azimuth (the overcast sky in any rain or mist: what a sweep over
//! the rain rate or the visibility changes) needs less: each node's light is a dot product of
//! weights the edges fix with the sky's integrals at a few elevations ([`super::profile`]).
//! The horizon makes those weights at the first such sky and keeps them (480 bytes per open
//! node), so every later one costs a dot product per node, again [`AmbientMap::build`]'s
//! values bit for bit.

use super::ambient::{AmbientMap, FillPlan, solid};
use super::illuminance::{AZIMUTHS, CHANNELS, SkyTable, VisibleSky, azimuth_dirs, boxes_above};
use super::profile::{self, Weights};
use crate::error::{Error, Param, Result, check_cancel, try_filled};
use crate::scene::boxes::BoxScene;
use glam::Vec3;
use rayon::prelude::*;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};

/// The most (open node, azimuth) pairs a horizon keeps: 2 bytes of count and 2 per edge each
/// (the bundled street at 1 m and 64 azimuths: 7.6 M pairs, about one edge each, 32 MB). A larger
/// grid's map is built directly ([`AmbientMap::build`]), at its full cost for every sky.
pub const MAX_PAIRS: usize = 1 << 24;

/// One column of nodes (fixed x and height, every z): its open nodes' visible skies.
#[derive(Debug, Clone, Default, PartialEq)]
struct Column {
    /// Whether each node of the column is inside a box.
    solid: Vec<bool>,
    /// The open nodes' edges per azimuth, node after node ([`VisibleSky`]).
    sky: VisibleSky,
}

/// What a scene fixes of its ambient-light map: the grid, the solid nodes and each open
/// node's visible elevations per azimuth.
#[derive(Debug, Clone, PartialEq)]
pub struct Horizon {
    origin_m: Vec3,
    spacing_m: f32,
    dims: [usize; 3],
    azimuths: usize,
    /// Columns (x, height) in the map's order, each its z nodes.
    columns: Vec<Column>,
    /// The solid nodes as a map holds them (1 inside a box), and how they are filled from the
    /// open ones.
    solid: Vec<u32>,
    fill: FillPlan,
    /// Each column's open nodes' weights under a symmetric sky ([`profile::weights`]), made
    /// at the first one; None when there was no memory for them (each node's are then made as
    /// the map is lit: the same values, at the cost of reading the edges).
    weights: OnceLock<Option<Vec<Vec<Weights>>>>,
}

impl Horizon {
    /// The horizon of `scene` over the grid [`AmbientMap::build`] would make for `min_m`,
    /// `max_m` and `spacing_m`, at `azimuths` (the sky tables' count: [`SkyTable::new`]'s,
    /// checked as its),
    /// stopping with [`Error::Cancelled`] soon after `cancel` is set (checked before every
    /// node). A grid of more than [`MAX_PAIRS`] (open node, azimuth) pairs is refused as
    /// [`Error::OutOfMemory`]: build its maps directly.
    pub fn build_cancellable(
        scene: &BoxScene,
        azimuths: usize,
        min_m: Vec3,
        max_m: Vec3,
        spacing_m: f64,
        cancel: &AtomicBool,
    ) -> Result<Self> {
        let dims = AmbientMap::grid_dims(min_m, max_m, spacing_m)?;
        let [nx, ny, nz] = dims;
        AZIMUTHS.check("samples", None, azimuths as f64)?;
        let n_az = azimuths;
        let pairs = (nx * ny * nz) as u128 * n_az as u128;
        if pairs > MAX_PAIRS as u128 {
            return Err(Error::out_of_memory::<[u8; 11]>(
                format!(
                    "a horizon of {nx}x{ny}x{nz} nodes at {n_az} azimuths (more than the \
                     {MAX_PAIRS} node-azimuth pairs a horizon keeps)"
                ),
                usize::try_from(pairs).unwrap_or(usize::MAX),
            ));
        }
        let s = spacing_m as f32;
        let dirs = &azimuth_dirs(n_az);
        // Every allocation that grows with the grid is fallible (out of memory is an error,
        // which Python answers by building the map directly; a `Vec` that cannot grow would
        // abort the process).
        let mut built = Vec::new();
        built
            .try_reserve_exact(nx * ny)
            .map_err(|_| Error::out_of_memory::<Column>("the horizon's columns", nx * ny))?;
        (0..nx * ny)
            .into_par_iter()
            .map(|ij| -> Result<Column> {
                let (i, j) = (ij / ny, ij % ny);
                let y = min_m.y + j as f32 * s;
                let above = boxes_above(scene, y);
                let mut col = Column {
                    solid: try_filled("the horizon's solid nodes", nz, false)?,
                    sky: VisibleSky::default(),
                };
                col.sky.counts.try_reserve_exact(nz * n_az).map_err(|_| {
                    Error::out_of_memory::<u16>("the horizon's edge counts", nz * n_az)
                })?;
                let mut node = VisibleSky::default();
                for k in 0..nz {
                    if cancel.load(Ordering::Relaxed) {
                        break;
                    }
                    let p = min_m + Vec3::new(i as f32 * s, j as f32 * s, k as f32 * s);
                    if solid(scene, p) {
                        col.solid[k] = true;
                    } else {
                        node.clear();
                        node.find(&above, dirs, p);
                        col.sky.edges.try_reserve(node.edges.len()).map_err(|_| {
                            Error::out_of_memory::<u16>("the horizon's edges", node.edges.len())
                        })?;
                        col.sky.edges.extend_from_slice(&node.edges);
                        col.sky.counts.extend_from_slice(&node.counts);
                    }
                }
                Ok(col)
            })
            .collect_into_vec(&mut built);
        check_cancel(cancel, "the ambient map's horizon")?;
        let columns = built.into_iter().collect::<Result<Vec<Column>>>()?;
        let mut is_solid = try_filled("the ambient map's solid nodes", nx * ny * nz, false)?;
        for (out, col) in is_solid.chunks_mut(nz).zip(&columns) {
            out.copy_from_slice(&col.solid);
        }
        let fill = FillPlan::new(dims, &is_solid, cancel)?;
        let mut solid = try_filled("the ambient map's solid nodes", is_solid.len(), 0u32)?;
        for (o, &b) in solid.iter_mut().zip(&is_solid) {
            *o = u32::from(b);
        }
        Ok(Horizon {
            solid,
            fill,
            origin_m: min_m,
            spacing_m: s,
            dims,
            azimuths: n_az,
            columns,
            weights: OnceLock::new(),
        })
    }

    /// Its grid's nodes along X, Y and Z.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// The azimuths it was found at.
    pub fn azimuths(&self) -> usize {
        self.azimuths
    }

    /// The bytes it holds (its edges and counts, and its weights once a symmetric sky made them).
    pub fn bytes(&self) -> usize {
        let weights = match self.weights.get() {
            Some(Some(w)) => w.iter().map(|c| c.len()).sum::<usize>() * size_of::<Weights>(),
            _ => 0,
        };
        weights
            + 4 * self.solid.len()
            + self.fill.bytes()
            + self
                .columns
                .iter()
                .map(|c| c.solid.len() + 2 * c.sky.counts.len() + 2 * c.sky.edges.len())
                .sum::<usize>()
    }

    /// Each column's open nodes' weights, or None if they cannot be allocated.
    fn make_weights(&self, dirs: &[(f64, f64)]) -> Option<Vec<Vec<Weights>>> {
        let n_az = self.azimuths;
        let mut out = Vec::new();
        out.try_reserve_exact(self.columns.len()).ok()?;
        self.columns
            .par_iter()
            .map(|col| {
                let open = col.sky.counts.len() / n_az;
                let mut ws = Vec::new();
                ws.try_reserve_exact(open).ok()?;
                let mut edge = 0;
                for counts in col.sky.counts.chunks_exact(n_az) {
                    let n_edges: usize = counts.iter().map(|&c| usize::from(c)).sum();
                    ws.push(profile::weights(
                        dirs,
                        counts,
                        &col.sky.edges[edge..edge + n_edges],
                    ));
                    edge += n_edges;
                }
                Some(ws)
            })
            .collect_into_vec(&mut out);
        out.into_iter().collect()
    }

    /// The map under the sky of `table` (which must have [`Self::azimuths`] azimuths):
    /// [`AmbientMap::build`]'s values for that sky, bit for bit.
    pub fn light(&self, table: &SkyTable, cancel: &AtomicBool) -> Result<AmbientMap> {
        if table.azimuths() != self.azimuths {
            return Err(Error::Invalid {
                param: Param {
                    name: "samples",
                    index: None,
                },
                message: format!(
                    "the sky is tabulated at {} azimuths, the horizon was found at {}: use the same samples",
                    table.azimuths(),
                    self.azimuths
                ),
            });
        }
        let [nx, ny, nz] = self.dims;
        let nodes = nx * ny * nz;
        let mut values = try_filled("the ambient map's values", nodes * CHANNELS, 0.0f32)?;
        let mut solid = try_filled("the ambient map's solid nodes", nodes, 0u32)?;
        solid.copy_from_slice(&self.solid);
        let n_az = self.azimuths;
        let coarse = table.coarse();
        let weights = coarse.and_then(|_| {
            self.weights
                .get_or_init(|| self.make_weights(table.dirs()))
                .as_ref()
        });
        values
            .par_chunks_mut(nz * CHANNELS)
            .zip(self.columns.par_iter())
            .enumerate()
            .for_each(|(ci, (column, col))| {
                let (mut node, mut edge) = (0, 0);
                for k in 0..nz {
                    if col.solid[k] {
                        continue;
                    }
                    let out = &mut column[k * CHANNELS..(k + 1) * CHANNELS];
                    if let (Some(sky), Some(ws)) = (coarse, weights) {
                        out.copy_from_slice(&profile::light(&ws[ci][node], sky));
                        node += 1;
                        continue;
                    }
                    let counts = &col.sky.counts[node * n_az..(node + 1) * n_az];
                    let n_edges: usize = counts.iter().map(|&c| usize::from(c)).sum();
                    let edges = &col.sky.edges[edge..edge + n_edges];
                    out.copy_from_slice(&VisibleSky::light_parts(table, counts, edges));
                    node += 1;
                    edge += n_edges;
                }
            });
        check_cancel(cancel, "the ambient-light map")?;
        Ok(AmbientMap::finish_planned(
            self.origin_m,
            self.spacing_m,
            self.dims,
            values,
            solid,
            &self.fill,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::boxes::SceneBox;
    use crate::sky::Sky;
    use crate::sky::cie::SkyKind;

    fn canyon() -> BoxScene {
        let wall = |x0: f32, x1: f32, h: f32| SceneBox {
            min_m: Vec3::new(x0, 0.0, -30.0),
            max_m: Vec3::new(x1, h, 30.0),
            albedo: Vec3::splat(0.4),
        };
        let awning = SceneBox {
            min_m: Vec3::new(4.0, 3.0, -5.0),
            max_m: Vec3::new(6.0, 3.2, 5.0),
            albedo: Vec3::splat(0.3),
        };
        BoxScene::new(
            vec![wall(-8.0, -6.0, 20.0), wall(6.0, 8.0, 12.0), awning],
            true,
            Vec3::splat(0.2),
        )
        .unwrap()
    }

    #[test]
    fn a_horizon_lights_the_map_of_every_sky_bit_for_bit() {
        let scene = canyon();
        let (lo, hi) = (Vec3::new(-10.0, 0.0, -12.0), Vec3::new(10.0, 14.0, 12.0));
        let cancel = AtomicBool::new(false);
        let table = |sky: &Sky| SkyTable::new(sky, 48).unwrap();
        let horizon = Horizon::build_cancellable(&scene, 48, lo, hi, 1.0, &cancel).unwrap();
        for sky in [
            Sky::new(SkyKind::Overcast, 1e-3, 900.0).unwrap(),
            Sky::new(SkyKind::Overcast, 0.04, 400.0).unwrap(),
            Sky::new(
                SkyKind::general(12, Some(Vec3::new(0.3, 0.64, -0.7).normalize())).unwrap(),
                3e-4,
                1200.0,
            )
            .unwrap(),
        ] {
            let t = table(&sky);
            let direct = AmbientMap::build(&scene, &t, lo, hi, 1.0).unwrap();
            let relit = horizon.light(&t, &cancel).unwrap();
            assert_eq!(direct, relit);
        }
        assert!(horizon.bytes() > 0);
        // Where there was no memory to keep the symmetric sky's weights, each column's are
        // made as it is lit: the same map.
        let bare = Horizon::build_cancellable(&scene, 48, lo, hi, 1.0, &cancel).unwrap();
        assert!(bare.weights.set(None).is_ok());
        let overcast = table(&Sky::new(SkyKind::Overcast, 2e-3, 700.0).unwrap());
        assert_eq!(
            bare.light(&overcast, &cancel).unwrap(),
            AmbientMap::build(&scene, &overcast, lo, hi, 1.0).unwrap()
        );
        // another number of azimuths is refused by name
        let other = SkyTable::new(&Sky::new(SkyKind::Overcast, 1e-3, 900.0).unwrap(), 32).unwrap();
        let e = horizon.light(&other, &cancel).unwrap_err().to_string();
        assert!(e.contains("samples"), "{e}");
    }

    #[test]
    fn a_symmetric_sky_reads_its_coarse_cumulative_within_1e_3() {
        // The map of a sky the same at every azimuth, lit from its few elevations (and built
        // directly the same way: bit for bit), against the 512-step tables along every
        // azimuth, at every open node of the canyon: within 1e-3 of the node's light, for the
        // overcast sky from clear air to fog and CIE types 1 and 5.
        let scene = canyon();
        let (lo, hi) = (Vec3::new(-10.0, 0.0, -12.0), Vec3::new(10.0, 14.0, 12.0));
        let cancel = AtomicBool::new(false);
        let horizon = Horizon::build_cancellable(&scene, 64, lo, hi, 1.0, &cancel).unwrap();
        let mut worst = 0.0f64;
        let mut worst_own = 0.0f64;
        for (kind, sigma, h) in [
            (SkyKind::Overcast, 0.0, 1500.0),
            (SkyKind::Overcast, 2e-4, 1476.0),
            (SkyKind::Overcast, 1.3e-3, 1052.0),
            (SkyKind::Overcast, 1.3e-2, 520.0),
            (SkyKind::Overcast, 0.04, 300.0),
            (SkyKind::general(5, None).unwrap(), 3e-4, 900.0),
            (SkyKind::general(1, None).unwrap(), 1e-3, 900.0),
        ] {
            let sky = Sky::new(kind, sigma, h).unwrap();
            let fast = SkyTable::new(&sky, 64).unwrap();
            assert!(fast.coarse().is_some(), "{kind:?}");
            let fine = SkyTable::per_azimuth(&sky, 64, &cancel).unwrap();
            assert!(fine.coarse().is_none());
            let relit = horizon.light(&fast, &cancel).unwrap();
            assert_eq!(
                relit,
                AmbientMap::build(&scene, &fast, lo, hi, 1.0).unwrap()
            );
            let reference = horizon.light(&fine, &cancel).unwrap();
            for (n, (a, b)) in relit
                .values
                .chunks(CHANNELS)
                .zip(reference.values.chunks(CHANNELS))
                .enumerate()
            {
                if relit.solid[n] == 1 {
                    continue;
                }
                // Relative to the node's brightest channel (the node's light as a vector),
                // and each channel relative to itself where it sees 1 % of E or more.
                let scale = b.iter().fold(0.0f64, |m, &v| m.max(f64::from(v).abs()));
                for c in 0..CHANNELS {
                    let (x, y) = (f64::from(a[c]), f64::from(b[c]));
                    let node_err = (x - y).abs() / scale.max(1e-6);
                    let own_err = (x - y).abs() / y.abs().max(1e-2);
                    assert!(
                        node_err < 1e-3 && own_err < 1e-3,
                        "{kind:?} σ {sigma}: node {n} channel {c}: {x} vs {y} in {b:?}"
                    );
                    worst = worst.max(node_err);
                    worst_own = worst_own.max(own_err);
                }
            }
        }
        // measured: 1.0e-4 of the node, 1.5e-4 of the channel
        eprintln!("worst error {worst:.2e} of the node, {worst_own:.2e} of the channel");
        assert!(horizon.bytes() > 480 * 1000);
    }
}
