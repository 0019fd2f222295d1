//! Measurement delay and actuator lag compensation (issue 19, item 3): the
//! paper's double pendulum, curved EigenMPC, 14 J, from q = (0.05, 0.05),
//! in the robustness loop ([`eigenmpc::robustness::run_imperfect`]) with a
//! delayed measurement and a sluggish motor, declared to the controller
//! (`measurement_delay`, `actuator_time_constant`) or not.
//!
//! `cargo test --test mpc_delay measure_table -- --ignored --nocapture` prints
//! the table of docs/delay.md.

use eigenmpc::integrate::{Dopri5, Tolerances};
use eigenmpc::math;
use eigenmpc::mechanics::{PlanarChain, PlanarChainParams, Vector, state_derivative};
use eigenmpc::mpc::closed_loop::{energy_tail, reference_for, summarise};
use eigenmpc::mpc::{Controller, EstimatorConfig, MpcConfig, MpcError, Variant};
use eigenmpc::robustness::{Imperfections, run_imperfect};
use nalgebra::SVector;

const E_REF: f64 = 14.0;
const DT: f64 = 0.025;
/// Long enough to settle at E_ref from q = (0.05, 0.05) (~20 s) and keep a
/// 5 s window of the settled orbit.
const DURATION: f64 = 30.0;
const WINDOW: f64 = 5.0;

fn pendulum() -> PlanarChain<2> {
    PlanarChain::new(PlanarChainParams::default()).unwrap()
}

fn controller(delay: f64, time_constant: f64) -> Controller<PlanarChain<2>, 2, 4> {
    let model = pendulum();
    let reference = reference_for::<_, 2, 4>(&model, Variant::Curved, 0, E_REF).unwrap();
    let mut config = MpcConfig::paper(Variant::Curved);
    config.measurement_delay = delay;
    config.actuator_time_constant = time_constant;
    Controller::new(model, config, reference).unwrap()
}

/// The responsiveness `a` of the robustness loop's discrete lag whose
/// samples match a first-order lag of time constant `lag_samples dt`.
fn responsiveness(lag_samples: f64) -> f64 {
    if lag_samples == 0.0 {
        1.0
    } else {
        1.0 - math::exp(-1.0 / lag_samples)
    }
}

/// What one closed loop ends with.
#[derive(Debug)]
struct Outcome {
    /// Mean energy of the last 5 s relative to E_ref (%).
    energy_error_percent: f64,
    /// Energy at the end relative to E_ref (%).
    final_energy_error_percent: f64,
    /// RMS torque over the last 5 s, both joints together (N m).
    rms_torque: f64,
    /// Samples whose status was not OK.
    failures: usize,
    /// First time after which the energy stays within 5 % of E_ref (s).
    time_to_5_percent: Option<f64>,
}

/// The paper's run with a delay of `delay_samples` and a lag of
/// `lag_samples` samples in the plant, and `declared` (delay, lag in
/// seconds) in the controller.
fn run_case(delay_samples: usize, lag_samples: f64, declared: (f64, f64)) -> Outcome {
    run_noisy(delay_samples, lag_samples, declared, None)
}

/// [`run_case`] with measurement noise of standard deviation `noise` (rad,
/// rad/s) filtered by the controller's EKF.
fn run_noisy(
    delay_samples: usize,
    lag_samples: f64,
    declared: (f64, f64),
    noise: Option<f64>,
) -> Outcome {
    let mut ctrl = match noise {
        None => controller(declared.0, declared.1),
        Some(sigma) => {
            let model = pendulum();
            let reference = reference_for::<_, 2, 4>(&model, Variant::Curved, 0, E_REF).unwrap();
            let mut config = MpcConfig::paper(Variant::Curved);
            config.measurement_delay = declared.0;
            config.actuator_time_constant = declared.1;
            config.estimator = Some(EstimatorConfig {
                angle_noise: sigma,
                speed_noise: sigma,
                acceleration_noise: 0.3,
            });
            Controller::new(model, config, reference).unwrap()
        }
    };
    let imperfections = Imperfections {
        delay_samples,
        responsiveness: responsiveness(lag_samples),
        measurement_noise: noise.unwrap_or(0.0),
        ..Imperfections::default()
    };
    let z0 = SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0);
    let run =
        run_imperfect::<2, 4, 11>(&mut ctrl, None, &pendulum(), &z0, DURATION, &imperfections)
            .unwrap();
    let samples = &run.samples;
    let (mean, _) = energy_tail(samples, E_REF, WINDOW);
    let t_end = samples.last().unwrap().time;
    let tail: Vec<_> = samples
        .iter()
        .filter(|s| s.time > t_end - WINDOW + 1e-9)
        .collect();
    let rms_torque =
        (tail.iter().map(|s| s.tau.norm_squared()).sum::<f64>() / tail.len() as f64).sqrt();
    Outcome {
        energy_error_percent: 100.0 * (mean - E_REF) / E_REF,
        final_energy_error_percent: 100.0 * (samples.last().unwrap().energy - E_REF) / E_REF,
        rms_torque,
        failures: samples.iter().filter(|s| !s.status.is_ok()).count(),
        time_to_5_percent: summarise(samples, E_REF, None, WINDOW).time_to_5_percent,
    }
}

#[test]
#[ignore = "measurement table (about 10 s)"]
fn measure_table() {
    println!(
        "| plant delay (samples) | plant lag T (samples) | declared delay, T (samples) | mean E err 5 s % | final E err % | RMS tau 5 s (N m) | to 5 % (s) | failures |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    // (plant delay, plant lag, declared delay, declared lag), in samples.
    let cases: Vec<(usize, f64, f64, f64)> = match std::env::var("DELAY_CASES") {
        Ok(text) => text
            .split(';')
            .map(|c| {
                let v: Vec<f64> = c.split(',').map(|x| x.trim().parse().unwrap()).collect();
                (v[0] as usize, v[1], v[2], v[3])
            })
            .collect(),
        Err(_) => vec![
            (0, 0.0, 0.0, 0.0),
            (2, 0.0, 0.0, 0.0),
            (2, 0.0, 2.0, 0.0),
            (4, 0.0, 0.0, 0.0),
            (4, 0.0, 4.0, 0.0),
            (0, 1.0, 0.0, 0.0),
            (0, 1.0, 0.0, 1.0),
            (0, 2.0, 0.0, 0.0),
            (0, 2.0, 0.0, 2.0),
            (4, 2.0, 0.0, 0.0),
            (4, 2.0, 4.0, 0.0),
            (4, 2.0, 4.0, 2.0),
            (0, 4.0, 0.0, 0.0),
            (0, 4.0, 0.0, 4.0),
            (0, 8.0, 0.0, 0.0),
            (0, 8.0, 0.0, 8.0),
            (4, 4.0, 0.0, 0.0),
            (4, 4.0, 4.0, 0.0),
            (4, 4.0, 4.0, 4.0),
        ],
    };
    for (d, l, dd, dl) in cases {
        let o = run_case(d, l, (dd * DT, dl * DT));
        println!(
            "| {d} | {l} | {dd}, {dl} | {:+.3} | {:+.3} | {:.4} | {} | {} |",
            o.energy_error_percent,
            o.final_energy_error_percent,
            o.rms_torque,
            o.time_to_5_percent
                .map_or("never".to_string(), |t| format!("{t:.2}")),
            o.failures
        );
    }
}

/// RMS torques of two runs agree within `share` of the first.
fn close(a: f64, b: f64, share: f64) -> bool {
    (a - b).abs() <= share * a
}

/// A declared delay of 2 or 4 samples costs nothing: the settled orbit's
/// energy and torque are the undelayed run's (measured: the same to four
/// digits, 0.0160 N m). Undeclared, the torque grows (measured: 0.0270 N m
/// at 2 samples, 0.0193 N m at 4), which this test would catch.
#[test]
fn a_declared_delay_costs_nothing() {
    let none = run_case(0, 0.0, (0.0, 0.0));
    for d in [2, 4] {
        let declared = run_case(d, 0.0, (d as f64 * DT, 0.0));
        eprintln!("delay {d}: {declared:?} (none: {none:?})");
        assert_eq!(declared.failures, 0);
        assert!(declared.energy_error_percent.abs() < 1.0, "{declared:?}");
        assert!(
            declared.final_energy_error_percent.abs() < 1.0,
            "{declared:?}"
        );
        assert!(
            close(none.rms_torque, declared.rms_torque, 0.03),
            "{declared:?} vs {none:?}"
        );
    }
}

/// A declared lag of 2 samples (the plant's a = 1 - exp(-1/2)) costs
/// nothing either: energy on target, and less torque than without lag or
/// with the lag undeclared (measured: 0.0124 N m against 0.0160 without
/// lag and 0.0151 undeclared). With a 4-sample delay on top: the same
/// (measured 0.0126 N m); undeclared, that pair drives the pendulum off
/// its orbit (0.82 N m, +2.2 % energy at the end).
#[test]
fn a_declared_lag_costs_nothing() {
    let none = run_case(0, 0.0, (0.0, 0.0));
    let undeclared = run_case(0, 2.0, (0.0, 0.0));
    let declared = run_case(0, 2.0, (0.0, 2.0 * DT));
    let both = run_case(4, 2.0, (4.0 * DT, 2.0 * DT));
    eprintln!("lag 2: declared {declared:?}, undeclared {undeclared:?}; with delay 4: {both:?}");
    for o in [&declared, &both] {
        assert_eq!(o.failures, 0);
        assert!(o.energy_error_percent.abs() < 1.0, "{o:?}");
        assert!(o.final_energy_error_percent.abs() < 1.0, "{o:?}");
        assert!(o.rms_torque < none.rms_torque, "{o:?} vs {none:?}");
    }
    assert!(
        declared.rms_torque < 0.9 * undeclared.rms_torque,
        "{declared:?} vs {undeclared:?}"
    );
    assert!(
        close(declared.rms_torque, both.rms_torque, 0.05),
        "{both:?}"
    );
}

/// Nothing catastrophic when not declared: a 4-sample delay alone keeps
/// the orbit (measured -0.24 % energy, 0.0193 N m); with a 2-sample lag on
/// top the torque grows fifty-fold but stays bounded and the energy near
/// E_ref (measured +0.34 % mean, 0.82 N m), without a failed solve.
#[test]
fn undeclared_delay_and_lag_stay_bounded() {
    let delay = run_case(4, 0.0, (0.0, 0.0));
    assert_eq!(delay.failures, 0);
    assert!(delay.energy_error_percent.abs() < 1.0, "{delay:?}");
    let both = run_case(4, 2.0, (0.0, 0.0));
    eprintln!("undeclared: delay 4 {delay:?}; delay 4, lag 2 {both:?}");
    assert_eq!(both.failures, 0);
    assert!(both.energy_error_percent.abs() < 5.0, "{both:?}");
    assert!(both.rms_torque <= 1.0, "{both:?}");
}

/// With the EKF on a noisy measurement (0.01 rad, 0.01 rad/s): it filters
/// the delayed measurement at its own time with the torque acting then,
/// and the filtered state is predicted forward. A declared 4-sample delay
/// then costs what it costs without noise: nothing measurable against the
/// undelayed filtered run.
#[test]
fn the_estimator_filters_the_delayed_measurement() {
    let none = run_noisy(0, 0.0, (0.0, 0.0), Some(0.01));
    let declared = run_noisy(4, 0.0, (4.0 * DT, 0.0), Some(0.01));
    let undeclared = run_noisy(4, 0.0, (0.0, 0.0), Some(0.01));
    eprintln!("EKF: none {none:?}\n  declared {declared:?}\n  undeclared {undeclared:?}");
    assert_eq!(declared.failures, 0);
    assert!(declared.energy_error_percent.abs() < 1.0, "{declared:?}");
    // Measured: 3 % apart (undeclared: 19 % more torque).
    assert!(
        close(none.rms_torque, declared.rms_torque, 0.06),
        "{declared:?} vs {none:?}"
    );
}

/// The torque the plant gets at time `t` from the commands `sent` (the
/// j-th from `j dt` on; none before 0) through a first-order lag of time
/// constant `lag` (0: none), from rest.
fn applied_torque(t: f64, sent: &[Vector<2>], lag: f64) -> Vector<2> {
    let mut a = Vector::<2>::zeros();
    for (j, u) in sent.iter().enumerate() {
        let start = j as f64 * DT;
        if t < start {
            break;
        }
        if lag == 0.0 {
            a = *u;
        } else {
            a = u + (a - u) * math::exp(-(t - start).min(DT) / lag);
        }
        if t <= start + DT {
            return a;
        }
    }
    a
}

/// The EKF filters the delayed measurement with the torque that acted
/// before it: on noise-free measurements of a plant that is exactly its
/// model, the estimate stays on the measurement (to the RK4 accuracy),
/// for a whole-sample delay, a fractional one and a lag. With the last
/// command instead (the undelayed propagation) it would be off by the
/// effect of 4 samples' torque difference.
#[test]
fn the_estimator_propagates_with_the_torque_of_the_measurement_time() {
    let model = pendulum();
    let reference = reference_for::<_, 2, 4>(&model, Variant::Curved, 0, E_REF).unwrap();
    for (delay, lag) in [(0.1, 0.0), (0.0625, 0.0), (0.0625, 0.05)] {
        let mut config = MpcConfig::paper(Variant::Curved);
        config.horizon = 40;
        config.measurement_delay = delay;
        config.actuator_time_constant = lag;
        config.estimator = Some(EstimatorConfig {
            angle_noise: 0.01,
            speed_noise: 0.01,
            acceleration_noise: 0.3,
        });
        let mut ctrl = Controller::<_, 2, 4>::new(model, config, reference.clone()).unwrap();
        // The plant rests at z0 until the first measurement's time -D (the
        // controller takes zero torque before its first command).
        let z0 = SVector::<f64, 4>::new(0.4, 0.3, 0.0, 0.0);
        let tol = Tolerances {
            rtol: 1e-12,
            atol: 1e-12,
        };
        let mut ode = Dopri5::new(-delay, z0, tol);
        let mut sent: Vec<Vector<2>> = Vec::new();
        let mut worst: f64 = 0.0;
        for k in 0..40 {
            let measured = *ode.state();
            sent.push(ctrl.step(&measured).tau);
            let estimate = ctrl.state_estimate().unwrap();
            worst = worst.max((estimate - measured).amax());
            // To the next measurement, piece by piece between samples.
            let t_next = (k + 1) as f64 * DT - delay;
            for (t0, t1) in pieces(ode.time(), t_next, 0.0) {
                let _ = t0;
                ode.advance_to(
                    |t, x| {
                        let tau = applied_torque(t, &sent, lag);
                        state_derivative::<_, 2, 4>(&model, x, &tau)
                    },
                    t1,
                )
                .unwrap();
            }
        }
        let moved = sent.iter().map(|u| u.amax()).fold(0.0, f64::max);
        eprintln!(
            "delay {delay}, lag {lag}: estimate off the measurement by {worst:e}; |tau| up to {moved}"
        );
        assert!(moved > 0.1, "{moved}");
        assert!(worst < 1e-5, "delay {delay}, lag {lag}: {worst}");
    }
}

/// The forward prediction is the controller's model integrated over the
/// delay with the torques it sent: compared with Dormand-Prince at tight
/// tolerance on the same model and torques (a whole-sample delay, a
/// fractional one, and a lag, integrated exactly over the delay).
#[test]
fn forward_prediction_is_the_model_over_the_delay() {
    let model = pendulum();
    for (delay, lag) in [(0.1, 0.0), (0.0625, 0.0), (0.0625, 0.03)] {
        let mut ctrl = controller(delay, lag);
        let mut z = SVector::<f64, 4>::new(0.3, -0.2, 0.5, 0.1);
        let mut sent = Vec::new();
        for _ in 0..8 {
            sent.push(ctrl.step(&z).tau);
            z = eigenmpc::integrate::rk4_step::<_, 2, 4>(&model, &z, &sent[sent.len() - 1], DT);
        }
        // The measurement of sample k = 8 taken `delay` before it.
        let measured = z;
        let predicted_at_sample = {
            ctrl.step(&measured);
            *ctrl.predicted_current_state().unwrap()
        };
        // Reference: t = 0 is sample 8; command j (0-based) acts over
        // [(j - 8) dt, (j - 7) dt]; applied torque a(t) by the exact lag.
        let applied_at = |t: f64| -> Vector<2> {
            if lag == 0.0 {
                let j = ((t / DT) + 8.0).floor() as usize;
                return sent[j.min(7)];
            }
            // Integrate the lag's closed form sample by sample.
            let mut a = Vector::<2>::zeros();
            for (j, u) in sent.iter().enumerate() {
                let start = (j as f64 - 8.0) * DT;
                let end = start + DT;
                if t <= end {
                    return u + (a - u) * math::exp(-(t - start) / lag);
                }
                a = u + (a - u) * math::exp(-DT / lag);
            }
            a
        };
        let command_at = |t: f64| -> Vector<2> {
            let j = ((t / DT) + 8.0).floor() as usize;
            sent[j.min(7)]
        };
        let tol = Tolerances {
            rtol: 1e-12,
            atol: 1e-12,
        };
        let mut ode = Dopri5::new(-delay, measured, tol);
        // Piecewise: every sample boundary is a breakpoint of the torque.
        for (t0, t1) in pieces(-delay, 0.0, 0.0) {
            let tau_mid = command_at(0.5 * (t0 + t1));
            ode.advance_to(
                |s, x| {
                    let tau = if lag == 0.0 { tau_mid } else { applied_at(s) };
                    state_derivative::<_, 2, 4>(&model, x, &tau)
                },
                t1,
            )
            .unwrap();
        }
        // Then over T the commands delayed by T (the lag's approximation).
        for (s0, s1) in pieces(0.0, lag, lag) {
            let tau = command_at(0.5 * (s0 + s1) - lag);
            ode.advance_to(|_, x| state_derivative::<_, 2, 4>(&model, x, &tau), s1)
                .unwrap();
        }
        let reference = *ode.state();
        let err = (predicted_at_sample - reference).amax();
        eprintln!("delay {delay} s, lag {lag} s: prediction error {err:e}");
        // RK4 of 25 ms on this pendulum: measured 1e-7 .. 4e-7 over these
        // 2.5 .. 4 samples, against a 2e-2 change of the state.
        assert!(err < 1e-6, "delay {delay}, lag {lag}: {err}");
        assert!((predicted_at_sample - measured).amax() > 1e-2);
    }
}

/// The pieces of `[from, to]` between the times `shift + k dt`.
fn pieces(from: f64, to: f64, shift: f64) -> Vec<(f64, f64)> {
    let mut cuts = vec![from];
    let k0 = ((from - shift) / DT).floor() as i64 - 1;
    let k1 = ((to - shift) / DT).ceil() as i64 + 1;
    for k in k0..=k1 {
        let t = shift + k as f64 * DT;
        if t > from + 1e-12 && t < to - 1e-12 {
            cuts.push(t);
        }
    }
    cuts.push(to);
    cuts.windows(2)
        .map(|w| (w[0], w[1]))
        .filter(|(a, b)| b > a)
        .collect()
}

#[test]
fn delay_and_lag_are_validated() {
    let model = pendulum();
    let reference = reference_for::<_, 2, 4>(&model, Variant::Curved, 0, E_REF).unwrap();
    let mut config = MpcConfig::paper(Variant::Curved);
    config.horizon = 20; // 0.5 s
    for (delay, lag, bad) in [
        (-0.01, 0.0, "measurement_delay"),
        (f64::NAN, 0.0, "measurement_delay"),
        (0.6, 0.0, "measurement_delay"),
        (0.0, f64::INFINITY, "actuator_time_constant"),
        (0.0, -1.0, "actuator_time_constant"),
        (0.0, 0.51, "actuator_time_constant"),
    ] {
        let mut c = config;
        c.measurement_delay = delay;
        c.actuator_time_constant = lag;
        match Controller::<_, 2, 4>::new(model, c, reference.clone()) {
            Err(MpcError::InvalidParameter { name, .. }) => assert_eq!(name, bad),
            other => panic!("{delay} {lag}: {:?}", other.err()),
        }
    }
    config.horizon = 80; // 2 s: the 1 s bound applies
    config.measurement_delay = 1.01;
    assert!(Controller::<_, 2, 4>::new(model, config, reference.clone()).is_err());
    config.measurement_delay = 1.0;
    config.actuator_time_constant = 1.0;
    assert!(Controller::<_, 2, 4>::new(model, config, reference).is_ok());
}

/// Save and restore mid-run with a delay, a lag and the estimator: the
/// restored controller continues bit for bit (the command history is part
/// of the state).
#[test]
fn saved_state_carries_the_command_history() {
    let model = pendulum();
    let reference = reference_for::<_, 2, 4>(&model, Variant::Curved, 0, E_REF).unwrap();
    let mut config = MpcConfig::paper(Variant::Curved);
    config.horizon = 40;
    config.measurement_delay = 0.0625;
    config.actuator_time_constant = 0.05;
    config.estimator = Some(EstimatorConfig {
        angle_noise: 0.01,
        speed_noise: 0.05,
        acceleration_noise: 0.3,
    });
    let mut a = Controller::<_, 2, 4>::new(model, config, reference.clone()).unwrap();
    let mut z = SVector::<f64, 4>::new(0.3, 0.2, 0.0, 0.0);
    for _ in 0..10 {
        let tau = a.step(&z).tau;
        z = eigenmpc::integrate::rk4_step::<_, 2, 4>(&model, &z, &tau, DT);
    }
    let saved = a.save_state();
    let mut b = Controller::<_, 2, 4>::new(model, config, reference.clone()).unwrap();
    b.restore_state(saved.clone()).unwrap();
    for _ in 0..10 {
        let ta = a.step(&z).tau;
        let tb = b.step(&z).tau;
        assert_eq!(ta, tb);
        z = eigenmpc::integrate::rk4_step::<_, 2, 4>(&model, &z, &ta, DT);
    }
    // Another delay: another history length, refused.
    config.measurement_delay = 0.2;
    let mut c = Controller::<_, 2, 4>::new(model, config, reference).unwrap();
    assert!(c.restore_state(saved).is_err());
}
