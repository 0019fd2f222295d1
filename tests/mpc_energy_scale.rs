//! The energy residual relative to `E_ref` (issue 19, item 4): exactly the
//! paper's residual at its 14 J set-up, `E_s / E_ref` times it elsewhere,
//! and a low `E_ref` reached from rest about as fast as 14 J.

use eigenmpc::mechanics::{DoublePendulum, MechanicalSystem, Vector};
use eigenmpc::modes::linear_modes;
use eigenmpc::mpc::closed_loop::{Summary, mode_and_chart, run, summarise};
use eigenmpc::mpc::cost::{CostParams, Reference, residuals};
use eigenmpc::mpc::{Controller, MpcConfig, MpcError, PAPER_ENERGY_SCALE, Variant};
use nalgebra::SVector;

type Z = SVector<f64, 4>;

/// The reference of `variant` for the in-phase mode at `e_ref`.
fn reference(variant: Variant, e_ref: f64) -> Reference<2> {
    let sys = DoublePendulum::default();
    match variant {
        Variant::Straight => Reference::Straight {
            eigenvector: linear_modes(&sys).unwrap()[0].eigenvector,
        },
        v => Reference::with_chart(v, mode_and_chart::<_, 2, 4>(&sys, 0, e_ref, 9).unwrap().1),
    }
}

const STATES: [Z; 3] = [
    Z::new(0.3, -0.2, 0.5, 1.1),
    Z::new(-0.9, 1.2, -2.0, 0.7),
    Z::new(0.05, 0.05, 0.0, 0.0),
];

#[test]
fn default_scale_is_the_papers_tuning_energy() {
    assert_eq!(PAPER_ENERGY_SCALE, 14.0);
    for v in [Variant::Straight, Variant::Curved, Variant::Hybrid] {
        let c = MpcConfig::paper(v).cost;
        assert_eq!(c.energy_scale, PAPER_ENERGY_SCALE);
        assert_eq!(c.e_ref, PAPER_ENERGY_SCALE);
        assert_eq!(c.energy_residual_factor(), 1.0);
    }
}

/// At the paper's set-up (E_ref = E_s = 14 J) the relative residual is the
/// paper's absolute one to the last bit, so are its Jacobians: the paper's
/// runs cannot change.
#[test]
fn relative_residual_is_exactly_the_papers_at_14_j() {
    let sys = DoublePendulum::default();
    let tau = Vector::<2>::new(0.4, -0.7);
    for v in [Variant::Straight, Variant::Curved, Variant::Hybrid] {
        let reference = reference(v, 14.0);
        let relative = MpcConfig::paper(v).cost;
        let absolute = CostParams {
            energy_scale: 0.0,
            ..relative
        };
        for z in &STATES {
            let a = residuals::<_, 2, 4>(&sys, &reference, &absolute, z, &tau);
            let r = residuals::<_, 2, 4>(&sys, &reference, &relative, z, &tau);
            let (q, qd) = (z.fixed_rows::<2>(0).into(), z.fixed_rows::<2>(2).into());
            assert_eq!(a.energy, 14.0 - sys.energy(&q, &qd), "{v}: the paper's r_E");
            assert_eq!(r.energy, a.energy, "{v} {z:?}");
            assert_eq!(r.energy_z, a.energy_z, "{v} {z:?}");
            assert_eq!(r.position, a.position);
            assert_eq!(r.velocity_z, a.velocity_z);
            assert_eq!(r.torque_z, a.torque_z);
        }
    }
}

/// Elsewhere the relative residual is the absolute one times `E_s / E_ref`
/// (the residuals' Jacobians against finite differences, for every form,
/// are in tests/mpc_controller.rs).
#[test]
fn relative_residual_is_the_error_as_a_fraction_of_e_ref() {
    let sys = DoublePendulum::default();
    let tau = Vector::<2>::new(0.4, -0.7);
    for (e_ref, e_s) in [(3.0, 14.0), (1.0, 14.0), (20.0, 14.0), (3.0, 2.0)] {
        let reference = reference(Variant::Curved, e_ref);
        let relative = CostParams {
            e_ref,
            energy_scale: e_s,
            ..MpcConfig::paper(Variant::Curved).cost
        };
        let absolute = CostParams {
            energy_scale: 0.0,
            ..relative
        };
        let k = e_s / e_ref;
        assert_eq!(relative.energy_residual_factor(), k);
        for z in &STATES {
            let a = residuals::<_, 2, 4>(&sys, &reference, &absolute, z, &tau);
            let r = residuals::<_, 2, 4>(&sys, &reference, &relative, z, &tau);
            assert!((r.energy - k * a.energy).abs() <= 1e-14 * (1.0 + r.energy.abs()));
            assert!((r.energy_z - a.energy_z * k).amax() <= 1e-14 * (1.0 + r.energy_z.amax()));
            // Only the energy term is scaled.
            assert_eq!(r.position_z, a.position_z);
            assert_eq!(r.velocity, a.velocity);
            assert_eq!(r.torque, a.torque);
        }
    }
}

/// The relative residual divides by `E_ref`: `E_ref = 0` needs the absolute
/// residual, and a refused value leaves the tuning as it was.
#[test]
fn zero_e_ref_needs_the_absolute_residual() {
    let sys = DoublePendulum::default();
    let config = MpcConfig::paper(Variant::Straight);
    let mut ctrl =
        Controller::<_, 2, 4>::new(sys, config, reference(Variant::Straight, 14.0)).unwrap();
    assert!(matches!(
        ctrl.set_e_ref(0.0),
        Err(MpcError::InvalidParameter { name: "e_ref", .. })
    ));
    assert_eq!(ctrl.config().cost.e_ref, 14.0);
    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        let cost = CostParams {
            energy_scale: bad,
            ..config.cost
        };
        assert!(ctrl.set_cost(cost).is_err(), "energy_scale {bad}");
    }
    ctrl.set_cost(CostParams {
        e_ref: 0.0,
        energy_scale: 0.0,
        ..config.cost
    })
    .unwrap();
    let out = ctrl.step(&Z::new(0.3, 0.3, 0.0, 0.0));
    assert!(out.status.is_ok(), "{:?}", out.status);
}

/// Curved closed loop from the paper's start near rest, `|tau| <= 1 N m`.
fn from_rest(e_ref: f64, energy_scale: f64, duration: f64) -> Summary<2> {
    let sys = DoublePendulum::default();
    let (mode, chart) = mode_and_chart::<_, 2, 4>(&sys, 0, e_ref, 9).unwrap();
    let mut config = MpcConfig::paper(Variant::Curved);
    config.cost.e_ref = e_ref;
    config.cost.energy_scale = energy_scale;
    let mut ctrl = Controller::<_, 2, 4>::new(sys, config, Reference::Curved(chart)).unwrap();
    let trace = run(&mut ctrl, &sys, &Z::new(0.05, 0.05, 0.0, 0.0), duration).unwrap();
    let s = summarise(&trace, e_ref, Some(&mode.path), 5.0);
    eprintln!("curved {e_ref} J, E_s = {energy_scale} J: {s:?}");
    s
}

/// Issue 19, item 4: with the paper's absolute residual 3 J is still out of
/// the 5 % band after 40 s (measured: it enters it for good at ~90 s);
/// relative to `E_ref` it enters it within 30 s and stays, settled on the
/// mode with small torque.
#[test]
fn curved_3_j_from_rest_enters_the_band_within_30_s() {
    let absolute = from_rest(3.0, 0.0, 40.0);
    assert!(absolute.time_to_5_percent.is_none(), "{absolute:?}");
    let relative = from_rest(3.0, PAPER_ENERGY_SCALE, 40.0);
    assert_eq!(relative.failures, 0);
    assert!(
        relative.time_to_5_percent.is_some_and(|t| t < 30.0),
        "{relative:?}"
    );
    assert!(relative.final_energy_error.abs() < 0.05 * 3.0, "{relative:?}");
    assert!(relative.rms_torque.iter().all(|&t| t < 0.05), "{relative:?}");
    assert!(relative.rms_distance.unwrap() < 0.02, "{relative:?}");
}
