//! Closed loops with the imperfections of a real set-up, as the published
//! robustness benchmarks of double-pendulum controllers apply them: a plant
//! that differs from the model (any [`PlanarChain`]), noisy and delayed
//! measurements, a noisy and sluggish motor, and optionally the online
//! adaptation ([`crate::adapt`]) that the controller runs against them.
//!
//! What the controller sees at sample `k` is the plant's state `delay`
//! earlier plus Gaussian noise; what the plant gets over the sample is
//! `u_k = a tau_k + (1 - a) u_(k-1)` (responsiveness `a`, above 1 an
//! overshooting motor) plus Gaussian torque noise plus an external
//! disturbance torque, held. The adaptation is fed the measurement and the
//! commanded torque (what a controller knows).
//!
//! A delay is `delay_samples + delay_fraction` samples. The fraction is
//! exact, not rounded: the plant's integration stops inside each sample at
//! the instant a later measurement will show (`t_(i+1) - fraction dt`), so
//! a delay of 40 ms at 25 ms samples shows the state of exactly 40 ms ago.

use crate::adapt::Adaptation;
use crate::integrate::{Dopri5, IntegrationError, Tolerances};
use crate::mechanics::{PlanarChain, Vector, state_derivative, state_energy};
use crate::mpc::Controller;
use crate::mpc::closed_loop::{GaussianNoise, Sample};
use nalgebra::SVector;
use std::collections::VecDeque;
use std::time::Instant;

/// The imperfections of one closed loop (the default: none).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Imperfections {
    /// Standard deviation of the measured angles' noise (rad), and of the
    /// speeds' (rad/s) unless [`Self::speed_noise`] is given.
    pub measurement_noise: f64,
    /// Standard deviation of the measured speeds' noise (rad/s) when it
    /// differs from the angles' (None: `measurement_noise` for both).
    pub speed_noise: Option<f64>,
    /// Standard deviation of the noise added to each joint's applied
    /// torque, drawn once per sample (N m).
    pub torque_noise: f64,
    /// Motor responsiveness `a` in (0, 2]: the applied torque moves the
    /// share `a` from the previous applied torque to the command per
    /// sample (1: immediate; above 1 it overshoots, as an under-damped
    /// current loop does).
    pub responsiveness: f64,
    /// Measurement delay, whole samples.
    pub delay_samples: usize,
    /// Measurement delay beyond `delay_samples`, a share of a sample in
    /// [0, 1).
    pub delay_fraction: f64,
    /// Seed of the noise (same seed, same run on every machine).
    pub seed: u64,
}

impl Default for Imperfections {
    fn default() -> Self {
        Self {
            measurement_noise: 0.0,
            speed_noise: None,
            torque_noise: 0.0,
            responsiveness: 1.0,
            delay_samples: 0,
            delay_fraction: 0.0,
            seed: 1,
        }
    }
}

impl Imperfections {
    /// Checks the fields; the message names the offending one.
    pub fn validate(&self) -> Result<(), String> {
        for (name, v) in [
            ("measurement_noise", self.measurement_noise),
            ("speed_noise", self.speed_noise.unwrap_or(0.0)),
            ("torque_noise", self.torque_noise),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("{name} = {v} must be finite and >= 0"));
            }
        }
        // Beyond 2 the lag `u += a (tau - u)` diverges (|1 - a| > 1).
        if !(self.responsiveness > 0.0 && self.responsiveness <= 2.0) {
            return Err(format!(
                "responsiveness = {} must be in (0, 2]",
                self.responsiveness
            ));
        }
        if !(self.delay_fraction >= 0.0 && self.delay_fraction < 1.0) {
            return Err(format!(
                "delay_fraction = {} must be in [0, 1)",
                self.delay_fraction
            ));
        }
        Ok(())
    }

    /// The speeds' noise (rad/s).
    pub fn speed_noise(&self) -> f64 {
        self.speed_noise.unwrap_or(self.measurement_noise)
    }
}

/// One imperfect closed loop: the samples (true state and energy, the
/// torque the plant got), the compute time of the adaptation per sample
/// (0 without) and the models it swapped in.
#[derive(Clone, Debug)]
pub struct ImperfectRun<const N: usize, const NX: usize> {
    /// Per sample: the true state, the applied torque (the motor's with
    /// the torque noise, without the disturbance), the plant's energy.
    pub samples: Vec<Sample<N, NX>>,
    /// Per sample: the motor's torque without the torque noise (the
    /// command after the motor's response): the effort the controller
    /// causes, which noise and disturbances do not.
    pub motor_torque: Vec<Vector<N>>,
    /// Wall time of `Adaptation::sample` per sample (s).
    pub adaptation_time: Vec<f64>,
    /// Models the adaptation swapped in.
    pub model_updates: usize,
}

/// Runs `duration` seconds of `controller` (and `adaptation`, if given) on
/// `plant` from `z0` with `imperfections`; the plant is integrated by
/// adaptive Dormand-Prince (rtol = atol = 1e-10), the applied torque held
/// over each sample.
pub fn run_imperfect<const N: usize, const NX: usize, const NP: usize>(
    controller: &mut Controller<PlanarChain<N>, N, NX>,
    adaptation: Option<&mut Adaptation<N, NX, NP>>,
    plant: &PlanarChain<N>,
    z0: &SVector<f64, NX>,
    duration: f64,
    imperfections: &Imperfections,
) -> Result<ImperfectRun<N, NX>, IntegrationError> {
    run_imperfect_disturbed(
        controller,
        adaptation,
        plant,
        z0,
        duration,
        imperfections,
        |_| Vector::<N>::zeros(),
    )
}

/// [`run_imperfect`] with an external torque `disturbance(t_k)` (N m per
/// joint) added to what the plant gets over the sample from `t_k`: the
/// plant feels it, the recorded torque ([`Sample::tau`], the motor's) does
/// not include it and the controller does not know it.
pub fn run_imperfect_disturbed<const N: usize, const NX: usize, const NP: usize>(
    controller: &mut Controller<PlanarChain<N>, N, NX>,
    mut adaptation: Option<&mut Adaptation<N, NX, NP>>,
    plant: &PlanarChain<N>,
    z0: &SVector<f64, NX>,
    duration: f64,
    imperfections: &Imperfections,
    disturbance: impl Fn(f64) -> Vector<N>,
) -> Result<ImperfectRun<N, NX>, IntegrationError> {
    let dt = controller.config().dt;
    let steps = (duration / dt).round() as usize;
    let mut samples = Vec::with_capacity(steps + 1);
    let mut adaptation_time = Vec::with_capacity(steps + 1);
    let mut motor_torque = Vec::with_capacity(steps + 1);
    let tol = Tolerances {
        rtol: 1e-10,
        atol: 1e-10,
    };
    let mut ode = Dopri5::new(0.0, *z0, tol);
    let mut noise = GaussianNoise::new(imperfections.seed);
    // With a fractional delay the history holds the states at
    // `t_i + (1 - fraction) dt` inside each sample, one sample further
    // back; before the first sample the plant rested at z0.
    let fraction = imperfections.delay_fraction;
    let fractional = fraction > 0.0;
    let mut history: VecDeque<SVector<f64, NX>> =
        std::iter::repeat_n(*z0, imperfections.delay_samples + usize::from(fractional)).collect();
    let a = imperfections.responsiveness;
    let (angle_noise, speed_noise) = (imperfections.measurement_noise, imperfections.speed_noise());
    let mut applied = Vector::<N>::zeros();
    for i in 0..=steps {
        let t = i as f64 * dt;
        let z = *ode.state();
        if !fractional {
            history.push_back(z);
        }
        let seen = history.pop_front().unwrap_or(z);
        let measured = if angle_noise > 0.0 || speed_noise > 0.0 {
            noise.measure(&seen, angle_noise, speed_noise)
        } else {
            seen
        };
        let out = controller.step(&measured);
        // The identification takes the measured state (not a state
        // estimate: the estimator's model is the one being corrected, and
        // its estimate leans towards it) and the torque commanded over the
        // sample before; a new model serves from the next sample.
        let started = Instant::now();
        if let Some(adaptation) = adaptation.as_deref_mut() {
            let q = Vector::<N>::from_fn(|j, _| measured[j]);
            let qd = Vector::<N>::from_fn(|j, _| measured[N + j]);
            // The torque that acted before the measurement was taken, as
            // far as the controller knows (the previous command when it
            // declares neither delay nor lag).
            let tau = controller.torque_before_measurement();
            adaptation.sample(controller, &q, &qd, &tau, dt);
        }
        adaptation_time.push(started.elapsed().as_secs_f64());
        applied = out.tau * a + applied * (1.0 - a);
        motor_torque.push(applied);
        let mut torque = applied;
        if imperfections.torque_noise > 0.0 {
            for j in 0..N {
                torque[j] += imperfections.torque_noise * noise.sample();
            }
        }
        samples.push(Sample {
            time: t,
            state: z,
            tau: torque,
            energy: state_energy::<PlanarChain<N>, N, NX>(plant, &z),
            solve_time: out.preparation_time + out.feedback_time,
            preparation_time: out.preparation_time,
            status: out.status,
            qp_iterations: out.qp_iterations,
        });
        if i == steps {
            break;
        }
        let felt = torque + disturbance(t);
        let rhs = |_: f64, z: &SVector<f64, NX>| {
            state_derivative::<PlanarChain<N>, N, NX>(plant, z, &felt)
        };
        if fractional {
            history.push_back(*ode.advance_to(rhs, t + (1.0 - fraction) * dt)?);
        }
        ode.advance_to(rhs, (i + 1) as f64 * dt)?;
    }
    Ok(ImperfectRun {
        samples,
        motor_torque,
        adaptation_time,
        model_updates: adaptation.map_or(0, |a| a.model_updates()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::PlanarChainParams;
    use crate::mpc::closed_loop::{reference_for, run};
    use crate::mpc::{MpcConfig, Variant};

    fn controller() -> Controller<PlanarChain<2>, 2, 4> {
        let model = PlanarChain::new(PlanarChainParams::default()).unwrap();
        let reference = reference_for::<_, 2, 4>(&model, Variant::Curved, 0, 14.0).unwrap();
        let mut config = MpcConfig::paper(Variant::Curved);
        config.horizon = 20;
        Controller::new(model, config, reference).unwrap()
    }

    /// Without imperfections the loop is the plain closed loop, sample for
    /// sample.
    #[test]
    fn no_imperfections_is_the_plain_closed_loop() {
        let plant = PlanarChain::new(PlanarChainParams::default()).unwrap();
        let z0 = SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0);
        let plain = run(&mut controller(), &plant, &z0, 2.0).unwrap();
        let imperfect = run_imperfect::<2, 4, 11>(
            &mut controller(),
            None,
            &plant,
            &z0,
            2.0,
            &Imperfections::default(),
        )
        .unwrap();
        assert_eq!(plain.len(), imperfect.samples.len());
        for (a, b) in plain.iter().zip(&imperfect.samples) {
            assert_eq!((a.state, a.tau, a.energy), (b.state, b.tau, b.energy));
        }
    }

    /// The delay shows the controller the state of `delay` samples ago; a
    /// sluggish motor moves the share `a` towards the command per sample.
    #[test]
    fn delay_and_responsiveness_act_as_defined() {
        let plant = PlanarChain::new(PlanarChainParams::default()).unwrap();
        let z0 = SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0);
        let plain = run_imperfect::<2, 4, 11>(
            &mut controller(),
            None,
            &plant,
            &z0,
            1.0,
            &Imperfections::default(),
        )
        .unwrap();
        let lag = Imperfections {
            responsiveness: 0.5,
            ..Imperfections::default()
        };
        let lagged =
            run_imperfect::<2, 4, 11>(&mut controller(), None, &plant, &z0, 1.0, &lag).unwrap();
        // same first command (same state), half of it applied
        assert_eq!(lagged.samples[0].tau, plain.samples[0].tau * 0.5);
        assert_eq!(lagged.motor_torque[0], lagged.samples[0].tau);
        // torque noise is in what the plant got, not in the motor's torque
        let noisy = Imperfections {
            torque_noise: 0.1,
            ..Imperfections::default()
        };
        let noisy =
            run_imperfect::<2, 4, 11>(&mut controller(), None, &plant, &z0, 1.0, &noisy).unwrap();
        assert_eq!(noisy.motor_torque[0], plain.samples[0].tau);
        assert!((noisy.samples[0].tau - plain.samples[0].tau).norm() > 1e-3);
        // a delayed controller's first samples see z0: the same command as
        // the undelayed one at t = 0, while the plant has moved
        let delayed = Imperfections {
            delay_samples: 2,
            ..Imperfections::default()
        };
        let mut c = controller();
        let run = run_imperfect::<2, 4, 11>(&mut c, None, &plant, &z0, 1.0, &delayed).unwrap();
        let mut reference = controller();
        let first = reference.step(&z0).tau;
        assert_eq!(run.samples[0].tau, first);
        assert_eq!(run.samples[1].tau, reference.step(&z0).tau);
        assert_eq!(
            run.samples[2].tau,
            reference.step(&run.samples[0].state).tau
        );
        assert!(
            Imperfections {
                responsiveness: 0.0,
                ..Imperfections::default()
            }
            .validate()
            .is_err()
        );
    }

    /// A delay of 1.6 samples shows the controller the plant's state of
    /// exactly 1.6 samples ago (integrated to that instant, not rounded).
    #[test]
    fn fractional_delay_shows_the_state_of_exactly_then() {
        use crate::integrate::simulate_accurate;
        let plant = PlanarChain::new(PlanarChainParams::default()).unwrap();
        let z0 = SVector::<f64, 4>::new(0.3, -0.2, 0.5, 0.1);
        let delayed = Imperfections {
            delay_samples: 1,
            delay_fraction: 0.6,
            ..Imperfections::default()
        };
        assert!(delayed.validate().is_ok());
        let run =
            run_imperfect::<2, 4, 11>(&mut controller(), None, &plant, &z0, 0.5, &delayed).unwrap();
        let dt = 0.025;
        let tol = Tolerances {
            rtol: 1e-11,
            atol: 1e-11,
        };
        let mut reference = controller();
        // samples 0 and 1 see the rest before the start
        assert_eq!(run.samples[0].tau, reference.step(&z0).tau);
        assert_eq!(run.samples[1].tau, reference.step(&z0).tau);
        for k in 2..12 {
            let back = &run.samples[k - 2];
            let then = simulate_accurate(&plant, &back.state, &back.tau, 0.4 * dt, tol).unwrap();
            let expected = reference.step(&then).tau;
            assert!(
                (run.samples[k].tau - expected).norm() < 1e-7,
                "sample {k}: {} vs {expected}",
                run.samples[k].tau
            );
        }
        for bad in [-0.1, 1.0] {
            let i = Imperfections {
                delay_fraction: bad,
                ..Imperfections::default()
            };
            assert!(i.validate().is_err(), "{bad}");
        }
    }

    /// An overshooting motor (a = 2) is allowed, beyond 2 it diverges; a
    /// disturbance moves the plant but is not the motor's torque.
    #[test]
    fn overshooting_motor_and_disturbance_act_as_defined() {
        use crate::integrate::simulate_accurate;
        for (a, ok) in [(2.0, true), (2.01, false)] {
            let i = Imperfections {
                responsiveness: a,
                ..Imperfections::default()
            };
            assert_eq!(i.validate().is_ok(), ok, "{a}");
        }
        let plant = PlanarChain::new(PlanarChainParams::default()).unwrap();
        let z0 = SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0);
        let d = Vector::<2>::new(0.3, -0.2);
        let run = run_imperfect_disturbed::<2, 4, 11>(
            &mut controller(),
            None,
            &plant,
            &z0,
            0.1,
            &Imperfections::default(),
            |t| if t < 0.01 { d } else { Vector::<2>::zeros() },
        )
        .unwrap();
        let first = controller().step(&z0).tau;
        assert_eq!(run.samples[0].tau, first);
        let tol = Tolerances {
            rtol: 1e-11,
            atol: 1e-11,
        };
        let expected = simulate_accurate(&plant, &z0, &(first + d), 0.025, tol).unwrap();
        let undisturbed = simulate_accurate(&plant, &z0, &first, 0.025, tol).unwrap();
        assert!((run.samples[1].state - expected).norm() < 1e-8);
        assert!((run.samples[1].state - undisturbed).norm() > 1e-4);
    }
}
