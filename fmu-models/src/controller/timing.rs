//! When the controller solves: at the communication points on its sample
//! grid `t_start + k sample_period`, or at the first communication point
//! after a grid point that falls inside a step; a step longer than the
//! sample period gets one solve per step. Both are documented behaviour:
//! logged once under `logStatusWarning`, and the call returns `fmi2OK`
//! (some masters stop at the first `fmi2Warning`).

use fmi2_slave::Logger;

/// Relative tolerance (in sample periods) for a communication point to count
/// as a grid point: absorbs the rounding of a master summing its steps.
pub const GRID_TOLERANCE: f64 = 1e-6;

/// What a communication step asks of the controller.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tick {
    /// A grid point was reached: solve with the current inputs.
    Solve,
    /// Still at `t_start` (solved at initialization): solve again only if
    /// the inputs changed since.
    AtStart,
    /// Between grid points: hold the outputs.
    Hold,
}

/// The sample grid and its warnings.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SampleClock {
    sample_period: f64,
    start_time: f64,
    /// Index of the next grid point to solve at.
    next_sample: i64,
    warned_long_step: bool,
    warned_off_grid: bool,
}

impl SampleClock {
    /// A grid from `start_time`; grid point 0 is solved at initialization.
    pub fn new(start_time: f64, sample_period: f64) -> Self {
        Self {
            sample_period,
            start_time,
            next_sample: 1,
            warned_long_step: false,
            warned_off_grid: false,
        }
    }

    /// The step `fmi2DoStep(t, h)`: what to do at `t` (warnings go to `log`;
    /// no allocation unless a warning is logged).
    pub fn step(&mut self, t: f64, h: f64, log: &Logger) -> Tick {
        let dt = self.sample_period;
        if h > dt * (1.0 + GRID_TOLERANCE) && !self.warned_long_step {
            self.warned_long_step = true;
            log.notice(&format!(
                "communication step {h} s is longer than the sample period {dt} s: one solve \
                 per step (the prediction still assumes {dt} s intervals)"
            ));
        }
        let samples = (t - self.start_time) / dt;
        // Last grid point at or before t.
        let reached = (samples + GRID_TOLERANCE).floor() as i64;
        let on_grid = (samples - samples.round()).abs() <= GRID_TOLERANCE;
        if reached >= self.next_sample {
            if !on_grid && !self.warned_off_grid && h <= dt * (1.0 + GRID_TOLERANCE) {
                self.warned_off_grid = true;
                log.notice(&format!(
                    "communication point t = {t} s is not on the sample grid (start {} s, \
                     period {dt} s): solving at the first communication point after each grid \
                     point",
                    self.start_time
                ));
            }
            self.next_sample = reached + 1;
            Tick::Solve
        } else if reached == 0 && on_grid {
            Tick::AtStart
        } else {
            Tick::Hold
        }
    }
}
