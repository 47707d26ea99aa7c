//! A warmed-up windshield on a frame's clock: the glass at any frame time `t`, the same bits
//! whatever frames were asked for before, and cheap for frames in sequence.
//!
//! The glass at `t` is the warm state (a whole number of wiper periods into the rain) advanced
//! by τ = t mod (`epoch_periods` · T) (rounded to the nanosecond), T the wiper period: frames within an epoch see the drops
//! move continuously (a clip), and the epoch bounds what one frame costs. The advance runs on a
//! fixed grid of equal steps h = T / ⌈T / [`MAX_SUBSTEP_S`]⌉ from each period's start: the
//! state at every period's start is kept (a checkpoint, made once), and so is the last state on
//! the grid that a frame reached, so the next frame of a clip steps only from there; a frame
//! between grid points steps a copy the rest of the way. As the states on the grid do not
//! depend on the path to them, neither does any frame.

use super::sim::{MAX_SUBSTEP_S, Windshield};
use crate::error::{Error, Param, Result};

/// A windshield's warm state and its checkpoints.
#[derive(Debug, Clone)]
pub struct GlassClock {
    /// The state at the start of each period of the epoch reached so far (the first is the
    /// warm state).
    checkpoints: Vec<Windshield>,
    /// The last state on the grid a frame reached: (period, step in it, the state).
    latest: Option<(usize, usize, Windshield)>,
    period_s: f64,
    epoch_periods: usize,
    steps_per_period: usize,
}

impl GlassClock {
    /// The clock of `warm` (a windshield a whole number of `period_s` into the rain: its wipers
    /// at the start of their sweep), whose frames repeat every `epoch_periods` periods.
    pub fn new(warm: Windshield, period_s: f64, epoch_periods: usize) -> Result<Self> {
        if !(period_s.is_finite() && period_s > 0.0 && period_s <= 3600.0) {
            return Err(Error::OutOfRange {
                param: Param {
                    name: "period_s",
                    index: None,
                },
                value: period_s,
                range: "(0, 3600] s".into(),
                integer: false,
            });
        }
        if !(1..=1000).contains(&epoch_periods) {
            return Err(Error::OutOfRange {
                param: Param {
                    name: "epoch_periods",
                    index: None,
                },
                value: epoch_periods as f64,
                range: "[1, 1000]".into(),
                integer: true,
            });
        }
        Ok(GlassClock {
            checkpoints: vec![warm],
            latest: None,
            period_s,
            epoch_periods,
            steps_per_period: (period_s / MAX_SUBSTEP_S).ceil().max(1.0) as usize,
        })
    }

    /// The period, s.
    pub fn period_s(&self) -> f64 {
        self.period_s
    }

    /// The epoch, s: frames `epoch_s` apart show the same glass.
    pub fn epoch_s(&self) -> f64 {
        self.period_s * self.epoch_periods as f64
    }

    /// The grid's step, s.
    fn step_s(&self) -> f64 {
        self.period_s / self.steps_per_period as f64
    }

    /// The checkpoint at the start of period `k`, made (from the one before) if need be.
    fn checkpoint(&mut self, k: usize) -> Result<&Windshield> {
        let h = self.step_s();
        while self.checkpoints.len() <= k {
            let mut next = self.checkpoints[self.checkpoints.len() - 1].clone();
            for _ in 0..self.steps_per_period {
                next.step_once(h)?;
            }
            self.checkpoints.push(next);
        }
        Ok(&self.checkpoints[k])
    }

    /// The glass at frame time `t_s` (in [-1e7, 1e7] s).
    pub fn at(&mut self, t_s: f64) -> Result<Windshield> {
        crate::ranges::TIME_S.check(t_s)?;
        let h = self.step_s();
        // τ rounded to the nanosecond, so t and t plus whole epochs give the same τ's bits
        let tau = (t_s.rem_euclid(self.epoch_s()) * 1e9).round() / 1e9;
        let k = ((tau / self.period_s).floor() as usize).min(self.epoch_periods - 1);
        let into = tau - k as f64 * self.period_s;
        let j = ((into / h).floor() as usize).min(self.steps_per_period);
        let mut w = match self.latest.take() {
            Some((lk, lj, w)) if lk == k && lj <= j => (lj, w),
            _ => (0, self.checkpoint(k)?.clone()),
        };
        for _ in w.0..j {
            w.1.step_once(h)?;
        }
        let rest = into - j as f64 * h;
        let mut frame = w.1.clone();
        self.latest = Some((k, j, w.1));
        if rest > 0.0 {
            frame.step_once(rest.min(MAX_SUBSTEP_S))?;
        }
        Ok(frame)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::windshield::WindshieldConfig;

    fn clock() -> GlassClock {
        let mut c = WindshieldConfig::car(300.0, 200.0, 1);
        c.rain_rate_mm_h = 20.0;
        c.wiper_period_s = 0.5;
        c.seed = 3;
        let mut w = Windshield::new(c).unwrap();
        w.step(0.5).unwrap();
        GlassClock::new(w, 0.5, 3).unwrap()
    }

    fn at(c: &mut GlassClock, t: f64) -> Windshield {
        c.at(t).unwrap()
    }

    #[test]
    fn a_frame_is_the_same_glass_whatever_came_before() {
        let times = [0.0, 0.31, 0.9, 0.4, 1.2, 0.31, 1.49, 1.5 + 0.31, -1.5 + 0.9];
        let mut fresh = Vec::new();
        for &t in &times {
            fresh.push(at(&mut clock(), t).state().clone());
        }
        let mut one = clock();
        for (t, want) in times.iter().zip(&fresh) {
            assert_eq!(at(&mut one, *t).state(), want, "t = {t}");
        }
        // an epoch (1.5 s) later, the same glass
        assert_eq!(fresh[1], fresh[7]);
        assert_eq!(fresh[2], fresh[8]);
    }

    #[test]
    fn the_glass_is_at_the_frames_time_and_its_water_is_conserved() {
        let mut c = clock();
        let start = c.checkpoints[0].state().t_s;
        for t in [0.0, 0.26, 0.74, 1.1] {
            let w = at(&mut c, t);
            assert!((w.state().t_s - (start + t)).abs() < 1e-9, "{t}");
            let s = w.state();
            let balance = w.on_glass_kg() + s.swept_off_kg + s.evaporated_kg - s.arrived_kg;
            assert!(balance.abs() <= 1e-12 * s.arrived_kg.max(1e-9), "{balance}");
        }
        assert!(matches!(c.at(f64::NAN), Err(Error::OutOfRange { .. })));
        assert!(GlassClock::new(c.checkpoints[0].clone(), 0.0, 3).is_err());
        assert!(GlassClock::new(c.checkpoints[0].clone(), 0.5, 0).is_err());
    }
}
