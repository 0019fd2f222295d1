//! The stall supervisor: a controller never holds a robot still at a torque
//! bound.
//!
//! A model that is wrong enough (gravity amplitudes 20-30 % off, friction
//! unknown) gives the closed loop a fixed point away from the mode: the
//! robot rests where its own gravity and stiction balance the torque bound,
//! while the model predicts that the same torque moves it. Each sample
//! re-plans the same saturated torque from the same state, for as long as
//! the run lasts (measured on the laboratory pendulum A0: 100 s at
//! (-0.5, +0.5) N m, a stalled motor at full current).
//!
//! The supervisor watches blocks of `stall_time`: a block in which a torque
//! sat at its bound for most samples, the robot did not move (its mean
//! absolute speed and its angle's range over the block small) and the energy is
//! outside the band around `E_ref` is a **stall**. Recovery: the
//! controller's plan and state estimate are dropped (the next solve starts
//! afresh from the measurement) and the torque is released to zero for
//! `release_time`, so that the robot swings free of the fixed point; each
//! repeat doubles the release, up to `max_release_time`. An online
//! adaptation hears of each event ([`super::Controller::supervisor_events`]) and
//! falls back to the last accepted model or takes its estimate.
//!
//! Per sample: a few comparisons and sums, no allocation.

use super::MpcError;
use nalgebra::SVector;

/// When the supervisor calls a stall, and how it recovers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SupervisorOptions {
    /// Watch for stalls (default true).
    pub enabled: bool,
    /// Length of a block the stall must fill (s).
    pub stall_time: f64,
    /// The robot is held when it is still and a joint's mean absolute
    /// torque over the block is at least this share of `tau_max`.
    pub held_share: f64,
    /// A joint alone is held when it is still and its torque was at its
    /// bound (at least 98 % of `tau_max`) for this share of the block's
    /// samples (the other joints may still swing).
    pub bound_samples: f64,
    /// Mean absolute joint speed over the block below which a joint is
    /// still (rad/s): above the mean absolute noise of a speed sensor of
    /// 0.05 rad/s (0.8 sigma), below the slowest swing of a climb's start.
    pub still_speed: f64,
    /// Range of a joint's angle over the block (largest minus smallest)
    /// below which it is still (rad): above the range of 40 samples of an
    /// angle sensor's noise of 0.005 rad (4.3 sigma), below a swing of
    /// 0.02 rad amplitude.
    pub still_angle: f64,
    /// Energy error, a share of `E_ref`, beyond which the loop is off its
    /// target (the 5 % band); the error must also not have come down by
    /// this share over the block (a climb that starts with a joint held by
    /// its stiction is not a stall).
    pub energy_share: f64,
    /// Zero torque after the first stall (s).
    pub release_time: f64,
    /// Longest release after repeated stalls (s).
    pub max_release_time: f64,
}

impl Default for SupervisorOptions {
    fn default() -> Self {
        Self {
            enabled: true,
            stall_time: 1.0,
            held_share: 0.5,
            bound_samples: 0.8,
            still_speed: 0.1,
            still_angle: 0.04,
            energy_share: 0.05,
            release_time: 0.5,
            max_release_time: 4.0,
        }
    }
}

impl SupervisorOptions {
    /// Checks the options; the message names the offending one.
    pub fn validate(&self) -> Result<(), MpcError> {
        for (name, v, lo, hi) in [
            ("supervisor.stall_time", self.stall_time, 0.0, 60.0),
            ("supervisor.held_share", self.held_share, 0.0, 1.0),
            ("supervisor.bound_samples", self.bound_samples, 0.0, 1.0),
            ("supervisor.still_speed", self.still_speed, 0.0, f64::MAX),
            ("supervisor.still_angle", self.still_angle, 0.0, f64::MAX),
            ("supervisor.energy_share", self.energy_share, 0.0, f64::MAX),
            ("supervisor.release_time", self.release_time, 0.0, 60.0),
            (
                "supervisor.max_release_time",
                self.max_release_time,
                0.0,
                60.0,
            ),
        ] {
            if !(v.is_finite() && v > lo && v <= hi) {
                return Err(MpcError::InvalidParameter {
                    name,
                    value: v,
                    reason: "out of range (stall_time, release times in (0, 60] s; shares in (0, 1]; \
                             speed, angle, energy share > 0)",
                });
            }
        }
        if self.max_release_time < self.release_time {
            return Err(MpcError::InvalidParameter {
                name: "supervisor.max_release_time",
                value: self.max_release_time,
                reason: "must be at least release_time",
            });
        }
        Ok(())
    }
}

/// One block's sums.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
struct Block<const N: usize> {
    samples: usize,
    /// Energy error at the block's first sample.
    energy_error: f64,
    abs_torque: SVector<f64, N>,
    /// Samples with the joint's torque at its bound.
    at_bound: SVector<f64, N>,
    abs_speed: SVector<f64, N>,
    lowest: SVector<f64, N>,
    highest: SVector<f64, N>,
}

impl<const N: usize> Default for Block<N> {
    fn default() -> Self {
        Self {
            samples: 0,
            energy_error: 0.0,
            abs_torque: SVector::zeros(),
            at_bound: SVector::zeros(),
            abs_speed: SVector::zeros(),
            lowest: SVector::repeat(f64::INFINITY),
            highest: SVector::repeat(f64::NEG_INFINITY),
        }
    }
}

impl<const N: usize> Block<N> {
    /// This block followed by `next`.
    fn merged(&self, next: &Self) -> Self {
        Self {
            samples: self.samples + next.samples,
            energy_error: self.energy_error,
            abs_torque: self.abs_torque + next.abs_torque,
            at_bound: self.at_bound + next.at_bound,
            abs_speed: self.abs_speed + next.abs_speed,
            lowest: self.lowest.inf(&next.lowest),
            highest: self.highest.sup(&next.highest),
        }
    }
}

/// What the supervisor tells the controller after a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Verdict {
    /// Go on.
    Run,
    /// A stall was called now: drop the plan and the estimate, release.
    Stall,
}

/// The supervisor's state (saved with the controller).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub(super) struct Supervisor<const N: usize> {
    /// The half block being filled, and the one before it: a stall is
    /// judged every half block over the last whole one, so that one is
    /// called at most 1.5 `stall_time` after it began.
    block: Block<N>,
    previous: Option<Block<N>>,
    /// Samples of zero torque still to come.
    releasing: usize,
    /// Stalls called so far.
    events: usize,
    /// Stalls in a row, none more than [`FORGET_TIME`] after the one
    /// before: the next release is `release_time 2^repeats`.
    repeats: u32,
    /// Blocks without a stall since the last one.
    good_blocks: usize,
}

/// A torque at least this share of `tau_max` is at its bound.
const AT_BOUND: f64 = 0.98;

/// Time without a stall after which a stall counts as a first one again (s).
pub const FORGET_TIME: f64 = 20.0;

impl<const N: usize> Supervisor<N> {
    pub(super) fn new() -> Self {
        Self {
            block: Block::default(),
            previous: None,
            releasing: 0,
            events: 0,
            repeats: 0,
            good_blocks: 0,
        }
    }

    /// Stalls called so far.
    pub(super) fn events(&self) -> usize {
        self.events
    }

    /// Whether the torque is being released now.
    pub(super) fn releasing(&self) -> bool {
        self.releasing > 0
    }

    /// Before the solve: whether this sample is still part of a release
    /// (the controller then commands zero and does not solve).
    pub(super) fn release_sample(&mut self) -> bool {
        if self.releasing > 0 {
            self.releasing -= 1;
            true
        } else {
            false
        }
    }

    /// After a solve: the sample's state `z = (q, qd)`, its energy error
    /// and commanded torque into the block; at the block's end, the
    /// verdict.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn observe<const NX: usize>(
        &mut self,
        options: &SupervisorOptions,
        dt: f64,
        z: &SVector<f64, NX>,
        energy_error: f64,
        e_ref: f64,
        tau: &SVector<f64, N>,
        tau_max: f64,
    ) -> Verdict {
        if !options.enabled {
            return Verdict::Run;
        }
        let half = ((options.stall_time / dt / 2.0).round() as usize).max(1);
        let b = &mut self.block;
        b.samples += 1;
        if b.samples == 1 {
            b.energy_error = energy_error;
        }
        for j in 0..N {
            b.abs_torque[j] += tau[j].abs();
            if tau[j].abs() >= AT_BOUND * tau_max {
                b.at_bound[j] += 1.0;
            }
            b.abs_speed[j] += z[N + j].abs();
            b.lowest[j] = b.lowest[j].min(z[j]);
            b.highest[j] = b.highest[j].max(z[j]);
        }
        if b.samples < half {
            return Verdict::Run;
        }
        let current = std::mem::take(&mut self.block);
        let Some(before) = self.previous.replace(current) else {
            return Verdict::Run;
        };
        let block = before.merged(&current);
        let n = block.samples as f64;
        let still = |j: usize| {
            block.abs_speed[j] / n < options.still_speed
                && block.highest[j] - block.lowest[j] < options.still_angle
        };
        // A joint still with its torque at the bound all along, or the whole
        // robot still with a large torque. (A joint merely held by a large
        // torque while another swings slowly is also how a climb with a
        // small torque bound starts.)
        let held = (0..N).any(|j| still(j) && block.at_bound[j] >= options.bound_samples * n)
            || ((0..N).all(still)
                && (0..N).any(|j| block.abs_torque[j] / n >= options.held_share * tau_max));
        let band = options.energy_share * e_ref;
        let off_target =
            energy_error.abs() > band && energy_error.abs() > block.energy_error.abs() - band;
        if !(held && off_target) {
            self.good_blocks += 1;
            if self.good_blocks as f64 * half as f64 * dt >= FORGET_TIME {
                self.repeats = 0;
            }
            return Verdict::Run;
        }
        self.events += 1;
        self.good_blocks = 0;
        // The next judgement starts from a fresh whole block.
        self.previous = None;
        let release = options.release_time * f64::from(1u32 << self.repeats.min(16));
        let release = release.min(options.max_release_time);
        self.releasing = ((release / dt).round() as usize).max(1);
        self.repeats += 1;
        Verdict::Stall
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math;

    const DT: f64 = 0.025;

    /// Feeds one block of `stall_time`: joint 2 at `q2` with speed `qd2`
    /// and torque `tau2`, joint 1 at rest at -0.3 rad (swinging 0.3 rad
    /// with `swing`); the energy error goes from `e.0` to `e.1`. Returns the
    /// last verdict.
    fn block(s: &mut Supervisor<2>, q2: f64, qd2: f64, tau2: f64, e: (f64, f64)) -> Verdict {
        swinging(s, false, q2, qd2, tau2, e)
    }

    fn swinging(
        s: &mut Supervisor<2>,
        swing: bool,
        q2: f64,
        qd2: f64,
        tau2: f64,
        e: (f64, f64),
    ) -> Verdict {
        let options = SupervisorOptions::default();
        let n = (options.stall_time / DT).round() as usize;
        let mut verdict = Verdict::Run;
        for k in 0..n {
            let t = k as f64 * DT;
            let z = if swing {
                SVector::<f64, 4>::new(0.3 * math::sin(5.0 * t), q2, 1.5 * math::cos(5.0 * t), qd2)
            } else {
                SVector::<f64, 4>::new(-0.3, q2, 0.0, qd2)
            };
            let error = e.0 + (e.1 - e.0) * k as f64 / (n - 1) as f64;
            let tau = SVector::<f64, 2>::new(0.1, tau2);
            verdict = s.observe(&options, DT, &z, error, 1.0, &tau, 0.5);
            if verdict == Verdict::Stall {
                assert_eq!(k, n - 1, "called before the block's end");
            }
        }
        verdict
    }

    /// Samples of the release that follows.
    fn release(s: &mut Supervisor<2>) -> usize {
        let mut n = 0;
        while s.release_sample() {
            n += 1;
        }
        n
    }

    /// The robot held still, a torque at its bound, while the energy stays
    /// 30 % low is a stall (judged every half block over the last whole
    /// one: half a block of motion before it delays the call by half a
    /// block); the releases double on repeats (0.5, 1, 2, 4, 4 s) and start
    /// again from 0.5 s after 20 s without one.
    #[test]
    fn a_held_joint_off_target_is_a_stall_and_repeats_back_off() {
        let mut s = Supervisor::<2>::new();
        let mut releases = vec![];
        for _ in 0..5 {
            assert_eq!(block(&mut s, 0.7, 0.0, 0.5, (-0.3, -0.3)), Verdict::Stall);
            releases.push(release(&mut s));
        }
        assert_eq!(releases, [20, 40, 80, 160, 160]);
        assert_eq!(s.events(), 5);
        for _ in 0..20 {
            assert_eq!(block(&mut s, 0.2, 1.0, 0.5, (-0.3, -0.3)), Verdict::Run);
        }
        assert_eq!(block(&mut s, 0.7, 0.0, 0.5, (-0.3, -0.3)), Verdict::Stall);
        assert_eq!(release(&mut s), 20);
    }

    /// Not a stall: a joint moves (speed, or its angle's range; also the
    /// other joint while this one is held below its bound, as a climb with
    /// a small torque bound starts), the torque is small, the energy is in the band or
    /// coming closer (a climb whose first second stiction holds), or the
    /// supervisor is off.
    #[test]
    fn motion_small_torque_a_climb_or_the_band_are_not_stalls() {
        let fresh = Supervisor::<2>::new;
        assert_eq!(
            block(&mut fresh(), 0.7, 0.3, 0.5, (-0.3, -0.3)),
            Verdict::Run
        );
        // Joint 2 held by a large torque below its bound while joint 1
        // swings: not a stall; at its bound all along: one.
        assert_eq!(
            swinging(&mut fresh(), true, 0.7, 0.0, 0.45, (-0.3, -0.3)),
            Verdict::Run
        );
        assert_eq!(
            swinging(&mut fresh(), true, 0.7, 0.0, 0.5, (-0.3, -0.3)),
            Verdict::Stall
        );
        assert_eq!(
            block(&mut fresh(), 0.7, 0.0, 0.2, (-0.3, -0.3)),
            Verdict::Run
        );
        assert_eq!(
            block(&mut fresh(), 0.7, 0.0, 0.5, (-0.03, -0.03)),
            Verdict::Run
        );
        assert_eq!(
            block(&mut fresh(), 0.7, 0.0, 0.5, (-0.9, -0.8)),
            Verdict::Run
        );
        let mut s = fresh();
        // The angle moving by 0.05 rad within the block is motion.
        let options = SupervisorOptions::default();
        let n = (options.stall_time / DT).round() as usize;
        let mut verdict = Verdict::Run;
        for k in 0..n {
            let q2 = if k < n / 2 { 0.7 } else { 0.75 };
            let z = SVector::<f64, 4>::new(-0.3, q2, 0.0, 0.0);
            let tau = SVector::<f64, 2>::new(0.0, 0.5);
            verdict = s.observe(&options, DT, &z, -0.3, 1.0, &tau, 0.5);
        }
        assert_eq!(verdict, Verdict::Run);
        let off = SupervisorOptions {
            enabled: false,
            ..options
        };
        for _ in 0..2 * n {
            let z = SVector::<f64, 4>::new(0.0, 0.7, 0.0, 0.0);
            let tau = SVector::<f64, 2>::new(0.0, 0.5);
            assert_eq!(s.observe(&off, DT, &z, -0.3, 1.0, &tau, 0.5), Verdict::Run);
        }
    }

    #[test]
    fn options_are_validated() {
        assert!(SupervisorOptions::default().validate().is_ok());
        for bad in [
            SupervisorOptions {
                stall_time: 0.0,
                ..Default::default()
            },
            SupervisorOptions {
                held_share: 1.5,
                ..Default::default()
            },
            SupervisorOptions {
                still_speed: f64::NAN,
                ..Default::default()
            },
            SupervisorOptions {
                max_release_time: 0.1,
                ..Default::default()
            },
        ] {
            assert!(bad.validate().is_err(), "{bad:?}");
        }
    }
}
