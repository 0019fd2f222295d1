//! The Riccati interior-point QP solver against independent references
//! (dense KKT solves and clarabel on the same QP assembled as one sparse
//! problem), checked with the solver-independent KKT residuals.

mod common;

use common::qp_reference::{Reference, clarabel_solve, dense_kkt_solve};
use eigenmpc::qp::record::{QpRecordReader, QpRecordWriter};
use eigenmpc::qp::synthetic::{PendulumQpOptions, SplitMix64, pendulum_rti_qp, random_ocp_qp};
use eigenmpc::qp::{
    OcpQp, QpSolution, QpSolver, QpStatus, RiccatiSettings, RiccatiSolver, StageQp, kkt_residuals,
};
use std::path::{Path, PathBuf};

/// Acceptance tolerances of issue 5.
const U0_TOL: f64 = 1e-6;
const OBJ_REL_TOL: f64 = 1e-8;
const KKT_TOL: f64 = 1e-8;
/// Relative stationarity accepted when the costate is so large (|pi| ~ 1e7
/// on unstable linearisations) that round-off of the sums alone exceeds
/// `KKT_TOL`: 1e-12 is still ~4500 ulps.
const KKT_REL_TOL: f64 = 1e-12;

fn solve(qp: &OcpQp) -> (QpSolution, RiccatiSolver) {
    let mut solver = RiccatiSolver::new(qp.nx, qp.nu, qp.horizon, RiccatiSettings::default());
    let mut sol = QpSolution::new(qp.nx, qp.nu, qp.horizon);
    let status = solver.solve(qp, &mut sol);
    assert_eq!(status, sol.status);
    (sol, solver)
}

/// Asserts the issue-5 acceptance criteria of `sol` against `reference`.
fn assert_matches(what: &str, qp: &OcpQp, sol: &QpSolution, reference: &Reference) {
    assert_eq!(sol.status, QpStatus::Solved, "{what}: status");
    assert!(reference.solved, "{what}: reference failed");
    let du0 = (&sol.u[0] - &reference.u[0]).amax();
    assert!(du0 <= U0_TOL, "{what}: first control differs by {du0:e}");
    let rel = (sol.objective - reference.objective).abs() / reference.objective.abs().max(1.0);
    assert!(
        rel <= OBJ_REL_TOL,
        "{what}: objective {} vs {} (rel {rel:e})",
        sol.objective,
        reference.objective
    );
    let kkt = kkt_residuals(qp, sol);
    assert!(
        kkt.within(KKT_TOL, KKT_REL_TOL),
        "{what}: KKT residuals {kkt:?}"
    );
    let obj_rel = (kkt.objective - sol.objective).abs() / sol.objective.abs().max(1.0);
    assert!(
        obj_rel <= 1e-9,
        "{what}: reported objective {obj_rel:e} off"
    );
}

fn with_control_box(mut qp: OcpQp, bound: f64) -> OcpQp {
    for k in 0..qp.horizon {
        qp.u_lower[k].fill(-bound);
        qp.u_upper[k].fill(bound);
    }
    qp
}

#[test]
fn unconstrained_matches_dense_kkt() {
    let mut rng = SplitMix64::new(1);
    for &n in &[1, 5, 80] {
        for rep in 0..3 {
            let qp = random_ocp_qp(&mut rng, 4, 2, n);
            let (sol, solver) = solve(&qp);
            let (reference, pi) = dense_kkt_solve(&qp);
            let what = format!("N = {n}, rep {rep}");
            assert_matches(&what, &qp, &sol, &reference);
            // No inequalities: one Newton step is exact.
            assert_eq!(solver.info().iterations, 1, "{what}");
            for (k, pi_k) in pi.iter().enumerate() {
                let dx = (&sol.x[k + 1] - &reference.x[k + 1]).amax();
                let dpi = (&sol.pi[k] - pi_k).amax();
                assert!(
                    dx <= 1e-9 && dpi <= 1e-8,
                    "{what}: stage {k}: {dx:e} {dpi:e}"
                );
            }
        }
    }
}

#[test]
fn other_dimensions_match_dense_kkt() {
    // Runtime-dimension kernels (nx = 3, nu = 1; nx = 5, nu = 4) and the
    // specialised single- and triple-joint sizes.
    let mut rng = SplitMix64::new(2);
    for &(nx, nu) in &[(3, 1), (5, 4), (2, 1), (6, 3)] {
        let qp = random_ocp_qp(&mut rng, nx, nu, 12);
        let (sol, _) = solve(&qp);
        let (reference, _) = dense_kkt_solve(&qp);
        assert_matches(&format!("nx = {nx}, nu = {nu}"), &qp, &sol, &reference);
        let qp = with_control_box(qp, 0.3);
        let (sol, _) = solve(&qp);
        assert_matches(
            &format!("boxed nx = {nx}, nu = {nu}"),
            &qp,
            &sol,
            &clarabel_solve(&qp),
        );
    }
}

#[test]
fn bounded_random_qps_match_clarabel() {
    let mut rng = SplitMix64::new(3);
    for &n in &[1, 5, 80] {
        for &bound in &[10.0, 0.5, 0.2] {
            let qp = with_control_box(random_ocp_qp(&mut rng, 4, 2, n), bound);
            let (sol, solver) = solve(&qp);
            let what = format!("N = {n}, |u| <= {bound}");
            assert_matches(&what, &qp, &sol, &clarabel_solve(&qp));
            assert_eq!(solver.info().regularised_pivots, 0, "{what}");
        }
    }
}

#[test]
fn one_sided_bounds_match_clarabel() {
    let mut rng = SplitMix64::new(4);
    let mut qp = random_ocp_qp(&mut rng, 4, 2, 20);
    for k in 0..20 {
        qp.u_lower[k][0] = -0.1;
        qp.u_upper[k][1] = 0.05;
    }
    let (sol, _) = solve(&qp);
    assert_matches("one-sided", &qp, &sol, &clarabel_solve(&qp));
}

#[test]
fn many_active_bounds() {
    let mut rng = SplitMix64::new(5);
    let opts = PendulumQpOptions {
        tau_max: 0.2,
        ..Default::default()
    };
    let mut active_total = 0;
    for rep in 0..5 {
        let qp = pendulum_rti_qp(&mut rng, &opts);
        let (sol, _) = solve(&qp);
        assert_matches(
            &format!("tau_max 0.2, rep {rep}"),
            &qp,
            &sol,
            &clarabel_solve(&qp),
        );
        active_total += (0..qp.horizon)
            .flat_map(|k| (0..2).map(move |j| (k, j)))
            .filter(|&(k, j)| {
                let u = sol.u[k][j];
                (u - qp.u_lower[k][j]).min(qp.u_upper[k][j] - u) < 1e-8
            })
            .count();
    }
    // The point of the case: a large share of the 5 x 160 bounds is active.
    assert!(active_total > 200, "only {active_total} active bounds");
}

#[test]
fn degenerate_bounds_fix_controls() {
    let mut rng = SplitMix64::new(6);
    let mut qp = with_control_box(random_ocp_qp(&mut rng, 4, 2, 30), 0.5);
    for k in (0..30).step_by(3) {
        qp.u_lower[k][1] = 0.25;
        qp.u_upper[k][1] = 0.25;
    }
    // A fully fixed stage too.
    qp.u_lower[7].fill(-0.1);
    qp.u_upper[7].fill(-0.1);
    let (sol, _) = solve(&qp);
    assert_matches("degenerate bounds", &qp, &sol, &clarabel_solve(&qp));
    for k in (0..30).step_by(3) {
        assert!((sol.u[k][1] - 0.25).abs() <= 1e-9);
    }
    assert!((sol.u[7][0] + 0.1).abs() <= 1e-9);
}

#[test]
fn soft_state_bounds_absorb_unrecoverable_initial_state() {
    let mut rng = SplitMix64::new(7);
    for &(l1, l2) in &[(10.0, 100.0), (50.0, 0.0), (0.0, 20.0)] {
        let mut qp = with_control_box(random_ocp_qp(&mut rng, 4, 2, 40), 0.3);
        for k in 0..=40 {
            qp.x_lower[k].fill(-0.2);
            qp.x_upper[k].fill(0.2);
        }
        // Component 3 only bounded above, component 0 only below.
        for k in 0..=40 {
            qp.x_lower[k][3] = f64::NEG_INFINITY;
            qp.x_upper[k][0] = f64::INFINITY;
        }
        qp.soft_l1.fill(l1);
        qp.soft_l2.fill(l2);
        qp.x0 = nalgebra::DVector::from_vec(vec![5.0, -4.0, 3.0, 6.0]);
        let (sol, _) = solve(&qp);
        let what = format!("soft l1 = {l1}, l2 = {l2}");
        assert_matches(&what, &qp, &sol, &clarabel_solve(&qp));
        // The bounds are violated (the controls cannot recover x0 at once),
        // yet the QP is solved.
        let violated = (1..=40)
            .filter(|&k| sol.x[k][2] > 0.2 + 1e-6 || sol.x[k][3] > 0.2 + 1e-6)
            .count();
        assert!(violated > 0, "{what}: no violated soft bound");
    }
}

#[test]
fn ill_conditioned_control_hessian() {
    let mut rng = SplitMix64::new(8);
    // R with condition number 1e12: still well posed, no regularisation
    // needed thanks to B' P B.
    let mut qp = with_control_box(random_ocp_qp(&mut rng, 4, 2, 20), 0.5);
    for k in 0..20 {
        qp.r[k] = nalgebra::DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![1e3, 1e-9]));
        qp.s[k].fill(0.0);
    }
    let (sol, _) = solve(&qp);
    assert_matches("cond(R) = 1e12", &qp, &sol, &clarabel_solve(&qp));

    // A control with zero weight and no effect: its Hessian block is
    // singular, the solver regularises, says so, and still meets the KKT
    // conditions (u_1 is not unique, so only the objective is compared).
    let mut qp = random_ocp_qp(&mut rng, 4, 2, 20);
    for k in 0..20 {
        qp.r[k][(1, 1)] = 0.0;
        qp.r[k][(0, 1)] = 0.0;
        qp.r[k][(1, 0)] = 0.0;
        for i in 0..4 {
            qp.s[k][(1, i)] = 0.0;
            qp.b[k][(i, 1)] = 0.0;
        }
        qp.r_lin[k][1] = 0.0;
    }
    let (sol, solver) = solve(&qp);
    assert_eq!(sol.status, QpStatus::Solved);
    assert!(solver.info().regularised_pivots > 0);
    assert!(solver.total_regularised_pivots() > 0);
    let kkt = kkt_residuals(&qp, &sol);
    assert!(kkt.within(KKT_TOL, KKT_REL_TOL), "{kkt:?}");
    let reference = clarabel_solve(&qp);
    let rel = (sol.objective - reference.objective).abs() / reference.objective.abs().max(1.0);
    assert!(rel <= OBJ_REL_TOL, "objective rel {rel:e}");
    assert!((sol.u[0][0] - reference.u[0][0]).abs() <= U0_TOL);
}

#[test]
fn semidefinite_state_cost() {
    // Q = 0 on every stage but the last (pure control cost): the state
    // pivots are truncated, which is exact.
    let mut rng = SplitMix64::new(9);
    let mut qp = with_control_box(random_ocp_qp(&mut rng, 4, 2, 15), 0.4);
    for k in 0..15 {
        qp.q[k].fill(0.0);
        qp.s[k].fill(0.0);
        qp.q_lin[k].fill(0.0);
    }
    qp.q[15].fill(0.0);
    qp.q[15][(0, 0)] = 10.0;
    let reference = clarabel_solve(&qp);
    let (sol, _) = solve(&qp);
    assert_matches("PSD Q", &qp, &sol, &reference);
    // The interior point alone (the active-set start has no pivots to
    // truncate: its recursion factors only the control blocks).
    let ip_only = RiccatiSettings {
        active_set_start: false,
        ..RiccatiSettings::default()
    };
    let mut solver = RiccatiSolver::new(4, 2, 15, ip_only);
    let mut sol = QpSolution::new(4, 2, 15);
    assert_eq!(solver.solve(&qp, &mut sol), QpStatus::Solved);
    assert_matches("PSD Q, interior point", &qp, &sol, &reference);
    assert!(solver.info().truncated_pivots > 0);
    assert_eq!(solver.info().regularised_pivots, 0);
}

#[test]
fn invalid_input_is_refused() {
    // (4, 2) and (6, 3) run on compile-time-sized cores, which check the
    // data while loading it (four values at a time and the rest: both
    // paths); (5, 2) on the runtime-size core and its own check.
    type Corrupt = fn(&mut OcpQp);
    let cases: [(&str, Corrupt); 22] = [
        ("NaN in A", |qp| qp.a[3][(1, 2)] = f64::NAN),
        ("Inf in B", |qp| qp.b[9][(0, 1)] = f64::INFINITY),
        ("Inf in c", |qp| qp.c[5][3] = f64::NEG_INFINITY),
        ("NaN in Q_N", |qp| qp.q[10][(2, 2)] = f64::NAN),
        ("NaN in S", |qp| qp.s[1][(1, 3)] = f64::NAN),
        ("NaN in R", |qp| qp.r[6][(1, 1)] = f64::NAN),
        ("NaN in q", |qp| qp.q_lin[7][0] = f64::NAN),
        ("NaN in r", |qp| qp.r_lin[0][1] = f64::NAN),
        ("NaN in x0", |qp| qp.x0[0] = f64::NAN),
        ("Inf in x0", |qp| qp.x0[3] = f64::INFINITY),
        ("NaN bound", |qp| qp.u_lower[2][0] = f64::NAN),
        ("lower bound +inf", |qp| qp.u_lower[8][1] = f64::INFINITY),
        ("NaN state bound", |qp| qp.x_upper[2][0] = f64::NAN),
        ("upper state bound -inf", |qp| {
            qp.x_upper[10][1] = f64::NEG_INFINITY
        }),
        ("NaN bound of x_0", |qp| qp.x_lower[0][2] = f64::NAN),
        ("crossed control bounds", |qp| {
            qp.u_lower[4][1] = 1.0;
            qp.u_upper[4][1] = -1.0;
        }),
        ("negative penalty", |qp| qp.soft_l1[1] = -1.0),
        ("NaN penalty", |qp| qp.soft_l2[0] = f64::NAN),
        ("asymmetric R", |qp| qp.r[1][(0, 1)] += 1.0),
        ("asymmetric Q", |qp| qp.q[4][(3, 0)] += 1e-3),
        ("wrong horizon", |qp| qp.horizon = 9),
        ("wrong vector size", |qp| {
            qp.c[2] = nalgebra::DVector::zeros(3);
        }),
    ];
    let mut rng = SplitMix64::new(10);
    for (nx, nu) in [(4, 2), (6, 3), (5, 2)] {
        let good = with_control_box(random_ocp_qp(&mut rng, nx, nu, 10), 1.0);
        let mut solver = RiccatiSolver::new(nx, nu, 10, RiccatiSettings::default());
        let mut sol = QpSolution::new(nx, nu, 10);
        for (what, corrupt) in cases {
            let mut qp = good.clone();
            corrupt(&mut qp);
            assert_eq!(
                solver.solve(&qp, &mut sol),
                QpStatus::InvalidInput,
                "({nx}, {nu}) {what}"
            );
            assert_eq!(sol.status, QpStatus::InvalidInput, "{what}");
            assert!(!sol.status.is_usable());
            assert!(sol.objective.is_nan(), "{what}");
            // The solver is still fine afterwards.
            assert_eq!(
                solver.solve(&good, &mut sol),
                QpStatus::Solved,
                "after {what}"
            );
        }
        // Asymmetry at round-off is accepted.
        let mut qp = good.clone();
        qp.q[4][(3, 0)] += 1e-14;
        assert_eq!(solver.solve(&qp, &mut sol), QpStatus::Solved);
        // A QP of other dimensions is refused too.
        let other = random_ocp_qp(&mut rng, nx, nu, 11);
        assert_eq!(solver.solve(&other, &mut sol), QpStatus::InvalidInput);
    }
}

#[test]
fn iteration_limit_is_reported() {
    let mut rng = SplitMix64::new(11);
    let qp = with_control_box(random_ocp_qp(&mut rng, 4, 2, 20), 0.2);
    let settings = RiccatiSettings {
        max_iterations: 2,
        ..Default::default()
    };
    let mut solver = RiccatiSolver::new(4, 2, 20, settings);
    let mut sol = QpSolution::new(4, 2, 20);
    assert_eq!(solver.solve(&qp, &mut sol), QpStatus::MaxIterations);
    assert_eq!(sol.iterations, 2);
    assert!(sol.primal_residual > 1e-6 || sol.dual_residual > 1e-6);
}

/// Solves every QP of a record file with both backends; returns (count,
/// worst first-control difference, worst KKT residual, max iterations).
fn check_record(path: &Path) -> (usize, f64, f64, usize) {
    let mut reader = QpRecordReader::open(path).expect("readable QP record");
    let mut solver: Option<RiccatiSolver> = None;
    let mut sol = QpSolution::new(1, 1, 1);
    let (mut count, mut worst_u0, mut worst_kkt, mut max_iter) = (0, 0.0f64, 0.0f64, 0);
    while let Some(qp) = reader.next_qp().expect("valid QP record") {
        let fits = solver
            .as_ref()
            .is_some_and(|s| s.dimensions() == (qp.nx, qp.nu, qp.horizon));
        if !fits {
            solver = Some(RiccatiSolver::new(
                qp.nx,
                qp.nu,
                qp.horizon,
                Default::default(),
            ));
            sol = QpSolution::new(qp.nx, qp.nu, qp.horizon);
        }
        let s = solver.as_mut().expect("solver created above");
        s.solve(&qp, &mut sol);
        let reference = clarabel_solve(&qp);
        assert_matches(
            &format!("{} QP {count}", path.display()),
            &qp,
            &sol,
            &reference,
        );
        worst_u0 = worst_u0.max((&sol.u[0] - &reference.u[0]).amax());
        worst_kkt = worst_kkt.max(kkt_residuals(&qp, &sol).max());
        max_iter = max_iter.max(sol.iterations);
        count += 1;
    }
    (count, worst_u0, worst_kkt, max_iter)
}

#[test]
fn synthetic_pendulum_set_matches_clarabel() {
    // 320 random double-pendulum linearisations (N = 80, dt = 0.025):
    // near-zero and large initial deviations, |tau| <= 1 and <= 0.2, with
    // and without soft velocity bounds; written to a record file and read
    // back, exercising the replay machinery.
    let mut rng = SplitMix64::new(12);
    let path = std::env::temp_dir().join(format!("eigenmpc-qp-set-{}.bin", std::process::id()));
    let mut writer = QpRecordWriter::create(&path).expect("temp file");
    let count = 320;
    for i in 0..count {
        let opts = PendulumQpOptions {
            tau_max: if i % 2 == 0 { 1.0 } else { 0.2 },
            initial_deviation: if i % 4 < 2 { 0.01 } else { 1.0 },
            velocity_bound: if i % 8 < 4 { 6.0 } else { f64::INFINITY },
            ..Default::default()
        };
        writer.write(&pendulum_rti_qp(&mut rng, &opts)).unwrap();
    }
    writer.finish().unwrap();
    let (n, u0, kkt, iters) = check_record(&path);
    std::fs::remove_file(&path).ok();
    assert_eq!(n, count);
    println!(
        "synthetic set: {n} QPs, max |du0| {u0:.1e}, max KKT {kkt:.1e}, max iterations {iters}"
    );
}

/// The recorded RTI QPs of the paper scenarios (issue 5 acceptance), when
/// the controller has produced them: `EIGENMPC_QP_RECORD` or
/// `tests/data/rti_qps.bin`.
#[test]
fn recorded_rti_set_matches_clarabel() {
    let path = std::env::var_os("EIGENMPC_QP_RECORD")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/rti_qps.bin"));
    if !path.exists() {
        println!("no recorded QP set at {}; skipped", path.display());
        return;
    }
    let (n, u0, kkt, iters) = check_record(&path);
    assert!(n > 0, "empty QP record");
    println!(
        "recorded set: {n} QPs, max |du0| {u0:.1e}, max KKT {kkt:.1e}, max iterations {iters}"
    );
}

#[test]
fn warm_start_from_an_unrelated_solution_still_converges_to_the_same_point() {
    // The warm start only changes the starting point: after a solve of one
    // QP and `shift_warm_start`, a different QP (bounds active, one core
    // compile-time-sized, one runtime-sized) gives the cold solution.
    let mut rng = SplitMix64::new(77);
    for (nx, nu) in [(4, 2), (3, 1)] {
        let n = 30;
        let first = with_control_box(random_ocp_qp(&mut rng, nx, nu, n), 0.3);
        let second = with_control_box(random_ocp_qp(&mut rng, nx, nu, n), 0.2);
        let (cold, _) = solve(&second);
        let mut solver = RiccatiSolver::new(nx, nu, n, RiccatiSettings::default());
        let mut sol = QpSolution::new(nx, nu, n);
        assert_eq!(solver.solve(&first, &mut sol), QpStatus::Solved);
        solver.shift_warm_start(true);
        assert_eq!(solver.solve(&second, &mut sol), QpStatus::Solved);
        let reference = clarabel_solve(&second);
        assert_matches(&format!("warm ({nx}, {nu})"), &second, &sol, &reference);
        let du = (0..n)
            .map(|k| (&sol.u[k] - &cold.u[k]).amax())
            .fold(0.0, f64::max);
        assert!(
            du < 1e-8,
            "({nx}, {nu}): warm vs cold controls differ by {du:e}"
        );
    }
}

#[test]
fn active_set_start_gives_the_interior_point_solution() {
    // Cold solves: the active-set start's first guess is "nothing active".
    // Where the interior point (the setting off) ends with no active bound,
    // that one Riccati recursion is the solution; with active bounds it
    // takes more guesses or falls back to the interior point. Either way
    // the same point as the interior point alone and clarabel.
    let mut rng = SplitMix64::new(91);
    let plain = RiccatiSettings {
        active_set_start: false,
        ..RiccatiSettings::default()
    };
    let mut cases: Vec<OcpQp> = vec![];
    for _ in 0..4 {
        cases.push(with_control_box(random_ocp_qp(&mut rng, 4, 2, 80), 10.0));
        cases.push(with_control_box(random_ocp_qp(&mut rng, 4, 2, 80), 0.2));
        cases.push(with_control_box(random_ocp_qp(&mut rng, 6, 3, 40), 10.0));
        cases.push(with_control_box(random_ocp_qp(&mut rng, 2, 1, 40), 10.0));
    }
    for tau_max in [1.0, 5.0, 50.0] {
        let pendulum = PendulumQpOptions {
            tau_max,
            initial_deviation: 0.01,
            velocity_bound: f64::INFINITY,
            ..Default::default()
        };
        for _ in 0..4 {
            cases.push(pendulum_rti_qp(&mut rng, &pendulum));
        }
    }
    let (mut one_step_count, mut active_count) = (0, 0);
    for (i, qp) in cases.iter().enumerate() {
        let (sol, solver) = solve(qp);
        let mut reference_solver = RiccatiSolver::new(qp.nx, qp.nu, qp.horizon, plain);
        let mut ip = QpSolution::new(qp.nx, qp.nu, qp.horizon);
        assert_eq!(reference_solver.solve(qp, &mut ip), QpStatus::Solved);
        assert!(!reference_solver.info().active_set_start);
        let largest_multiplier = ip
            .lam_u_lower
            .iter()
            .chain(&ip.lam_u_upper)
            .map(|l| l.amax())
            .fold(0.0, f64::max);
        let active = largest_multiplier > 1e-6;
        let what = format!("case {i} (largest multiplier {largest_multiplier:.1e})");
        assert_matches(&what, qp, &sol, &clarabel_solve(qp));
        let du = (0..qp.horizon)
            .map(|k| (&sol.u[k] - &ip.u[k]).amax())
            .fold(0.0, f64::max);
        assert!(
            du < 1e-8,
            "{what}: controls differ from the interior point's by {du:e}"
        );
        let info = solver.info();
        let one_step = info.active_set_start && info.iterations == 1;
        assert_eq!(one_step, !active, "{what}: {info:?}");
        if one_step {
            one_step_count += 1;
            // Multipliers of an inactive solution are exactly zero.
            assert!(
                sol.lam_u_lower
                    .iter()
                    .chain(&sol.lam_u_upper)
                    .all(|l| l.amax() == 0.0)
            );
        } else {
            active_count += 1;
        }
    }
    assert!(
        one_step_count >= 12 && active_count >= 4,
        "{one_step_count} / {active_count}"
    );
}

/// The QP's data moved by a relative `size` (a new RTI linearisation).
fn perturbed(qp: &OcpQp, rng: &mut SplitMix64, size: f64) -> OcpQp {
    let mut out = qp.clone();
    let mut wiggle = |v: &mut f64| *v *= 1.0 + size * (2.0 * rng.unit() - 1.0);
    for k in 0..qp.horizon {
        out.a[k].iter_mut().for_each(&mut wiggle);
        out.b[k].iter_mut().for_each(&mut wiggle);
        out.c[k].iter_mut().for_each(&mut wiggle);
        out.r_lin[k].iter_mut().for_each(&mut wiggle);
    }
    for k in 0..=qp.horizon {
        out.q_lin[k].iter_mut().for_each(&mut wiggle);
    }
    out
}

/// The QP shifted by one stage, as the next RTI sample sees it.
fn shifted(qp: &OcpQp) -> OcpQp {
    let mut out = qp.clone();
    let n = qp.horizon;
    for k in 0..n - 1 {
        out.a[k] = qp.a[k + 1].clone();
        out.b[k] = qp.b[k + 1].clone();
        out.c[k] = qp.c[k + 1].clone();
        out.q[k] = qp.q[k + 1].clone();
        out.s[k] = qp.s[k + 1].clone();
        out.r[k] = qp.r[k + 1].clone();
        out.q_lin[k] = qp.q_lin[k + 1].clone();
        out.r_lin[k] = qp.r_lin[k + 1].clone();
    }
    out
}

#[test]
fn active_set_start_follows_the_shifted_active_set() {
    // A sequence of RTI-like QPs with many saturated controls: each the
    // previous one shifted by a stage and its data moved by 1 %. The
    // active-set start, guessing the shifted previous active set, solves
    // most of them in one or two recursions; every solution (whichever
    // path) matches clarabel, multipliers included.
    let mut rng = SplitMix64::new(93);
    for (nx, nu, bound) in [(4, 2, 0.3), (6, 3, 0.3), (2, 1, 0.5)] {
        let n = 60;
        let mut qp = with_control_box(random_ocp_qp(&mut rng, nx, nu, n), bound);
        let mut solver = RiccatiSolver::new(nx, nu, n, RiccatiSettings::default());
        let mut sol = QpSolution::new(nx, nu, n);
        let (mut taken, mut with_active, mut ip_iterations) = (0, 0, vec![]);
        for sample in 0..30 {
            assert_eq!(solver.solve(&qp, &mut sol), QpStatus::Solved);
            let reference = clarabel_solve(&qp);
            let what = format!("({nx}, {nu}) sample {sample}: {:?}", solver.info());
            assert_matches(&what, &qp, &sol, &reference);
            let active: usize = (0..n)
                .map(|k| {
                    (0..nu)
                        .filter(|&j| (sol.u[k][j].abs() - bound).abs() < 1e-9)
                        .count()
                })
                .sum();
            let info = *solver.info();
            if info.active_set_start {
                taken += 1;
                with_active += usize::from(active > 0);
                assert!(info.iterations <= RiccatiSettings::default().active_set_guesses);
                // Exact: the saturated controls sit on their bounds.
                let du = (0..n)
                    .map(|k| (&sol.u[k] - &reference.u[k]).amax())
                    .fold(0.0, f64::max);
                assert!(du < 1e-6, "{what}: controls {du:e} from clarabel's");
            } else {
                ip_iterations.push(info.iterations);
            }
            solver.shift_warm_start(true);
            qp = perturbed(&shifted(&qp), &mut rng, 0.01);
        }
        eprintln!(
            "({nx}, {nu}): active-set start took {taken} of 30 ({with_active} with active bounds); interior point iterations otherwise {ip_iterations:?}"
        );
        assert!(
            taken >= 20 && with_active >= 15,
            "({nx}, {nu}): {taken} / {with_active}"
        );
    }
}

#[test]
fn active_set_start_gives_up_after_its_guesses() {
    // A wrong guess that needs more than the allowed guesses: the interior
    // point runs from the warm start and reaches the same point.
    let mut rng = SplitMix64::new(94);
    let n = 40;
    let tight = with_control_box(random_ocp_qp(&mut rng, 4, 2, n), 0.05);
    let other = with_control_box(random_ocp_qp(&mut rng, 4, 2, n), 0.3);
    let one_guess = RiccatiSettings {
        active_set_guesses: 1,
        ..RiccatiSettings::default()
    };
    let mut solver = RiccatiSolver::new(4, 2, n, one_guess);
    let mut sol = QpSolution::new(4, 2, n);
    assert_eq!(solver.solve(&tight, &mut sol), QpStatus::Solved);
    solver.shift_warm_start(true);
    assert_eq!(solver.solve(&other, &mut sol), QpStatus::Solved);
    assert!(!solver.info().active_set_start, "{:?}", solver.info());
    assert!(solver.info().iterations > 1);
    assert_matches(
        "after one wrong guess",
        &other,
        &sol,
        &clarabel_solve(&other),
    );
    // The next sample of the other QP (shifted, from the predicted state):
    // the shifted active set is right but near the horizon's end, and
    // the default guesses find the solution.
    let mut solver = RiccatiSolver::new(4, 2, n, RiccatiSettings::default());
    let mut first = QpSolution::new(4, 2, n);
    assert_eq!(solver.solve(&other, &mut first), QpStatus::Solved);
    let mut next = shifted(&other);
    next.x0 = first.x[1].clone();
    solver.shift_warm_start(true);
    let mut sol = QpSolution::new(4, 2, n);
    assert_eq!(solver.solve(&next, &mut sol), QpStatus::Solved);
    assert!(solver.info().active_set_start, "{:?}", solver.info());
    assert_matches("the next sample", &next, &sol, &clarabel_solve(&next));
}

/// [`QpSolver::solve_stages`] on the stage-wise form against
/// [`QpSolver::solve`] on the same QP: a sequence of shifted, perturbed
/// QPs with saturated controls and warm starts, both solvers fed the same.
fn stage_wise_matches<const NX: usize, const NU: usize>(rng: &mut SplitMix64) {
    let n = 40;
    let mut qp = with_control_box(random_ocp_qp(rng, NX, NU, n), 0.3);
    let settings = RiccatiSettings::default();
    let mut by_ocp = RiccatiSolver::new(NX, NU, n, settings);
    let mut by_stages = RiccatiSolver::new(NX, NU, n, settings);
    let (mut sol, mut sol_stages) = (QpSolution::new(NX, NU, n), QpSolution::new(NX, NU, n));
    let mut scratch = OcpQp::new(NX, NU, n);
    let mut taken = 0;
    for sample in 0..12 {
        let stages = StageQp::<NX, NU>::from_ocp(&qp).expect("sizes");
        let status = by_ocp.solve(&qp, &mut sol);
        assert_eq!(status, QpStatus::Solved, "({NX}, {NU}) sample {sample}");
        let status = by_stages.solve_stages(&stages, &mut scratch, &mut sol_stages);
        assert_eq!(status, QpStatus::Solved, "({NX}, {NU}) sample {sample}");
        // The same arithmetic in the same order: the same bits.
        assert_eq!(
            format!("{sol:?}"),
            format!("{sol_stages:?}"),
            "({NX}, {NU}) {sample}"
        );
        assert_eq!(
            by_ocp.info(),
            by_stages.info(),
            "({NX}, {NU}) sample {sample}"
        );
        taken += usize::from(by_stages.info().active_set_start);
        by_ocp.shift_warm_start(true);
        by_stages.shift_warm_start(true);
        qp = perturbed(&shifted(&qp), rng, 0.01);
    }
    // The runtime-size core has no active-set start.
    let fixed = NX == 2 * NU;
    assert!(
        !fixed || taken >= 6,
        "({NX}, {NU}): the active-set start took {taken} of 12"
    );

    // Bad data is refused as on the other path, and the solver recovers.
    let good = StageQp::<NX, NU>::from_ocp(&qp).expect("sizes");
    type Corrupt<const NX: usize, const NU: usize> = fn(&mut StageQp<NX, NU>);
    let cases: [(&str, Corrupt<NX, NU>); 6] = [
        ("NaN in A", |qp| qp.stages[3].a[(1, 0)] = f64::NAN),
        ("Inf in c", |qp| qp.stages[5].c[0] = f64::INFINITY),
        ("NaN in Q_N", |qp| qp.stages[40].q[(0, 0)] = f64::NAN),
        ("NaN in x0", |qp| qp.x0[0] = f64::NAN),
        ("crossed control bounds", |qp| {
            qp.stages[4].u_lower[0] = 1.0;
            qp.stages[4].u_upper[0] = -1.0;
        }),
        ("asymmetric R", |qp| {
            qp.stages[1].r[(NU - 1, 0)] += if NU > 1 { 1.0 } else { 0.0 };
            qp.stages[1].q[(NX - 1, 0)] += 1.0;
        }),
    ];
    for (what, corrupt) in cases {
        let mut bad = good.clone();
        corrupt(&mut bad);
        let status = by_stages.solve_stages(&bad, &mut scratch, &mut sol_stages);
        assert_eq!(status, QpStatus::InvalidInput, "({NX}, {NU}) {what}");
        assert!(sol_stages.objective.is_nan(), "({NX}, {NU}) {what}");
        let status = by_stages.solve_stages(&good, &mut scratch, &mut sol_stages);
        assert_eq!(status, QpStatus::Solved, "({NX}, {NU}) after {what}");
    }
    // Another horizon, or other sizes, reach the converted path's refusal.
    let longer = StageQp::<NX, NU>::from_ocp(&random_ocp_qp(rng, NX, NU, n + 1)).expect("sizes");
    let status = by_stages.solve_stages(&longer, &mut scratch, &mut sol_stages);
    assert_eq!(
        status,
        QpStatus::InvalidInput,
        "({NX}, {NU}) longer horizon"
    );
    let other = StageQp::<3, 1>::from_ocp(&random_ocp_qp(rng, 3, 1, n)).expect("sizes");
    let status = by_stages.solve_stages(&other, &mut scratch, &mut sol_stages);
    assert_eq!(status, QpStatus::InvalidInput, "({NX}, {NU}) other sizes");
}

#[test]
fn the_stage_wise_form_solves_as_the_ocp_form() {
    // (4, 2), (6, 3), (2, 1): the compile-time-sized cores read the stages
    // directly; (5, 2): the runtime-size core gets them converted.
    let mut rng = SplitMix64::new(22);
    stage_wise_matches::<4, 2>(&mut rng);
    stage_wise_matches::<6, 3>(&mut rng);
    stage_wise_matches::<2, 1>(&mut rng);
    stage_wise_matches::<5, 2>(&mut rng);
}
