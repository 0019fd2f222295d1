//! Can one integration step of 25 ms replace the friction's RK4 substeps?
//! (issue 22). `cargo run --release --example one_step_friction`
//!
//! Along 15 s of the default controller on the laboratory robots A0 and B0
//! (2 J, |tau| <= 0.5, from rest), every planned interval of every sixth
//! sample is integrated by the controller's prediction and by candidates,
//! each against the robot's exact Coulomb law integrated accurately (the
//! plant). The candidates: RK4 on the exact law with one and three steps,
//! and ROS34PW2 (Rang and Angermann, 2005), an L-stable Rosenbrock-W method
//! of order 3 that stays stable on the stiff friction in one step with the
//! full Jacobian or only the friction's block in its W matrix. First, its
//! order on a smooth interval (the error falls 8x a halving of the step).
//!
//! Measured (the book, `docs/book/src/performance.md`): one Rosenbrock-W step predicts no better than
//! one RK4 step; the substeps resolve the friction torque's flip at a stop,
//! they do not merely keep RK4 stable.

use eigenmpc::integrate::{Tolerances, rk4_step, simulate_accurate};
use eigenmpc::mechanics::{MechanicalSystem, PlanarChain, Vector};
use eigenmpc::model_file::RobotFile;
use eigenmpc::mpc::closed_loop::{START_ANGLE, robot_controller};
use eigenmpc::mpc::{SPEED_REACH, Variant};
use nalgebra::{SMatrix, SVector};

type State = SVector<f64, 4>;
type Square = SMatrix<f64, 4, 4>;

/// ROS34PW2's diagonal `gamma`, propagation `alpha`, stage `gamma_ij` and
/// weights `b`.
const GAMMA: f64 = 4.358_665_215_084_59e-1;
const ALPHA: [[f64; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [8.717_330_430_169_18e-1, 0.0, 0.0],
    [8.445_706_001_536_942e-1, -1.129_906_423_648_418_5e-1, 0.0],
    [0.0, 0.0, 1.0],
];
const STAGE_GAMMA: [[f64; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [-8.717_330_430_169_18e-1, 0.0, 0.0],
    [-9.033_805_701_304_408e-1, 5.418_067_238_809_533e-2, 0.0],
    [
        2.421_238_070_609_534_6e-1,
        -1.223_250_583_904_514_7,
        5.452_602_553_351_021e-1,
    ],
];
const WEIGHTS: [f64; 4] = [
    2.421_238_070_609_534_6e-1,
    -1.223_250_583_904_514_7,
    1.545_260_255_335_102,
    4.358_665_215_084_59e-1,
];
const DT: f64 = 0.025;

fn split(z: &State) -> (Vector<2>, Vector<2>) {
    (Vector::<2>::new(z[0], z[1]), Vector::<2>::new(z[2], z[3]))
}

/// `z' = (qd, qdd)`.
fn rate<S: MechanicalSystem<2>>(system: &S, z: &State, u: &Vector<2>) -> State {
    let (q, qd) = split(z);
    let qdd = system.forward_dynamics(&q, &qd, u);
    State::new(z[2], z[3], qdd[0], qdd[1])
}

/// One ROS34PW2 step of `h` with the matrix `jacobian` in its W matrix
/// (any approximation keeps order 3: a W-method).
fn rosenbrock_w<S: MechanicalSystem<2>>(
    system: &S,
    z: &State,
    u: &Vector<2>,
    h: f64,
    jacobian: &Square,
) -> State {
    let w = (Square::identity() - jacobian * (h * GAMMA)).lu();
    let mut k = [State::zeros(); 4];
    for i in 0..4 {
        let (mut y, mut g) = (*z, State::zeros());
        for j in 0..i {
            y += k[j] * ALPHA[i][j];
            g += k[j] * STAGE_GAMMA[i][j];
        }
        let rhs = (rate(system, &y, u) + jacobian * g) * h;
        k[i] = w.solve(&rhs).expect("W is regular for these steps");
    }
    (0..4).fold(*z, |out, i| out + k[i] * WEIGHTS[i])
}

/// `[0 I; d_q d_qd]` at `z`.
fn full_jacobian<S: MechanicalSystem<2>>(system: &S, z: &State, u: &Vector<2>) -> Square {
    let (q, qd) = split(z);
    let d = system.dynamics_jacobian(&q, &qd, u);
    let mut j = Square::zeros();
    j[(0, 2)] = 1.0;
    j[(1, 3)] = 1.0;
    j.fixed_view_mut::<2, 2>(2, 0).copy_from(&d.d_q);
    j.fixed_view_mut::<2, 2>(2, 2).copy_from(&d.d_qd);
    j
}

/// `[0 0; 0 -M^-1 diag(tau_f'(v))]`: the friction's block alone.
fn friction_jacobian(system: &PlanarChain<2>, z: &State, v: &Vector<2>) -> Square {
    let (q, _) = split(z);
    let inverse = system
        .mass_matrix(&q)
        .try_inverse()
        .expect("a mass matrix is invertible");
    let slope = system.friction_slope(v);
    let mut j = Square::zeros();
    for r in 0..2 {
        for c in 0..2 {
            j[(2 + r, 2 + c)] = -inverse[(r, c)] * slope[c];
        }
    }
    j
}

/// Each joint's slowest speed within reach of the interval (as the
/// controller's substep choice takes it): zero where it may stop.
fn slowest_in_reach(z: &State, rate: &State) -> Vector<2> {
    let reach = SPEED_REACH * DT;
    Vector::<2>::from_fn(|j, _| {
        let (v, a) = (z[2 + j], rate[2 + j].abs());
        let (lo, hi) = (v - reach * a, v + reach * a);
        if lo <= 0.0 && hi >= 0.0 {
            0.0
        } else {
            lo.abs().min(hi.abs())
        }
    })
}

fn accurate(robot: &PlanarChain<2>, z: &State, u: &Vector<2>, t: f64, tol: f64) -> State {
    let tol = Tolerances {
        rtol: tol,
        atol: tol,
    };
    simulate_accurate::<_, 2, 4>(robot, z, u, t, tol).expect("accurate integration")
}

fn rk4(system: &PlanarChain<2>, z: &State, u: &Vector<2>, steps: usize) -> State {
    (0..steps).fold(*z, |x, _| {
        rk4_step::<_, 2, 4>(system, &x, u, DT / steps as f64)
    })
}

fn load(name: &str) -> PlanarChain<2> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("robots")
        .join(name);
    RobotFile::load(path)
        .and_then(|file| file.chain::<2>())
        .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// ROS34PW2's error over 50 ms of a smooth interval (both joints fast)
/// in 1 to 16 steps.
fn order_check() {
    let robot = load("lab-double-pendulum-A0.yml");
    let (z, u, t) = (
        State::new(0.1, -0.1, 3.0, -3.0),
        Vector::<2>::new(0.1, -0.05),
        0.05,
    );
    let exact = accurate(&robot, &z, &u, t, 1e-13);
    println!("ROS34PW2 on a smooth interval of A0 (50 ms), max abs state error:\n");
    println!("| steps | full Jacobian | J = 0 (explicit) |");
    println!("|---|---|---|");
    for n in [1usize, 2, 4, 8, 16] {
        let h = t / n as f64;
        let (mut full, mut explicit) = (z, z);
        for _ in 0..n {
            full = rosenbrock_w(&robot, &full, &u, h, &full_jacobian(&robot, &full, &u));
            explicit = rosenbrock_w(&robot, &explicit, &u, h, &Square::zeros());
        }
        println!(
            "| {n} | {:.2e} | {:.2e} |",
            (full - exact).amax(),
            (explicit - exact).amax()
        );
    }
}

fn main() {
    order_check();
    const CANDIDATES: [&str; 8] = [
        "prediction model (slope lowered), its 1-3 RK4 substeps",
        "prediction model, 1 RK4 step",
        "exact law, 1 RK4 step",
        "exact law, 3 RK4 substeps",
        "exact law, 1 ROS34PW2 step, full Jacobian",
        "exact law, 1 ROS34PW2 step, friction block at the start speed",
        "exact law, 1 ROS34PW2 step, friction block at the slowest speed in reach",
        "exact law, 2 ROS34PW2 substeps, full Jacobian",
    ];
    for name in ["lab-double-pendulum-A0.yml", "lab-double-pendulum-B0.yml"] {
        let robot = load(name);
        let (mut ctrl, _) =
            robot_controller::<2, 4>(&robot, Variant::Curved, 2.0, 0.5).expect("controller");
        let model = *ctrl.system();
        let (mut worst, mut sum, mut count) = ([0.0f64; 8], [0.0f64; 8], 0usize);
        let mut z = State::new(START_ANGLE, START_ANGLE, 0.0, 0.0);
        for sample in 0..600 {
            let out = ctrl.step(&z);
            if sample % 6 == 0 {
                let xs = ctrl.predicted_states();
                for (x, u) in xs.iter().zip(ctrl.planned_controls()) {
                    let exact = accurate(&robot, x, u, DT, 1e-11);
                    let start = Vector::<2>::new(x[2], x[3]);
                    let slowest = slowest_in_reach(x, &rate(&robot, x, u));
                    let halves = (0..2).fold(*x, |y, _| {
                        rosenbrock_w(&robot, &y, u, DT / 2.0, &full_jacobian(&robot, &y, u))
                    });
                    let predictions = [
                        rk4(&model, x, u, ctrl.interval_substeps(x, u)),
                        rk4(&model, x, u, 1),
                        rk4(&robot, x, u, 1),
                        rk4(&robot, x, u, 3),
                        rosenbrock_w(&robot, x, u, DT, &full_jacobian(&robot, x, u)),
                        rosenbrock_w(&robot, x, u, DT, &friction_jacobian(&robot, x, &start)),
                        rosenbrock_w(&robot, x, u, DT, &friction_jacobian(&robot, x, &slowest)),
                        halves,
                    ];
                    for (i, p) in predictions.iter().enumerate() {
                        // A diverged step counts as an error of 1e9.
                        let e = (p - exact).amax();
                        let e = if e.is_finite() { e } else { 1e9 };
                        worst[i] = worst[i].max(e);
                        sum[i] += e;
                    }
                    count += 1;
                }
            }
            z = accurate(&robot, &z, &out.tau, DT, 1e-9);
        }
        println!(
            "\n{name}, 2 J: {count} planned intervals, max abs state error against the exact law\n"
        );
        println!("| prediction | worst | mean |");
        println!("|---|---|---|");
        for (i, label) in CANDIDATES.iter().enumerate() {
            println!(
                "| {label} | {:.2e} | {:.2e} |",
                worst[i],
                sum[i] / count as f64
            );
        }
    }
}
