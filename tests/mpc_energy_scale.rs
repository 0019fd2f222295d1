//! The energy scale `E_s` (issue 19, item 4): the energy residual is the
//! paper's exactly from `E_s` (14 J) up, `sqrt(E_s / E_ref)` times it below,
//! and a low `E_ref` is reached from rest about as fast as 14 J.

use eigenmpc::mechanics::{DoublePendulum, MechanicalSystem, Vector};
use eigenmpc::modes::linear_modes;
use eigenmpc::mpc::Guide;
use eigenmpc::mpc::closed_loop::{Summary, mode_and_chart, run, summarise};
use eigenmpc::mpc::cost::{CostParams, Reference, residuals};
use eigenmpc::mpc::{Controller, MpcConfig, MpcError, PAPER_ENERGY_SCALE, Variant};
use nalgebra::SVector;

type Z = SVector<f64, 4>;

/// The reference of `variant` for the in-phase mode at `e_ref`.
fn reference(variant: Variant, e_ref: f64) -> Reference<2> {
    let sys = DoublePendulum::default();
    match variant {
        Variant::Straight => Reference::new(
            Variant::Straight,
            Guide::Line(linear_modes(&sys).unwrap()[0].eigenvector),
        )
        .unwrap(),
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

/// From `E_s` up (the paper's set-up: E_ref = E_s = 14 J; and 20 J) the
/// scaled residual is the paper's to the last bit, so are its Jacobians:
/// the paper's runs cannot change.
#[test]
fn scaled_residual_is_exactly_the_papers_from_e_s_up() {
    let sys = DoublePendulum::default();
    let tau = Vector::<2>::new(0.4, -0.7);
    for (v, e_ref) in [
        (Variant::Straight, 14.0),
        (Variant::Curved, 14.0),
        (Variant::Hybrid, 14.0),
        (Variant::Curved, 20.0),
    ] {
        let reference = reference(v, e_ref);
        let scaled = CostParams {
            e_ref,
            ..MpcConfig::paper(v).cost
        };
        assert_eq!(scaled.energy_residual_factor(), 1.0);
        let absolute = CostParams {
            energy_scale: 0.0,
            ..scaled
        };
        for z in &STATES {
            let a = residuals::<_, 2, 4>(&sys, &reference, &absolute, z, &tau);
            let r = residuals::<_, 2, 4>(&sys, &reference, &scaled, z, &tau);
            let (q, qd) = (z.fixed_rows::<2>(0).into(), z.fixed_rows::<2>(2).into());
            assert_eq!(
                a.energy,
                e_ref - sys.energy_with_gradient(&q, &qd).0,
                "{v}: the paper's r_E"
            );
            assert_eq!(r.energy, a.energy, "{v} {z:?}");
            assert_eq!(r.energy_z, a.energy_z, "{v} {z:?}");
            assert_eq!(r.position, a.position);
            assert_eq!(r.velocity_z, a.velocity_z);
            assert_eq!(r.torque_z, a.torque_z);
        }
    }
}

/// Below `E_s` the scaled residual is the paper's times `sqrt(E_s / E_ref)`,
/// so that the value of a joule, `d(w_E r_E^2)/dE = -2 w_E E_s (1 - E/E_ref)`,
/// is the one at `E_ref = E_s` (the residuals' Jacobians against finite
/// differences, for every form, are in tests/mpc_controller.rs).
#[test]
fn scaled_residual_below_e_s_values_a_joule_as_at_e_s() {
    let sys = DoublePendulum::default();
    let tau = Vector::<2>::new(0.4, -0.7);
    for (e_ref, e_s, k) in [
        (3.0, 14.0, (14.0f64 / 3.0).sqrt()),
        (1.0, 14.0, 14.0f64.sqrt()),
        (3.0, 2.0, 1.0),
        (3.0, 0.0, 1.0),
    ] {
        let reference = reference(Variant::Curved, e_ref);
        let scaled = CostParams {
            e_ref,
            energy_scale: e_s,
            ..MpcConfig::paper(Variant::Curved).cost
        };
        let absolute = CostParams {
            energy_scale: 0.0,
            ..scaled
        };
        assert_eq!(scaled.energy_residual_factor(), k);
        for z in &STATES {
            let a = residuals::<_, 2, 4>(&sys, &reference, &absolute, z, &tau);
            let r = residuals::<_, 2, 4>(&sys, &reference, &scaled, z, &tau);
            // The value of a joule at this state is that at E_ref = E_s at
            // the same fraction of the climb.
            let (q, qd) = (z.fixed_rows::<2>(0).into(), z.fixed_rows::<2>(2).into());
            let progress = sys.energy(&q, &qd) / e_ref;
            let per_joule = -2.0 * r.energy * k;
            let at_e_s = 2.0 * e_s.max(e_ref) * (1.0 - progress);
            assert!((per_joule + at_e_s).abs() < 1e-12 * (1.0 + at_e_s.abs()));
            assert!((r.energy - k * a.energy).abs() <= 1e-14 * (1.0 + r.energy.abs()));
            assert!((r.energy_z - a.energy_z * k).amax() <= 1e-14 * (1.0 + r.energy_z.amax()));
            // Only the energy term is scaled.
            assert_eq!(r.position_z, a.position_z);
            assert_eq!(r.velocity, a.velocity);
            assert_eq!(r.torque, a.torque);
        }
    }
}

/// The scaled residual divides by `E_ref`: `E_ref = 0` needs the paper's
/// (`E_s = 0`), and a refused value leaves the tuning as it was.
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
    let mut ctrl =
        Controller::<_, 2, 4>::new(sys, config, Reference::with_chart(Variant::Curved, chart))
            .unwrap();
    let trace = run(&mut ctrl, &sys, &Z::new(0.05, 0.05, 0.0, 0.0), duration).unwrap();
    let s = summarise(&trace, e_ref, Some(&mode.path), 5.0);
    eprintln!("curved {e_ref} J, E_s = {energy_scale} J: {s:?}");
    s
}

/// Issue 19, item 4: with the paper's residual 3 J is still out of the 5 %
/// band after 40 s (measured: it enters it for good at 59.7 s); with the
/// default energy scale it enters it within 30 s (measured: 13.65 s) and
/// stays, settled on the mode with small torque.
#[test]
fn curved_3_j_from_rest_enters_the_band_within_30_s() {
    let absolute = from_rest(3.0, 0.0, 40.0);
    assert!(absolute.time_to_5_percent.is_none(), "{absolute:?}");
    let scaled = from_rest(3.0, PAPER_ENERGY_SCALE, 40.0);
    assert_eq!(scaled.failures, 0);
    assert!(
        scaled.time_to_5_percent.is_some_and(|t| t < 30.0),
        "{scaled:?}"
    );
    assert!(scaled.final_energy_error.abs() < 0.01 * 3.0, "{scaled:?}");
    assert!(scaled.rms_torque.iter().all(|&t| t < 0.01), "{scaled:?}");
    assert!(scaled.rms_distance.unwrap() < 0.01, "{scaled:?}");
}
