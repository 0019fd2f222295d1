//! Eigenmode engine checks: brake orbits close on themselves, are symmetric,
//! match the linear mode at low energy, and the chart reproduces the path.

use eigenmpc::integrate::{Dopri5, Tolerances};
use eigenmpc::mechanics::{DoublePendulum, MechanicalSystem, Vector, state_derivative};
use eigenmpc::modes::{
    Chart, ContinuationOptions, Family, ModeError, eigenmode_family, linear_modes,
};
use nalgebra::SVector;

fn family(f: Family, energies: &[f64]) -> Result<Vec<eigenmpc::modes::Eigenmode<2>>, ModeError> {
    eigenmode_family::<_, 2, 4>(
        &DoublePendulum::default(),
        f.index(),
        energies,
        &ContinuationOptions::default(),
    )
}

#[test]
fn in_phase_14j_orbit_closes_and_is_symmetric() {
    let sys = DoublePendulum::default();
    let modes = family(Family::InPhase, &[14.0]).unwrap();
    let m = &modes[0];
    println!("{m:?}");
    assert!((sys.potential(&m.turning_point) - 14.0).abs() < 1e-9);
    assert!((sys.potential(&m.other_turning_point) - 14.0).abs() < 1e-8);
    // Symmetry of the double pendulum: q1 = -q0.
    let asym = (m.other_turning_point + m.turning_point).amax();
    assert!(asym < 1e-8, "asymmetry {asym:e}");
    assert!(
        m.closing_error < 1e-9,
        "closing error {:e}",
        m.closing_error
    );
    assert!(
        m.turning_speed < 1e-9,
        "turning speed {:e}",
        m.turning_speed
    );
    // The positive turning point lies on the eigenvector's side.
    let c = linear_modes(&sys).unwrap()[0].eigenvector;
    assert!(c.dot(&m.turning_point) > 0.5);
    // Independent re-integration: energy along the path stays at E and the
    // path ends at the other turning point.
    assert_eq!(m.path.len(), 200);
    assert_eq!(m.path[0], m.turning_point);
    assert!((m.path[199] - m.other_turning_point).amax() < 1e-14);
    let mut ode = Dopri5::new(
        0.0,
        SVector::<f64, 4>::new(m.turning_point[0], m.turning_point[1], 0.0, 0.0),
        Tolerances::default(),
    );
    let zero = Vector::<2>::zeros();
    let z = *ode
        .advance_to(|_, z| state_derivative(&sys, z, &zero), m.half_period * 0.5)
        .unwrap();
    let e = sys.energy(&Vector::<2>::new(z[0], z[1]), &Vector::<2>::new(z[2], z[3]));
    assert!((e - 14.0).abs() < 1e-9);
    // Quarter period of a symmetric brake orbit passes through the equilibrium line's centre.
    assert!(Vector::<2>::new(z[0], z[1]).amax() < 1e-8, "mid-point {z}");
}

#[test]
fn low_energy_orbits_approach_the_linear_mode() {
    let sys = DoublePendulum::default();
    let lin = linear_modes(&sys).unwrap();
    for f in [Family::InPhase, Family::AntiPhase] {
        let m = &family(f, &[0.01]).unwrap()[0];
        let c = lin[f.index()].eigenvector;
        let dir = m.turning_point.normalize();
        assert!((dir - c).norm() < 5e-3, "{f}: {dir} vs {c}");
        let period = std::f64::consts::PI / lin[f.index()].omega;
        assert!(
            ((m.half_period - period) / period).abs() < 2e-3,
            "{f}: {} vs {period}",
            m.half_period
        );
    }
}

#[test]
fn families_at_several_energies_all_verify_and_come_back_in_request_order() {
    let energies = [8.0, 2.0, 14.0, 0.25];
    let modes = family(Family::InPhase, &energies).unwrap();
    for (m, &e) in modes.iter().zip(&energies) {
        assert_eq!(m.energy, e);
        assert!(
            m.closing_error < 1e-9 && m.turning_speed < 1e-9,
            "{e}: {m:?}"
        );
    }
    // Amplitude and half period grow with energy (softening pendulum).
    assert!(modes[1].turning_point.norm() < modes[0].turning_point.norm());
    assert!(modes[1].half_period < modes[0].half_period);
    let anti = family(Family::AntiPhase, &[2.0, 12.0]).unwrap();
    assert!(anti[1].closing_error < 1e-9);
    assert!(anti[1].turning_point[0] > 0.0 && anti[1].turning_point[1] < 0.0);
}

#[test]
fn chart_reproduces_the_14j_path() {
    let sys = DoublePendulum::default();
    let m = &family(Family::InPhase, &[14.0]).unwrap()[0];
    let c = linear_modes(&sys).unwrap()[0].eigenvector;
    let chart = Chart::fit(&m.path, &c, &Vector::<2>::zeros(), 9).unwrap();
    assert_eq!(chart.degree, 9);
    assert!(chart.max_residual < 2e-3, "residual {}", chart.max_residual);
    // Check off the fitted samples too: mid-points of the path.
    for w in m.path.windows(2) {
        let mid = (w[0] + w[1]) * 0.5;
        let x = chart.eval(chart.coordinate(&mid)).x;
        assert!((x - mid).amax() < 3e-3);
    }
    // Turning points: X(s) lands on them.
    for q in [m.turning_point, m.other_turning_point] {
        assert!((chart.eval(chart.coordinate(&q)).x - q).amax() < 3e-3);
    }
}

#[test]
fn bad_requests_give_errors() {
    assert!(matches!(
        family(Family::InPhase, &[-1.0]),
        Err(ModeError::InvalidEnergy(_))
    ));
    assert!(matches!(
        family(Family::InPhase, &[f64::NAN]),
        Err(ModeError::InvalidEnergy(_))
    ));
    let r = eigenmode_family::<_, 2, 4>(
        &DoublePendulum::default(),
        2,
        &[1.0],
        &ContinuationOptions::default(),
    );
    assert!(matches!(r, Err(ModeError::NoSuchMode { index: 2, dof: 2 })));
    // Beyond the top of the potential (V <= 58.86 J) no brake orbit exists;
    // towards it the period grows without bound, and the continuation ends
    // at its work limit or where Newton fails, whichever comes first.
    match family(Family::InPhase, &[70.0]) {
        Err(ModeError::ContinuationFailed {
            reached, requested, ..
        }) => {
            assert_eq!(requested, 70.0);
            assert!(reached > 14.0 && reached < 70.0, "reached {reached}");
        }
        Err(ModeError::WorkLimit { reached, .. }) => {
            assert!(reached > 50.0 && reached < 58.86, "reached {reached}");
        }
        other => panic!("expected a continuation failure, got {other:?}"),
    }
}

/// The work limit stops a continuation with a message naming it, and the
/// work it bounds is what the default allows a normal family many times
/// over: the 14 J in-phase orbit of the paper's pendulum needs well under a
/// tenth of it, and a budget too small for the first orbit stops at once.
#[test]
fn the_work_limit_stops_the_continuation_and_says_so() {
    let sys = DoublePendulum::default();
    let opts = ContinuationOptions::default();
    assert!(opts.max_evaluations >= 1_000_000);
    let run = |max_evaluations| {
        eigenmode_family::<_, 2, 4>(
            &sys,
            Family::InPhase.index(),
            &[14.0],
            &ContinuationOptions {
                max_evaluations,
                ..opts
            },
        )
    };
    assert!(run(opts.max_evaluations / 10).is_ok());
    match run(2_000) {
        Err(ModeError::WorkLimit { limit, reached, .. }) => {
            assert_eq!(limit, 2_000);
            assert!(reached < 14.0);
        }
        other => panic!("expected the work limit, got {other:?}"),
    }
    let message = run(50_000).unwrap_err().to_string();
    assert!(
        message.contains("work limit (50000 integrator evaluations)"),
        "{message}"
    );
    // A very light first link (the FMU's declared minimum mass): the time
    // scales are far apart, and the default limit ends it, fast.
    let light = eigenmpc::mechanics::PlanarChain::<2>::new(
        eigenmpc::mechanics::PlanarChainParams::point_masses([1e-6, 1.0], [1.0, 1.0], 9.81),
    )
    .unwrap();
    let start = std::time::Instant::now();
    let outcome = eigenmode_family::<_, 2, 4>(&light, 0, &[14.0], &opts);
    println!("light first link: {outcome:?} in {:?}", start.elapsed());
    assert!(
        matches!(outcome, Err(ModeError::WorkLimit { .. })),
        "{outcome:?}"
    );
}
