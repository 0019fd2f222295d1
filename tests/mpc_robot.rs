//! EigenMPC on rigid-link robots with friction, and the chart family over
//! energy: a tuned E_ref is followed along the eigenmanifold, friction is
//! compensated (the torque is what friction takes along the final orbit).

use eigenmpc::math;
use eigenmpc::mechanics::{DoublePendulum, MechanicalSystem, Vector};
use eigenmpc::model_file::RobotFile;
use eigenmpc::modes::{Chart, ChartFamily, ContinuationOptions, FamilyOptions, eigenmode_family};
use eigenmpc::mpc::Guide;
use eigenmpc::mpc::closed_loop::{
    energy_tail, mode_and_chart, rms_friction_torque, run_tuned, summarise,
};
use eigenmpc::mpc::cost::residuals;
use eigenmpc::mpc::{
    Controller, MpcConfig, Reference, Variant, prediction_coulomb_sharpness, prediction_substeps,
};
use nalgebra::{DVector, SVector};
use std::path::Path;

fn robot(name: &str) -> eigenmpc::mechanics::PlanarChain<2> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("robots")
        .join(name);
    RobotFile::load(path).unwrap().chain::<2>().unwrap()
}

/// The interpolated chart at energies between the grid points fits the
/// true orbit there as well as a chart fitted to that orbit directly.
#[test]
fn family_charts_between_grid_energies_fit_the_true_orbits() {
    let sys = DoublePendulum::default();
    let family = ChartFamily::compute::<_, 4>(&sys, 0, &FamilyOptions::up_to(20.0)).unwrap();
    let (lo, hi) = family.energy_range();
    assert!(
        (lo - 0.2).abs() < 1e-9 && (hi - 20.0).abs() < 1e-9,
        "{lo} {hi}"
    );
    assert!(family.ended_early().is_none());
    for e in [1.3, 3.3, 8.0, 13.7, 14.0, 19.0] {
        let mode = eigenmode_family::<_, 2, 4>(&sys, 0, &[e], &ContinuationOptions::default())
            .unwrap()
            .remove(0);
        let chart = family.chart(e);
        let miss = mode
            .path
            .iter()
            .map(|q| (chart.eval(chart.coordinate(q)).x - q).amax())
            .fold(0.0, f64::max);
        let direct = Chart::fit(&mode.path, &family.eigenvector(), &sys.equilibrium(), 9)
            .unwrap()
            .max_residual;
        assert!(
            miss <= 1.1 * direct + 5e-6,
            "{e} J: interpolated chart misses by {miss:e}, a direct fit by {direct:e}"
        );
    }
    // Outside the range the chart of the nearest end is used.
    assert_eq!(family.chart(50.0), family.chart(20.0));
    assert_eq!(family.chart(0.01), family.chart(lo));
}

#[test]
fn a_family_ends_where_its_chart_can_no_longer_follow_the_orbit() {
    let sys = DoublePendulum::default();
    let opts = FamilyOptions {
        max_chart_residual: 1e-3,
        ..FamilyOptions::up_to(40.0)
    };
    let family = ChartFamily::compute::<_, 4>(&sys, 0, &opts).unwrap();
    let (_, hi) = family.energy_range();
    // The degree-9 chart misses the 14 J orbit by 8.2e-4 and the 16 J one by 1.5e-3.
    assert!((12.0..16.0).contains(&hi), "family ends at {hi} J");
    assert!(family.ended_early().unwrap().contains("misses the orbit"));
    assert!(family.residuals().iter().all(|&r| r <= 1e-3));
}

/// `r_F = tau - tau_f(qd)` and its Jacobian, against finite differences.
#[test]
fn friction_compensating_residual_jacobians_match_finite_differences() {
    let sys = robot("lab-double-pendulum-A0.yml");
    let (_, chart) = mode_and_chart::<_, 2, 4>(&sys, 0, 2.0, 9).unwrap();
    let references = [
        (
            Reference::with_chart(Variant::Curved, chart),
            Variant::Curved,
        ),
        (
            Reference::new(
                Variant::Straight,
                Guide::Line(Vector::<2>::new(0.9, 0.43).normalize()),
            )
            .unwrap(),
            Variant::Straight,
        ),
    ];
    let tau = Vector::<2>::new(0.2, -0.1);
    for (reference, variant) in references {
        let p = MpcConfig::paper(variant).cost;
        let stacked = |z: &SVector<f64, 4>| {
            let r = residuals::<_, 2, 4>(&sys, &reference, &p, z, &tau);
            DVector::from_iterator(2, r.torque.iter().copied())
        };
        for z in [
            SVector::<f64, 4>::new(0.3, -0.2, 0.5, 1.1),
            SVector::<f64, 4>::new(-0.9, 1.2, 0.004, -0.007),
        ] {
            let r = residuals::<_, 2, 4>(&sys, &reference, &p, &z, &tau);
            let f = sys.friction(&Vector::<2>::new(z[2], z[3]));
            let scale = match variant {
                Variant::Curved => 1.0,
                Variant::Straight | Variant::Hybrid => {
                    math::tanh(
                        p.alpha
                            * sys.energy(
                                &z.fixed_rows::<2>(0).into_owned(),
                                &z.fixed_rows::<2>(2).into_owned(),
                            ),
                    ) + p.beta
                }
            };
            assert!((r.torque - (tau - f) * scale).amax() < 1e-14);
            for j in 0..4 {
                let h = 1e-7;
                let (mut zp, mut zm) = (z, z);
                zp[j] += h;
                zm[j] -= h;
                let fd = (stacked(&zp) - stacked(&zm)) / (2.0 * h);
                for i in 0..2 {
                    let exact = r.torque_z[(i, j)];
                    assert!(
                        (fd[i] - exact).abs() < 1e-5 * (1.0 + exact.abs()),
                        "{variant} d r_F{i}/d z{j}: fd {} exact {exact}",
                        fd[i]
                    );
                }
            }
        }
    }
}

/// The paper's pendulum with a mode family: E_ref tuned 14 -> 8 J is
/// followed onto the 8 J eigenmode with near-zero torque (with the fixed
/// 14 J chart it settled 4 % high with 0.45 N m RMS).
#[test]
fn a_tuned_e_ref_is_followed_along_the_mode_family() {
    let sys = DoublePendulum::default();
    let family = ChartFamily::compute::<_, 4>(&sys, 0, &FamilyOptions::up_to(20.0)).unwrap();
    let mut ctrl =
        Controller::<_, 2, 4>::with_family(sys, MpcConfig::paper(Variant::Curved), family).unwrap();
    let (mode14, _) = mode_and_chart::<_, 2, 4>(&sys, 0, 14.0, 9).unwrap();
    let (mode8, _) = mode_and_chart::<_, 2, 4>(&sys, 0, 8.0, 9).unwrap();
    let q = mode14.turning_point;
    let z0 = SVector::<f64, 4>::new(q[0], q[1], 0.0, 0.0);
    let trace = run_tuned(&mut ctrl, &sys, &z0, 35.0, |t, c| {
        if (t - 2.0).abs() < 1e-9 {
            c.set_e_ref(8.0).unwrap();
        }
    })
    .unwrap();
    assert_eq!(ctrl.chart_energy(), Some(8.0));
    let (mean, _) = energy_tail(&trace, 8.0, 5.0);
    let s = summarise(&trace, 8.0, Some(&mode8.path), 5.0);
    eprintln!(
        "14 -> 8 J: mean {mean}, RMS tau {}, distance {:?}",
        s.rms_torque, s.rms_distance
    );
    assert!((mean - 8.0).abs() < 0.02 * 8.0, "energy {mean}");
    assert!(s.rms_torque.amax() < 0.02, "RMS torque {}", s.rms_torque);
    assert!(s.rms_distance.unwrap() < 0.01);
}

/// The identified laboratory pendulum A0 (|tau| <= 0.5 N m): the energy
/// settles within 2 % of E_ref and the torque is what friction takes.
#[test]
fn friction_is_compensated_on_the_identified_robot() {
    let plant = robot("lab-double-pendulum-A0.yml");
    let mut config = MpcConfig::paper(Variant::Curved);
    config.tau_max = 0.5;
    config.cost.e_ref = 2.0;
    config.cost.weights.energy = 250.0;
    config.substeps = prediction_substeps(&plant, config.dt);
    assert!(
        config.substeps > 1,
        "the robot's Coulomb law needs substeps"
    );
    let h = config.dt / config.substeps as f64;
    assert_eq!(prediction_coulomb_sharpness(&plant, h), 100.0);
    let (mode, chart) = mode_and_chart::<_, 2, 4>(&plant, 0, 2.0, 9).unwrap();
    let mut ctrl =
        Controller::<_, 2, 4>::new(plant, config, Reference::with_chart(Variant::Curved, chart))
            .unwrap();
    let z0 = SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0);
    let trace = run_tuned(&mut ctrl, &plant, &z0, 25.0, |_, _| {}).unwrap();
    let s = summarise(&trace, 2.0, Some(&mode.path), 5.0);
    let (mean, _) = energy_tail(&trace, 2.0, 5.0);
    let friction = rms_friction_torque(&trace, &plant, 5.0);
    eprintln!(
        "A0 2 J: 5 % at {:?} s, mean {mean}, RMS tau {} vs friction {}, distance {:?}",
        s.time_to_5_percent, s.rms_torque, friction, s.rms_distance
    );
    assert!(s.time_to_5_percent.is_some());
    assert!((mean - 2.0).abs() < 0.02 * 2.0, "energy {mean}");
    assert!(s.rms_torque.norm() <= 1.2 * friction.norm());
    assert!(
        friction.norm() > 0.1,
        "the orbit is held against real friction"
    );
    assert!(s.rms_distance.unwrap() < 0.02);
}

/// A 3-link point-mass chain: started at a turning point of its 20 J
/// in-phase eigenmode, the curved controller keeps it there torque-free
/// (from rest it gets there in 37 s: `examples/three_link.rs`).
#[test]
fn three_link_chain_stays_on_its_eigenmode_torque_free() {
    use eigenmpc::mechanics::PlanarChain;
    let sys = PlanarChain::<3>::default();
    let family = ChartFamily::compute::<_, 6>(&sys, 0, &FamilyOptions::up_to(25.0)).unwrap();
    let mut config = MpcConfig::paper(Variant::Curved);
    config.cost.e_ref = 20.0;
    config.horizon = 60;
    let mut ctrl = Controller::<_, 3, 6>::with_family(sys, config, family).unwrap();
    let (mode, _) = mode_and_chart::<_, 3, 6>(&sys, 0, 20.0, 9).unwrap();
    let q = mode.turning_point;
    let z0 = SVector::<f64, 6>::new(q[0], q[1], q[2], 0.0, 0.0, 0.0);
    let trace = run_tuned(&mut ctrl, &sys, &z0, 8.0, |_, _| {}).unwrap();
    let s = summarise(&trace, 20.0, Some(&mode.path), 5.0);
    let (mean, _) = energy_tail(&trace, 20.0, 5.0);
    eprintln!(
        "3 links on the 20 J mode: mean {mean}, RMS tau {}, distance {:?}",
        s.rms_torque, s.rms_distance
    );
    assert!((mean - 20.0).abs() < 0.01 * 20.0, "energy {mean}");
    assert!(s.rms_torque.amax() < 0.05, "RMS torque {}", s.rms_torque);
    assert!(s.rms_distance.unwrap() < 0.01);
    assert_eq!(s.failures, 0);
}
