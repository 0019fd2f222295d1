//! Issue 5 acceptance, correctness part (a): RTI QPs recorded from closed
//! loops of the paper scenarios (straight and curved, near-zero and large
//! initial states, and the same with |tau| <= 0.2 N m so that many torque
//! bounds are active), each solved by the controller's Riccati backend and
//! checked against clarabel with accurate settings: first control within
//! 1e-6, objective within 1e-8 relative, KKT residuals within 1e-8.

use eigenmpc::mechanics::DoublePendulum;
use eigenmpc::mpc::closed_loop::{reference_for, run_with};
use eigenmpc::mpc::{Controller, MpcConfig, QpBackend, Variant};
use eigenmpc::qp::clarabel::{ClarabelQpSolver, accurate_settings};
use eigenmpc::qp::{QpSolution, QpSolver, QpStatus, kkt_residuals};
use nalgebra::SVector;
use std::time::Instant;

const U0_TOL: f64 = 1e-6;
const OBJ_REL_TOL: f64 = 1e-8;
const KKT_TOL: f64 = 1e-8;

/// Worst figures over a scenario's QPs.
#[derive(Debug, Default)]
struct Worst {
    qps: usize,
    du0: f64,
    objective_rel: f64,
    kkt: f64,
    max_iterations: usize,
    active_bounds: usize,
    /// QPs solved by the inactive-set start (one Riccati step).
    one_step: usize,
}

/// Runs `samples` RTI samples of the closed loop with the Riccati backend
/// and checks every `stride`-th QP (with its controller solution) against
/// clarabel.
fn check_scenario(
    variant: Variant,
    q0: [f64; 2],
    tau_max: f64,
    samples: usize,
    stride: usize,
) -> Worst {
    let sys = DoublePendulum::default();
    let reference = reference_for::<_, 2, 4>(&sys, variant, 0, 14.0).unwrap();
    let mut config = MpcConfig::paper(variant);
    config.tau_max = tau_max;
    config.qp = QpBackend::Riccati;
    let mut ctrl = Controller::<_, 2, 4>::new(sys, config, reference).unwrap();
    assert_eq!(ctrl.qp_solver_name(), "riccati");
    let n = config.horizon;
    let mut clarabel = ClarabelQpSolver::new(4, 2, n, accurate_settings());
    let mut reference_sol = QpSolution::new(4, 2, n);

    let z0 = SVector::<f64, 4>::new(q0[0], q0[1], 0.0, 0.0);
    let mut worst = Worst::default();
    let what = format!("{variant} q0 {q0:?} tau_max {tau_max}");
    let duration = (samples - 1) as f64 * config.dt;
    run_with(&mut ctrl, &sys, &z0, duration, |i, ctrl, out| {
        assert!(out.status.is_ok(), "{what} sample {i}: {}", out.status);
        // The first sample is the converged SQP; its last QP counts too.
        if i % stride == 0 {
            let (qp, sol) = ctrl.last_qp();
            assert_eq!(sol.status, QpStatus::Solved, "{what} sample {i}");
            let status = clarabel.solve(&qp, &mut reference_sol);
            assert_eq!(status, QpStatus::Solved, "{what} sample {i}: clarabel");
            let du0 = (&sol.u[0] - &reference_sol.u[0]).amax();
            let objective_rel = (sol.objective - reference_sol.objective).abs()
                / reference_sol.objective.abs().max(1.0);
            let kkt = kkt_residuals(&qp, sol);
            assert!(
                du0 <= U0_TOL,
                "{what} sample {i}: first control differs by {du0:e}\nriccati {:?} obj {} it {} kkt {:?}\nclarabel {:?} obj {} kkt {:?}",
                sol.u[0].as_slice(),
                sol.objective,
                sol.iterations,
                kkt,
                reference_sol.u[0].as_slice(),
                reference_sol.objective,
                kkt_residuals(&qp, &reference_sol)
            );
            assert!(
                objective_rel <= OBJ_REL_TOL,
                "{what} sample {i}: objective {} vs {} (rel {objective_rel:e})",
                sol.objective,
                reference_sol.objective
            );
            assert!(
                kkt.within(KKT_TOL, 0.0),
                "{what} sample {i}: KKT residuals {kkt:?}"
            );
            worst.qps += 1;
            worst.du0 = worst.du0.max(du0);
            worst.objective_rel = worst.objective_rel.max(objective_rel);
            worst.kkt = worst.kkt.max(kkt.max());
            worst.max_iterations = worst.max_iterations.max(sol.iterations);
            worst.one_step += usize::from(sol.iterations == 1);
            // Bounds active in the reference solution (step bounds of the
            // torque, 1e-7 from the boundary).
            for k in 0..n {
                for j in 0..2 {
                    let u = reference_sol.u[k][j];
                    if u - qp.u_lower[k][j] < 1e-7 || qp.u_upper[k][j] - u < 1e-7 {
                        worst.active_bounds += 1;
                    }
                }
            }
        }
    })
    .unwrap();
    eprintln!("{what}: {worst:?}");
    worst
}

#[test]
fn recorded_rti_qps_of_the_paper_scenarios_match_clarabel() {
    let start = Instant::now();
    let mut total = 0;
    let mut active = [0usize; 2];
    for (b, tau_max) in [1.0, 0.2].into_iter().enumerate() {
        for variant in [Variant::Curved, Variant::Straight] {
            for q0 in [[0.05, 0.05], [-1.1, 1.1]] {
                let w = check_scenario(variant, q0, tau_max, 130, 1);
                total += w.qps;
                active[b] += w.active_bounds;
            }
        }
    }
    eprintln!(
        "{total} QPs checked in {:.1} s; active torque bounds: {} (|tau| <= 1), {} (|tau| <= 0.2)",
        start.elapsed().as_secs_f64(),
        active[0],
        active[1]
    );
    // On the 14 J orbit (from the mode's turning point at rest) the torques
    // stay far from their bounds: the inactive-set start solves the QPs,
    // and they match clarabel as well.
    let sys = DoublePendulum::default();
    let (mode, _) =
        eigenmpc::mpc::closed_loop::mode_and_chart::<_, 2, 4>(&sys, 0, 14.0, 9).unwrap();
    let on_orbit = [mode.turning_point[0], mode.turning_point[1]];
    for variant in [Variant::Curved, Variant::Straight] {
        let w = check_scenario(variant, on_orbit, 1.0, 130, 1);
        total += w.qps;
        assert!(w.one_step >= 120, "{variant}: {w:?}");
    }
    assert!(total >= 1000, "{total}");
    // The tau_max = 0.2 set is there to exercise active bounds.
    assert!(active[1] > 10 * total, "{active:?}");
}
