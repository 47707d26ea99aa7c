//! Drops whose footprints touch merge into one.
//!
//! Gotou, Tanaka & Sagawa fuse two drops when one enters the other's cell. A drop's base is
//! wider than a 2 mm cell, though (a 2 mm raindrop spreads to a base radius of 2.1 mm on the
//! 40°/20° glass), so drops in neighbouring cells overlap long before they share one. Here a
//! mesh drop whose base disc (radius a, the spherical cap's: [`super::furmidge::Wetting`])
//! touches another's, |x_i − x_j| < a_i + a_j, merges with it: the masses add and the drop
//! stands at their mass-weighted centre, so water and its first moment are conserved exactly
//! (to rounding). The merged drop is wider and may touch more: it merges again until it touches
//! none. Trail drops are left out (a thin residue, not a cap; they fuse only by a drop entering
//! their cell, as in the paper), and so are the wipers' particles.
//!
//! The search uses the cell grid: a drop of base radius a can touch only drops whose centres
//! lie within a + a_max of its own (a_max an upper bound on every base radius on the glass),
//! i.e. within ⌈(a + a_max)/cell⌉ cells; where that square holds more cells than the glass has
//! drops, the drops are scanned instead. Merging runs for the drops that changed (an arrival,
//! a drop that fused, a converted particle, a slider at each cell it enters), so a step's cost
//! grows with the drops that change, not with those that rest.

use super::sim::{EMPTY, Windshield};

impl Windshield {
    /// Merges mesh drop `i` with every mesh drop whose base disc touches its own, again and
    /// again until it touches none; drop `i` keeps its index and takes the summed mass at the
    /// mass-weighted centre. A trail drop or a dead drop `i` is left as it is.
    pub(super) fn merge_touching(&mut self, i: usize) {
        loop {
            let d = self.state.drops[i];
            if d.mass_kg <= 0.0 || d.trail {
                return;
            }
            let a = self.base_radius_mm(d.mass_kg);
            let partners = self.touching(i, d.x_mm, d.y_mm, a);
            if partners.is_empty() {
                return;
            }
            self.absorb(i, &partners);
        }
    }

    /// The live, non-trail mesh drops other than `i` whose base disc touches the disc of
    /// radius `a_mm` at (x, y), in increasing index (the same order whichever way they were
    /// found, so the merged sums round alike).
    pub(super) fn touching(&self, i: usize, x: f64, y: f64, a_mm: f64) -> Vec<usize> {
        let reach = a_mm + self.a_max_mm;
        let s = self.config.cell_mm;
        let k = (reach / s).ceil() as i64;
        let side = (2 * k + 1) as u128;
        let mut out = vec![];
        let consider = |j: usize, out: &mut Vec<usize>| {
            if j == i {
                return;
            }
            let o = &self.state.drops[j];
            if o.mass_kg <= 0.0 || o.trail {
                return;
            }
            let (dx, dy) = (o.x_mm - x, o.y_mm - y);
            let d2 = dx * dx + dy * dy;
            if d2 >= reach * reach {
                return;
            }
            let sum = a_mm + self.base_radius_mm(o.mass_kg);
            if d2 < sum * sum {
                out.push(j);
            }
        };
        if side * side >= self.state.drops.len() as u128 {
            for j in 0..self.state.drops.len() {
                consider(j, &mut out);
            }
        } else {
            let (cx, cy) = ((x / s).floor() as i64, (y / s).floor() as i64);
            let (nx, ny) = (self.nx as i64, self.ny as i64);
            for ty in (cy - k).max(0)..=(cy + k).min(ny - 1) {
                for tx in (cx - k).max(0)..=(cx + k).min(nx - 1) {
                    let at = self.grid[(ty * nx + tx) as usize];
                    if at != EMPTY {
                        consider(at as usize, &mut out);
                    }
                }
            }
            out.sort_unstable();
        }
        out
    }

    /// Drop `i` takes the mass of `partners` (and of any drop already in the cell of the
    /// merged centre: one drop per cell) and moves to the mass-weighted centre.
    fn absorb(&mut self, i: usize, partners: &[usize]) {
        let d = self.state.drops[i];
        let (mut m, mut mx, mut my) = (d.mass_kg, d.mass_kg * d.x_mm, d.mass_kg * d.y_mm);
        for &j in partners {
            let o = self.state.drops[j];
            m += o.mass_kg;
            mx += o.mass_kg * o.x_mm;
            my += o.mass_kg * o.y_mm;
            self.kill(j);
        }
        self.kill_cell_of(i);
        let (x, y, c) = loop {
            let (x, y) = self.clamp_to_glass(mx / m, my / m);
            let c = self.cell_clamped(x, y);
            let at = self.grid[c];
            if at == EMPTY || at as usize == i {
                break (x, y, c);
            }
            let o = self.state.drops[at as usize];
            m += o.mass_kg;
            mx += o.mass_kg * o.x_mm;
            my += o.mass_kg * o.y_mm;
            self.kill(at as usize);
        };
        let d = &mut self.state.drops[i];
        d.x_mm = x;
        d.y_mm = y;
        d.mass_kg = m;
        d.trail = false;
        self.grid[c] = i as u32;
        self.a_max_mm = self.a_max_mm.max(self.base_radius_mm(m));
    }

    /// Empties drop `i`'s cell if the grid points there at `i`.
    fn kill_cell_of(&mut self, i: usize) {
        let d = self.state.drops[i];
        if let Some(c) = self.cell_of(d.x_mm, d.y_mm)
            && self.grid[c] == i as u32
        {
            self.grid[c] = EMPTY;
        }
    }

    /// (x, y) mm on the glass: a mass-weighted centre of drops on the glass lies on it, up to
    /// rounding at an edge.
    fn clamp_to_glass(&self, x_mm: f64, y_mm: f64) -> (f64, f64) {
        let inside = 1.0 - 1e-12;
        (
            x_mm.clamp(0.0, self.config.width_mm * inside),
            y_mm.clamp(0.0, self.config.height_mm * inside),
        )
    }

    /// The cell under (x, y) mm, clamped onto the grid.
    fn cell_clamped(&self, x_mm: f64, y_mm: f64) -> usize {
        let s = self.config.cell_mm;
        let i = ((x_mm / s).floor().max(0.0) as usize).min(self.nx - 1);
        let j = ((y_mm / s).floor().max(0.0) as usize).min(self.ny - 1);
        j * self.nx + i
    }
}

#[cfg(test)]
mod tests {
    use crate::windshield::{Windshield, WindshieldConfig};

    /// Water's density, kg/m³, and the 40°/20° glass's spherical cap at the mean angle θ = 30°:
    /// V = π a³ (2 − 3 cos θ + cos³ θ) / (3 sin³ θ), written here from the geometry.
    const RHO: f64 = 998.2;
    fn base_radius_mm(mass_kg: f64) -> f64 {
        let t = 30f64.to_radians();
        let (s, c) = t.sin_cos();
        let per_a3 = std::f64::consts::PI * (2.0 - 3.0 * c + c * c * c) / (3.0 * s * s * s);
        (mass_kg / RHO / per_a3).cbrt() * 1e3
    }

    /// Level, dry glass without wipers: nothing arrives and nothing slides.
    fn level() -> Windshield {
        let mut c = WindshieldConfig::car(300.0, 200.0, 0);
        c.rain_rate_mm_h = 0.0;
        c.tilt_deg = 0.0;
        Windshield::new(c).unwrap()
    }

    fn cell(w: &Windshield, x: f64, y: f64) -> (usize, usize) {
        let s = w.config().cell_mm;
        ((x / s) as usize, (y / s) as usize)
    }

    #[test]
    fn two_touching_drops_in_neighbouring_cells_merge_at_their_mass_centre() {
        let (m1, m2) = (4e-6, 2e-6);
        let sum = base_radius_mm(m1) + base_radius_mm(m2);
        // 0.98 of the summed base radii apart (3.7 mm): the next cell along x
        let (x1, y1) = (100.2, 101.0);
        let (x2, y2) = (x1 + 0.98 * sum, y1);
        let mut w = level();
        assert_eq!(cell(&w, x2, y2).0, cell(&w, x1, y1).0 + 1);
        w.place_drop(x1, y1, m1).unwrap();
        w.place_drop(x2, y2, m2).unwrap();
        let d = &w.state().drops;
        assert_eq!(d.len(), 1, "{d:?}");
        assert!((d[0].mass_kg - (m1 + m2)).abs() <= 1e-15 * (m1 + m2));
        assert!((d[0].x_mm - (m1 * x1 + m2 * x2) / (m1 + m2)).abs() < 1e-12);
        assert!((d[0].y_mm - y1).abs() < 1e-12);
        // diagonal neighbours too
        let mut w = level();
        let off = 0.98 * sum / std::f64::consts::SQRT_2;
        let (x3, y3) = (100.1 + off, 100.1 + off);
        assert_eq!(cell(&w, x3, y3), (51, 51));
        w.place_drop(100.1, 100.1, m1).unwrap();
        w.place_drop(x3, y3, m2).unwrap();
        assert_eq!(w.state().drops.len(), 1);
        assert!((w.state().drops[0].mass_kg - (m1 + m2)).abs() <= 1e-15 * (m1 + m2));
    }

    #[test]
    fn two_drops_that_do_not_touch_stay_apart() {
        let (m1, m2) = (4e-6, 2e-6);
        let sum = base_radius_mm(m1) + base_radius_mm(m2);
        let (x1, y1) = (100.05, 101.0);
        let (x2, y2) = (x1 + 1.02 * sum, y1);
        let mut w = level();
        assert_eq!(cell(&w, x2, y2).0, cell(&w, x1, y1).0 + 1);
        w.place_drop(x1, y1, m1).unwrap();
        w.place_drop(x2, y2, m2).unwrap();
        w.step(0.5).unwrap();
        let d = &w.state().drops;
        assert_eq!(d.len(), 2);
        assert_eq!((d[0].x_mm, d[0].mass_kg), (x1, m1));
        assert_eq!((d[1].x_mm, d[1].mass_kg), (x2, m2));
    }

    #[test]
    fn a_merged_drop_that_touches_a_third_merges_again() {
        // equal drops: A and B touch; C, above their midpoint, touches neither (2.21 a from
        // each, the sum of radii 2 a) but touches the merged A + B (2 a from its centre, the
        // sum 1.26 a + a)
        let m = 4e-6;
        let a = base_radius_mm(m);
        let (xa, xb) = (100.0, 100.0 + 1.9 * a);
        let (xc, yc) = (100.0 + 0.95 * a, 100.0 + 2.0 * a);
        assert!(((xc - xa).powi(2) + (yc - 100.0).powi(2)).sqrt() > 2.0 * a);
        assert!(2.0 * a < base_radius_mm(2.0 * m) + a);
        let mut w = level();
        w.place_drop(xc, yc, m).unwrap();
        w.place_drop(xa, 100.0, m).unwrap();
        assert_eq!(w.state().drops.len(), 2);
        w.place_drop(xb, 100.0, m).unwrap();
        let d = &w.state().drops;
        assert_eq!(d.len(), 1, "{d:?}");
        assert!((d[0].mass_kg - 3.0 * m).abs() <= 1e-15 * m);
        assert!((d[0].x_mm - (xa + xb + xc) / 3.0).abs() < 1e-9);
        assert!((d[0].y_mm - (200.0 + yc) / 3.0).abs() < 1e-9);
    }

    #[test]
    fn after_rain_no_two_drops_overlap_and_the_water_is_all_there() {
        // heavy rain on level glass: every pair of (non-trail) drops is at least the sum of
        // their base radii apart, checked over all pairs with the cap's radius computed here
        let mut c = WindshieldConfig::car(120.0, 80.0, 0);
        c.rain_rate_mm_h = 100.0;
        c.tilt_deg = 0.0;
        c.seed = 3;
        let mut w = Windshield::new(c).unwrap();
        for _ in 0..20 {
            w.step(0.25).unwrap();
        }
        let drops: Vec<_> = w.state().drops.iter().filter(|d| !d.trail).collect();
        assert!(drops.len() > 20, "{}", drops.len());
        let mut arrivals_merged = 0.0;
        for (i, p) in drops.iter().enumerate() {
            arrivals_merged += p.mass_kg;
            for q in &drops[i + 1..] {
                let d = ((p.x_mm - q.x_mm).powi(2) + (p.y_mm - q.y_mm).powi(2)).sqrt();
                let sum = base_radius_mm(p.mass_kg) + base_radius_mm(q.mass_kg);
                assert!(
                    d >= sum * (1.0 - 1e-9),
                    "{p:?} and {q:?} overlap: {d} < {sum}"
                );
            }
        }
        let s = w.state();
        let on: f64 = s.drops.iter().map(|d| d.mass_kg).sum();
        assert!(arrivals_merged <= on);
        assert!(
            (on + s.swept_off_kg + s.evaporated_kg - s.arrived_kg).abs() <= 1e-12 * s.arrived_kg
        );
    }
}
