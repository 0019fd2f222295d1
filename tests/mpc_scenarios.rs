//! Closed-loop scenarios of the paper (section V) with the assertions of
//! issue 3. Long: run in release by tests/run.sh.

use eigenmpc::mechanics::DoublePendulum;
use eigenmpc::modes::linear_modes;
use eigenmpc::mpc::closed_loop::{Summary, mode_and_chart, run, summarise};
use eigenmpc::mpc::{Controller, MpcConfig, Reference, Variant};
use nalgebra::SVector;

fn scenario(
    variant: Variant,
    family: usize,
    e_ref: f64,
    q0: [f64; 2],
    duration: f64,
) -> Summary<2> {
    let sys = DoublePendulum::default();
    let (mode, chart) = mode_and_chart::<_, 2, 4>(&sys, family, e_ref, 9).unwrap();
    let reference = match variant {
        Variant::Straight => Reference::Straight {
            eigenvector: linear_modes(&sys).unwrap()[family].eigenvector,
        },
        Variant::Curved => Reference::Curved(chart),
    };
    let mut config = MpcConfig::paper(variant);
    config.cost.e_ref = e_ref;
    let mut ctrl = Controller::<_, 2, 4>::new(sys, config, reference).unwrap();
    let z0 = SVector::<f64, 4>::new(q0[0], q0[1], 0.0, 0.0);
    let trace = run(&mut ctrl, &sys, &z0, duration).unwrap();
    let s = summarise(&trace, e_ref, Some(&mode.path), 5.0);
    eprintln!("{variant} family {family} E_ref {e_ref} q0 {q0:?}: {s:?}");
    s
}

#[test]
fn curved_in_phase_14j_reaches_the_mode_torque_free() {
    let s = scenario(Variant::Curved, 0, 14.0, [0.05, 0.05], 30.0);
    assert_eq!(s.failures, 0);
    assert!(s.time_to_5_percent.is_some_and(|t| t <= 25.0), "{s:?}");
    assert!(s.rms_torque.iter().all(|&t| t < 0.03), "{s:?}");
    assert!(s.rms_distance.unwrap() < 0.01, "{s:?}");
}

#[test]
fn straight_anti_phase_12j_reaches_energy_within_10s() {
    let s = scenario(Variant::Straight, 1, 12.0, [0.05, 0.05], 15.0);
    assert_eq!(s.failures, 0);
    assert!(s.time_to_5_percent.is_some_and(|t| t <= 10.0), "{s:?}");
}

#[test]
fn curved_recovers_from_large_initial_conditions() {
    // Paper, section V-B2: from theta = (-1.1, 1.1) the curved version
    // recovers quickly (measured: 9.95 s to 5 %).
    let s = scenario(Variant::Curved, 0, 14.0, [-1.1, 1.1], 20.0);
    assert_eq!(s.failures, 0);
    assert!(s.time_to_5_percent.is_some_and(|t| t <= 15.0), "{s:?}");
    assert!(s.rms_torque.iter().all(|&t| t < 0.03), "{s:?}");
    assert!(s.rms_distance.unwrap() < 0.01, "{s:?}");
}

#[test]
fn straight_in_phase_2j_finds_a_mode_nearby() {
    // Paper, Fig. 2(a): at low energy the straight version settles close to
    // the true eigenmode (measured: 0.0084 rad RMS after 30 s).
    let s = scenario(Variant::Straight, 0, 2.0, [0.05, 0.05], 30.0);
    assert_eq!(s.failures, 0);
    assert!(s.time_to_5_percent.is_some_and(|t| t <= 25.0), "{s:?}");
    assert!(s.rms_distance.unwrap() < 0.02, "{s:?}");
    assert!(s.rms_torque.iter().all(|&t| t < 0.05), "{s:?}");
}

#[test]
fn riccati_backend_plugs_into_the_controller_and_matches_clarabel() {
    use eigenmpc::qp::{RiccatiSettings, RiccatiSolver};
    let sys = DoublePendulum::default();
    let (_, chart) = mode_and_chart::<_, 2, 4>(&sys, 0, 14.0, 9).unwrap();
    let config = MpcConfig::paper(Variant::Curved);
    let z0 = SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0);
    let mut clarabel =
        Controller::<_, 2, 4>::new(sys, config, Reference::Curved(chart.clone())).unwrap();
    let riccati = RiccatiSolver::new(4, 2, config.horizon, RiccatiSettings::default());
    let mut ctrl = Controller::<_, 2, 4>::with_solver(
        sys,
        config,
        Reference::Curved(chart),
        Box::new(riccati),
    )
    .unwrap();
    assert_eq!(ctrl.qp_solver_name(), "riccati");
    let a = run(&mut clarabel, &sys, &z0, 10.0).unwrap();
    let b = run(&mut ctrl, &sys, &z0, 10.0).unwrap();
    let worst = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x.energy - y.energy).abs())
        .fold(0.0, f64::max);
    eprintln!("riccati vs clarabel, 10 s curved 14 J: max energy difference {worst:e} J");
    assert!(b.iter().all(|s| s.status.is_ok()));
    assert!(worst < 1e-3, "{worst}");
}
