//! Measurement delay and actuator lag: the controller predicts the measured
//! state forward to the time its command takes effect.
//!
//! The measured state is `measurement_delay` (`D`) old when it arrives at
//! sample time `t_k`. The controller knows every torque it commanded since
//! (a ring buffer of its past commands, sized at creation), so it integrates
//! its own model from `t_k - D` to `t_k` with them, through the same RK4
//! steps the prediction uses (a whole number of samples without lag goes
//! through [`Controller::simulate_interval`] itself; a fractional part or a
//! lagged torque through RK4 steps of at most the same length, with the
//! torque evaluated at the stage times).
//!
//! The actuator's first-order lag `da/dt = (tau - a) / T` is integrated
//! exactly over the delay: per past sample the buffer also keeps the
//! applied torque the controller expects at its start, and within the
//! sample `a(s) = tau + (a_0 - tau) exp(-s / T)`.
//!
//! Over the horizon the lag is not part of the OCP (its state would have to
//! join `x`, whose dimension `NX = 2 N` is fixed). It is approximated by its
//! low-frequency effect, a dead time of `T`: the applied torque at `t` is
//! taken as the command of `t - T`. Then the state at `t_k + T` depends on
//! past commands only, and the controller embeds that state as the plan's
//! start, so the plan's first control is the one the lag lets through at
//! `t_k + T`. Measured on the paper's pendulum (docs/delay.md): at a lag of
//! 2 samples alike to leaving the horizon lag-free, at 8 samples half the
//! torque and energy error. The alternative, the exact interval-mean torque
//! of the lag on the first interval only, leaves the later intervals
//! lag-free and plans torque the motor delivers only `T` later.
//!
//! With the state estimator, the EKF filters the measurement at its own
//! time `t_k - D`: its propagation over the sample before uses the torque
//! that acted then (from the buffer), and the filtered state is what the
//! forward prediction starts from.

use super::Controller;
use crate::math;
use crate::mechanics::{MechanicalSystem, Vector, state_derivative};
use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

/// Positions (in samples) this close to a whole number are taken as whole:
/// `0.1 / 0.025` is `4.000000000000001` in floating point.
const WHOLE_SAMPLE_SNAP: f64 = 1e-9;

/// `value / dt` in samples, snapped to a whole number when within
/// rounding of one.
fn samples(value: f64, dt: f64) -> f64 {
    let p = value / dt;
    let r = p.round();
    if (p - r).abs() < WHOLE_SAMPLE_SNAP {
        r
    } else {
        p
    }
}

/// Past samples the history must cover for a delay `delay` and a lag
/// `time_constant` at sample period `dt`: the sample before the
/// measurement (`D / dt + 1`, the EKF's propagation), once more after the
/// new command is pushed ([`Controller::torque_before_measurement`]), and
/// the dead time `T / dt` of the lag's approximation.
pub(super) fn history_length(delay: f64, time_constant: f64, dt: f64) -> usize {
    let d = samples(delay, dt).ceil() as usize + 2;
    let t = samples(time_constant, dt).ceil() as usize;
    d.max(t).max(1)
}

/// The controller's past commands, most recent first, each with the
/// applied torque it expected at the start of its sample (a ring buffer of
/// fixed length: pushing overwrites the oldest).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct CommandHistory<const N: usize> {
    /// Commanded torque per past sample.
    commands: Vec<Vector<N>>,
    /// Applied torque (the lag's state) at the start of that sample.
    applied: Vec<Vector<N>>,
    /// Index of the most recent sample.
    head: usize,
}

impl<const N: usize> CommandHistory<N> {
    /// `length` past samples of zero torque: before the first sample the
    /// plant is taken to have rested without torque.
    pub(super) fn new(length: usize) -> Self {
        Self {
            commands: vec![Vector::zeros(); length],
            applied: vec![Vector::zeros(); length],
            head: 0,
        }
    }

    /// Number of past samples kept.
    pub(super) fn len(&self) -> usize {
        self.commands.len()
    }

    /// The command of the `m`-th last sample (`m = 1`: acting since the
    /// last sample time) and the applied torque at its start.
    pub(super) fn entry(&self, m: usize) -> (Vector<N>, Vector<N>) {
        let len = self.len();
        debug_assert!((1..=len).contains(&m), "history of {len} has no entry {m}");
        let i = (self.head + len - (m - 1)) % len;
        (self.commands[i], self.applied[i])
    }

    /// Records the command sent now; `decay = exp(-dt / T)` (0 without
    /// lag) carries the applied torque over the last sample.
    pub(super) fn push(&mut self, command: &Vector<N>, decay: f64) {
        let (last, last_applied) = self.entry(1);
        let applied = last + (last_applied - last) * decay;
        self.head = (self.head + 1) % self.len();
        self.commands[self.head] = *command;
        self.applied[self.head] = applied;
    }

    /// Every stored torque is finite (a restored state is checked).
    pub(super) fn is_finite(&self) -> bool {
        self.commands
            .iter()
            .chain(&self.applied)
            .all(|v| v.iter().all(|x| x.is_finite()))
            && self.head < self.len()
    }
}

impl<S, const N: usize, const NX: usize> Controller<S, N, NX>
where
    S: MechanicalSystem<N>,
{
    /// `exp(-dt / T)`: the share of the applied torque's distance to the
    /// command left after one sample (0 without lag).
    pub(super) fn lag_decay(&self) -> f64 {
        let t = self.config.actuator_time_constant;
        if t > 0.0 {
            math::exp(-self.config.dt / t)
        } else {
            0.0
        }
    }

    /// Whether the measurement is predicted forward at all.
    pub(super) fn compensates(&self) -> bool {
        self.config.measurement_delay > 0.0 || self.config.actuator_time_constant > 0.0
    }

    /// The measured (or filtered) state `z` of time `t_k - D` predicted to
    /// `t_k + T`: exactly (to RK4 accuracy) to `t_k` with the commands and
    /// the lag, then over `T` with the commands delayed by `T`.
    pub(super) fn predict_measured(&self, z: &SVector<f64, NX>) -> SVector<f64, NX> {
        let dt = self.config.dt;
        let x = self.integrate_history(z, samples(self.config.measurement_delay, dt), 0.0, true);
        self.integrate_history(
            &x,
            samples(self.config.actuator_time_constant, dt),
            0.0,
            false,
        )
    }

    /// The estimate of time `t_k-1 - D` propagated to `t_k - D` with the
    /// torque that acted then, and the sensitivity of that propagation
    /// (exact for a whole-sample delay without lag; else that of the
    /// command acting mid-way, enough for the covariance).
    pub(super) fn propagate_delayed(
        &self,
        from: &SVector<f64, NX>,
    ) -> (SVector<f64, NX>, SMatrix<f64, NX, NX>) {
        let d = samples(self.config.measurement_delay, self.config.dt);
        let lagged = self.config.actuator_time_constant > 0.0;
        if d.fract() == 0.0 && !lagged {
            let (u, _) = self.history.entry(d as usize + 1);
            let (next, a, _) =
                self.interval_sensitivity(from, &u, self.interval_substeps(from, &u));
            return (next, a);
        }
        let next = self.integrate_history(from, d + 1.0, d, true);
        let (u, _) = self.history.entry((d + 0.5).ceil() as usize);
        let (_, a, _) = self.interval_sensitivity(from, &u, self.interval_substeps(from, &u));
        (next, a)
    }

    /// The mean torque applied over the sample that ended when the last
    /// measurement was taken (`measurement_delay` before the last sample):
    /// the command `D` before, with the actuator lag the mean of the
    /// applied torque the controller expects (exact for the lag's law).
    /// What an identification pairs with [`Controller::state_estimate`]
    /// (with neither delay nor lag: the command before the last).
    pub fn torque_before_measurement(&self) -> Vector<N> {
        // After the last feedback its command is the newest entry: the
        // measurement's sample ends 1 + D / dt samples back.
        let d = samples(self.config.measurement_delay, self.config.dt) + 1.0;
        let t = self.config.actuator_time_constant;
        let dt = self.config.dt;
        if t == 0.0 && d.fract() == 0.0 {
            // One whole command (as it is: no rounding through dt).
            return self.history.entry(d as usize + 1).0;
        }
        let mut sum = Vector::<N>::zeros();
        let mut p = d + 1.0;
        while p > d {
            let m = p.ceil() as usize;
            let end = ((m - 1) as f64).max(d);
            let (offset, length) = ((m as f64 - p) * dt, (p - end) * dt);
            let (u, a0) = self.history.entry(m);
            sum += u * length;
            if t > 0.0 {
                // Integral of (a0 - u) exp(-s / T) over the piece.
                let decay = math::exp(-offset / t) - math::exp(-(offset + length) / t);
                sum += (a0 - u) * (t * decay);
            }
            p = end;
        }
        sum / dt
    }

    /// Integrates the model from `from` to `to` samples before now
    /// (`from > to >= 0`) under the past commands: lagged (the applied
    /// torque the lag makes of them) or as commanded.
    fn integrate_history(
        &self,
        z: &SVector<f64, NX>,
        from: f64,
        to: f64,
        lagged: bool,
    ) -> SVector<f64, NX> {
        let dt = self.config.dt;
        let mut x = *z;
        let mut p = from;
        while p > to {
            // The m-th last sample spans the positions m-1 .. m.
            let m = p.ceil() as usize;
            let end = ((m - 1) as f64).max(to);
            x = self.integrate_piece(&x, m, (m as f64 - p) * dt, (p - end) * dt, lagged);
            p = end;
        }
        x
    }

    /// Integrates `length` seconds from `offset` seconds into the `m`-th
    /// last sample.
    fn integrate_piece(
        &self,
        z: &SVector<f64, NX>,
        m: usize,
        offset: f64,
        length: f64,
        lagged: bool,
    ) -> SVector<f64, NX> {
        let (u, a0) = self.history.entry(m);
        let t = self.config.actuator_time_constant;
        let constant = !lagged || t == 0.0 || u == a0;
        let dt = self.config.dt;
        if constant && offset == 0.0 && length == dt {
            // A whole sample: the prediction's own interval, bit for bit.
            return self.simulate_interval(z, &u);
        }
        let torque = |s: f64| {
            if constant {
                u
            } else {
                u + (a0 - u) * math::exp(-s / t)
            }
        };
        // Steps no longer than the prediction's.
        let steps = (length / dt * self.config.substeps as f64).ceil().max(1.0) as usize;
        let h = length / steps as f64;
        let f = |x: &SVector<f64, NX>, tau: &Vector<N>| {
            state_derivative::<S, N, NX>(&self.system, x, tau)
        };
        let mut x = *z;
        for i in 0..steps {
            let s = offset + i as f64 * h;
            let (u0, um, u1) = (torque(s), torque(s + 0.5 * h), torque(s + h));
            let k1 = f(&x, &u0);
            let k2 = f(&(x + k1 * (0.5 * h)), &um);
            let k3 = f(&(x + k2 * (0.5 * h)), &um);
            let k4 = f(&(x + k3 * h), &u1);
            x += (k1 + (k2 + k3) * 2.0 + k4) * (h / 6.0);
        }
        x
    }
}
