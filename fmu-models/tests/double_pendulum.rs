//! The DoublePendulum FMU through its FMI 2.0 C functions: physics (energy
//! conservation, work of the torque, damping), independence from the
//! communication step, parameter checks, the checked-in model description.
//! (The FMU binary's symbols and loading: robot-fmu's tests.)

/// The FMU's C functions over the model, as the FMU binary exports them
/// (one model per test binary: the symbols are unmangled).
mod fmi2_exports {
    fmi2_slave::export_fmi2!(eigenmpc_fmu_models::products::DoublePendulumFmu);
}
use eigenmpc::math;
use eigenmpc_fmu_models::products::DoublePendulumFmu;
use fmi2_exports::*;
use fmi2_slave::testing::TestInstance;
use fmi2_slave::{Model, ffi, xml};
use std::path::PathBuf;
use std::ptr;

const OK: ffi::fmi2Status = ffi::fmi2Status_fmi2OK;
const ERROR: ffi::fmi2Status = ffi::fmi2Status_fmi2Error;
/// Value reference of `name` in the FMU's variable table.
fn vref(name: &str) -> u32 {
    DoublePendulumFmu::description()
        .variable(name)
        .unwrap_or_else(|| panic!("no variable {name}"))
        .value_reference
}

fn outputs_vr() -> [u32; 5] {
    [
        vref("q[1]"),
        vref("q[2]"),
        vref("qd[1]"),
        vref("qd[2]"),
        vref("energy"),
    ]
}

struct Fmu {
    c: ffi::fmi2Component,
    instance: TestInstance,
    t: f64,
}

impl Fmu {
    /// Instantiated, parameters set, initialized.
    fn start(params: &[(u32, f64)]) -> Self {
        let fmu = Self::instantiate();
        for &(vr, v) in params {
            assert_eq!(fmu.set(&[vr], &[v]), OK, "{:?}", fmu.instance.log.lines());
        }
        unsafe {
            assert_eq!(fmi2SetupExperiment(fmu.c, 0, 0.0, 0.0, 0, 0.0), OK);
            assert_eq!(fmi2EnterInitializationMode(fmu.c), OK);
            assert_eq!(fmi2ExitInitializationMode(fmu.c), OK);
        }
        fmu
    }

    fn instantiate() -> Self {
        let instance = TestInstance::new::<DoublePendulumFmu>(Some(fmi2Instantiate), "pendulum");
        Self {
            c: instance.component,
            instance,
            t: 0.0,
        }
    }

    fn set(&self, vr: &[u32], v: &[f64]) -> ffi::fmi2Status {
        unsafe { fmi2SetReal(self.c, vr.as_ptr(), vr.len(), v.as_ptr()) }
    }

    fn outputs(&self) -> [f64; 5] {
        let mut v = [f64::NAN; 5];
        assert_eq!(
            unsafe { fmi2GetReal(self.c, outputs_vr().as_ptr(), 5, v.as_mut_ptr()) },
            OK
        );
        v
    }

    fn step(&mut self, h: f64) {
        assert_eq!(
            unsafe { fmi2DoStep(self.c, self.t, h, 1) },
            OK,
            "{:?}",
            self.instance.log.lines()
        );
        self.t += h;
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        unsafe { fmi2FreeInstance(self.c) }
    }
}

fn swing() -> [(u32, f64); 4] {
    [
        (vref("q0[1]"), 1.2),
        (vref("q0[2]"), -0.7),
        (vref("qd0[1]"), 0.5),
        (vref("qd0[2]"), 1.5),
    ]
}

#[test]
fn free_run_of_60_s_conserves_energy() {
    let mut fmu = Fmu::start(&swing());
    let e0 = fmu.outputs()[4];
    // E0 from the paper's formula: V = g (m1 + m2) l1 (1 - cos q1) + g m2 l2 (1 - cos(q1 + q2)), T = 1/2 qd'M qd
    let (q1, q2, w1, w2) = (1.2f64, -0.7f64, 0.5f64, 1.5f64);
    let v = 9.81 * 2.0 * (1.0 - math::cos(q1)) + 9.81 * (1.0 - math::cos(q1 + q2));
    let m = [
        [3.0 + 2.0 * math::cos(q2), 1.0 + math::cos(q2)],
        [1.0 + math::cos(q2), 1.0],
    ];
    let kin = 0.5 * (m[0][0] * w1 * w1 + 2.0 * m[0][1] * w1 * w2 + m[1][1] * w2 * w2);
    assert!((e0 - (v + kin)).abs() < 1e-12, "{e0} vs {}", v + kin);
    let mut worst: f64 = 0.0;
    for _ in 0..6000 {
        fmu.step(0.01);
        worst = worst.max(((fmu.outputs()[4] - e0) / e0).abs());
    }
    println!("60 s free run: max relative energy drift {worst:.2e}");
    assert!(worst < 1e-8, "relative energy drift {worst}");
    // chaotic swing: it really moved
    assert!(fmu.outputs()[3].abs() > 0.1);
}

#[test]
fn result_does_not_depend_on_the_communication_step() {
    let mut fine = Fmu::start(&swing());
    let mut coarse = Fmu::start(&swing());
    for _ in 0..200 {
        fine.step(0.005);
    }
    for _ in 0..4 {
        coarse.step(0.25);
    }
    let (a, b) = (fine.outputs(), coarse.outputs());
    for k in 0..5 {
        assert!(
            (a[k] - b[k]).abs() < 1e-8,
            "output {k}: {} vs {}",
            a[k],
            b[k]
        );
    }
}

#[test]
fn energy_gain_equals_the_work_of_piecewise_constant_torques() {
    // dE/dt = tau . qd, so with tau held over a step: dE = tau . dq exactly.
    let mut fmu = Fmu::start(&swing());
    let e0 = fmu.outputs()[4];
    let mut work = 0.0;
    for k in 0..500 {
        let tau = [
            3.0 * math::sin(0.37 * k as f64),
            -2.0 * math::cos(0.23 * k as f64),
        ];
        assert_eq!(fmu.set(&[vref("tau[1]"), vref("tau[2]")], &tau), OK);
        let before = fmu.outputs();
        fmu.step(0.01);
        let after = fmu.outputs();
        work += tau[0] * (after[0] - before[0]) + tau[1] * (after[1] - before[1]);
    }
    let gain = fmu.outputs()[4] - e0;
    println!("energy gain {gain:.9} J, work {work:.9} J");
    assert!(gain.abs() > 0.1, "torques did work: {gain}");
    assert!(
        (gain - work).abs() < 1e-8 * e0,
        "gain {gain} vs work {work}"
    );
}

#[test]
fn damping_dissipates_energy() {
    let mut fmu = Fmu::start(&[
        swing()[0],
        swing()[1],
        (vref("damping[1]"), 0.2),
        (vref("damping[2]"), 0.1),
    ]);
    let mut e = fmu.outputs()[4];
    for _ in 0..100 {
        fmu.step(0.05);
        let e_next = fmu.outputs()[4];
        assert!(e_next <= e + 1e-12, "energy rose: {e} -> {e_next}");
        e = e_next;
    }
    assert!(e < 0.7 * Fmu::start(&swing()[..2]).outputs()[4]);
}

#[test]
fn parameters_scale_the_model() {
    // Hanging at rest with q0 = (pi/2, 0): V = g (m1 + m2) l1 + g m2 l2
    let fmu = Fmu::start(&[
        (vref("q0[1]"), std::f64::consts::FRAC_PI_2),
        (vref("m[1]"), 2.0),
        (vref("m[2]"), 0.5),
        (vref("l[1]"), 1.5),
        (vref("l[2]"), 0.8),
        (vref("g"), 3.0),
    ]);
    let expected = 3.0 * 2.5 * 1.5 + 3.0 * 0.5 * 0.8;
    assert!((fmu.outputs()[4] - expected).abs() < 1e-12);
}

#[test]
fn invalid_parameters_and_inputs_are_rejected() {
    for (vr, v, needle) in [
        (vref("m[1]"), 0.0, "m[1] = 0 is below its minimum"),
        (vref("l[2]"), -1.0, "l[2] = -1 is below its minimum"),
        (vref("g"), f64::NAN, "g = NaN is not a finite number"),
        (vref("rtol"), 1.0, "rtol = 1 is above its maximum"),
        (
            vref("tau[1]"),
            f64::INFINITY,
            "tau[1] = inf is not a finite number",
        ),
        (
            vref("q0[1]"),
            f64::NEG_INFINITY,
            "q0[1] = -inf is not a finite number",
        ),
    ] {
        let fmu = Fmu::instantiate();
        assert_eq!(fmu.set(&[vr], &[v]), ERROR);
        assert!(
            fmu.instance.log.contains(&[needle]),
            "{:?}",
            fmu.instance.log.lines()
        );
    }
    let mut fmu = Fmu::start(&[]);
    fmu.step(0.1);
    assert_eq!(
        fmu.set(&[vref("m[1]")], &[2.0]),
        ERROR,
        "fixed parameter in step mode"
    );
    let mut fmu = Fmu::start(&[]);
    fmu.step(0.1);
    assert_eq!(fmu.set(&[vref("energy")], &[2.0]), ERROR, "output");
    assert!(
        fmu.instance
            .log
            .contains(&["energy (value reference 6, causality Output"])
    );
}

#[test]
fn checked_in_model_description_matches_the_table() {
    let d = DoublePendulumFmu::description();
    d.validate().unwrap();
    let generated = xml::model_description_xml(&d);
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../modelDescription/DoublePendulum.xml");
    let checked_in = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        checked_in == generated,
        "{} is out of date with the variable table: run `cargo run --release -p fmu-build -- --update-checked-in` and commit it",
        path.display()
    );
}

/// The identified laboratory pendulum of `shared/robots/lab-double-pendulum-A0.yml`
/// (inertias about the joints, geared motors, viscous and Coulomb friction)
/// plus springs with rest angles: every rigid-link parameter reaches the model.
fn robot_a0() -> Vec<(&'static str, f64)> {
    vec![
        ("m[1]", 0.5593806151425046),
        ("m[2]", 0.6043459469186889),
        ("l[1]", 0.3),
        ("l[2]", 0.2),
        ("r[1]", 0.3),
        ("r[2]", 0.18377686083653508),
        ("I[1]", 0.053470810264216295),
        ("I[2]", 0.02392374528789766),
        ("Ir[1]", 7.659297952841183e-05),
        ("Ir[2]", 7.659297952841183e-05),
        ("gr[1]", 6.0),
        ("gr[2]", 6.0),
        ("b[1]", 0.001),
        ("b[2]", 0.001),
        ("cf[1]", 0.093),
        ("cf[2]", 0.078),
        ("k[1]", 0.3),
        ("k[2]", 0.2),
        ("q_rest[1]", 0.1),
        ("q_rest[2]", -0.2),
        ("g", 9.81),
        ("coulomb_sharpness", 50.0),
    ]
}

fn a0_params() -> eigenmpc::mechanics::PlanarChainParams<2> {
    use eigenmpc::mechanics::{Joint, Link, PlanarChainParams};
    let joint = |b, cf, k, rest| Joint {
        rotor_inertia: 7.659297952841183e-05,
        gear_ratio: 6.0,
        viscous: b,
        coulomb: cf,
        stiffness: k,
        rest_angle: rest,
    };
    PlanarChainParams {
        links: [
            Link::with_inertia_about_joint(0.5593806151425046, 0.3, 0.3, 0.053470810264216295),
            Link::with_inertia_about_joint(
                0.6043459469186889,
                0.2,
                0.18377686083653508,
                0.02392374528789766,
            ),
        ],
        joints: [
            joint(0.001, 0.093, 0.3, 0.1),
            joint(0.001, 0.078, 0.2, -0.2),
        ],
        gravity: 9.81,
        coulomb_sharpness: 50.0,
    }
}

#[test]
fn rigid_link_parameters_give_the_core_model() {
    use eigenmpc::integrate::{Tolerances, simulate_accurate};
    use eigenmpc::mechanics::{PlanarChain, Vector};
    let mut params: Vec<(u32, f64)> = robot_a0().iter().map(|&(n, v)| (vref(n), v)).collect();
    params.extend(swing());
    let mut fmu = Fmu::start(&params);
    let tau = [0.05, -0.03];
    assert_eq!(fmu.set(&[vref("tau[1]"), vref("tau[2]")], &tau), OK);
    let system = PlanarChain::new(a0_params()).unwrap();
    let z0 = nalgebra::SVector::<f64, 4>::from([1.2, -0.7, 0.5, 1.5]);
    // energy at t = 0 is the core's (rotor inertia, COM, springs, V(q_eq) = 0)
    let e0 = eigenmpc::mechanics::state_energy::<_, 2, 4>(&system, &z0);
    assert!(
        (fmu.outputs()[4] - e0).abs() < 1e-14,
        "{} vs {e0}",
        fmu.outputs()[4]
    );
    for _ in 0..100 {
        fmu.step(0.01);
    }
    let z = simulate_accurate::<_, 2, 4>(
        &system,
        &z0,
        &Vector::<2>::from(tau),
        1.0,
        Tolerances::default(),
    )
    .unwrap();
    let out = fmu.outputs();
    println!("A0 robot, 1 s: FMU {out:?}, core {z:?}");
    for k in 0..4 {
        assert!(
            (out[k] - z[k]).abs() < 1e-9,
            "state {k}: {} vs {}",
            out[k],
            z[k]
        );
    }
    // friction took energy: well below the swing's
    assert!(out[4] < e0);
}

#[test]
fn damping_is_an_alias_of_the_viscous_friction() {
    let run = |params: &[(&str, f64)]| {
        let mut p: Vec<(u32, f64)> = params.iter().map(|&(n, v)| (vref(n), v)).collect();
        p.extend(swing());
        let mut fmu = Fmu::start(&p);
        for _ in 0..100 {
            fmu.step(0.05);
        }
        fmu.outputs()
    };
    let by_b = run(&[("b[1]", 0.2), ("b[2]", 0.1)]);
    let by_damping = run(&[("damping[1]", 0.2), ("damping[2]", 0.1)]);
    let both_equal = run(&[("damping[1]", 0.2), ("b[1]", 0.2), ("b[2]", 0.1)]);
    assert_eq!(by_b, by_damping);
    assert_eq!(by_b, both_equal);
    assert!(by_b[4] < 0.7 * Fmu::start(&swing()).outputs()[4]);
    // both set to different values: refused at initialization, naming both
    let fmu = Fmu::instantiate();
    assert_eq!(
        fmu.set(&[vref("b[2]"), vref("damping[2]")], &[0.1, 0.3]),
        OK
    );
    unsafe {
        assert_eq!(fmi2EnterInitializationMode(fmu.c), OK);
        assert_eq!(fmi2ExitInitializationMode(fmu.c), ERROR);
    }
    assert!(
        fmu.instance.log.contains(&[
            "fmi2ExitInitializationMode",
            "b[2] = 0.1 and damping[2] = 0.3"
        ]),
        "{:?}",
        fmu.instance.log.lines()
    );
}

#[test]
fn non_physical_rigid_links_are_refused_naming_the_parameter() {
    // range: refused when set, naming the variable
    for (name, v, needle) in [
        ("I[1]", -2.0, "I[1] = -2 is below its minimum"),
        ("gr[2]", 0.0, "gr[2] = 0 is below its minimum"),
        ("cf[1]", -0.1, "cf[1] = -0.1 is below its minimum"),
        (
            "coulomb_sharpness",
            0.0,
            "coulomb_sharpness = 0 is below its minimum",
        ),
    ] {
        let fmu = Fmu::instantiate();
        assert_eq!(fmu.set(&[vref(name)], &[v]), ERROR);
        assert!(
            fmu.instance.log.contains(&[needle]),
            "{:?}",
            fmu.instance.log.lines()
        );
    }
    // relations: at fmi2ExitInitializationMode with the core's reason
    for (params, needles) in [
        (
            vec![("r[2]", 0.0)],
            vec!["model parameter I[2] = 0 is invalid"],
        ),
        (
            // an inertia about the joint far below m r^2: M(q) not positive definite
            vec![("r[2]", 1.0), ("I[2]", 1e-6)],
            vec![
                "model parameter I[2] = 0.00000100",
                "M(q) is not positive definite",
            ],
        ),
        (vec![("g", 0.0)], vec!["no stable equilibrium"]),
    ] {
        let needles = [vec!["fmi2ExitInitializationMode"], needles].concat();
        let fmu = Fmu::instantiate();
        for (n, v) in params {
            assert_eq!(fmu.set(&[vref(n)], &[v]), OK);
        }
        unsafe {
            assert_eq!(fmi2EnterInitializationMode(fmu.c), OK);
            assert_eq!(fmi2ExitInitializationMode(fmu.c), ERROR, "{needles:?}");
        }
        assert!(
            fmu.instance.log.contains(&needles),
            "{needles:?}: {:?}",
            fmu.instance.log.lines()
        );
    }
}

/// Issue 8: the plant starts from rest (q0 = qd0 = 0) under a nonzero or
/// saturated torque for every tolerance it accepts: the first fmi2DoStep
/// returns fmi2OK, and the state agrees with a tight reference run to the
/// requested accuracy.
#[test]
fn starts_from_rest_for_every_accepted_tolerance() {
    let d = DoublePendulumFmu::description();
    let (lo, hi) = {
        let v = d.variable("rtol").unwrap();
        (v.min.unwrap(), v.max.unwrap())
    };
    assert_eq!((lo, hi), (1e-14, 1e-2));
    assert_eq!(d.variable("atol").unwrap().min, Some(lo));
    assert_eq!(d.variable("atol").unwrap().max, Some(hi));
    let tolerances = [lo, 1e-12, 1e-8, hi];
    let tau_vr = [vref("tau[1]"), vref("tau[2]")];
    let mut worst: f64 = 0.0;
    for tau in [[1.0, -1.0], [1.0, 1.0], [1e-6, 0.0], [0.0, -1e3]] {
        let mut reference = Fmu::start(&[(vref("rtol"), 1e-13), (vref("atol"), 1e-14)]);
        assert_eq!(reference.set(&tau_vr, &tau), OK);
        reference.step(0.025);
        let want = reference.outputs();
        for rtol in tolerances {
            for atol in tolerances {
                let fmu = Fmu::start(&[(vref("rtol"), rtol), (vref("atol"), atol)]);
                assert_eq!(fmu.set(&tau_vr, &tau), OK);
                let status = unsafe { fmi2DoStep(fmu.c, 0.0, 0.025, 1) };
                assert_eq!(
                    status,
                    OK,
                    "tau {tau:?}, rtol {rtol}, atol {atol}: {:?}",
                    fmu.instance.log.lines()
                );
                let got = fmu.outputs();
                for k in 0..4 {
                    let err = (got[k] - want[k]).abs();
                    let allowed = 10.0 * (rtol * want[k].abs() + atol) + 1e-13 * want[k].abs();
                    worst = worst.max(err / allowed);
                    assert!(
                        err <= allowed,
                        "tau {tau:?}, rtol {rtol}, atol {atol}, state {k}: {} vs {}",
                        got[k],
                        want[k]
                    );
                }
                // it moved the way the torque pushes
                assert!(got[2] * tau[0] + got[3] * tau[1] > 0.0);
            }
        }
    }
    println!("start from rest: worst error / allowed = {worst:.2e}");
}

/// A master's tolerance (`fmi2SetupExperiment` with `toleranceDefined`)
/// becomes the integrator's relative tolerance while `rtol` is at its start
/// value (the run equals one with `rtol` set to it); a set `rtol` wins.
/// The default experiment declares the default tolerance.
#[test]
fn the_masters_tolerance_sets_rtol_unless_rtol_was_set() {
    let d = DoublePendulumFmu::description();
    let default_rtol = d.default_experiment.unwrap().tolerance.unwrap();
    assert_eq!(
        d.variable("rtol").unwrap().start,
        Some(fmi2_slave::Value::Real(default_rtol))
    );
    let tau_vr = [vref("tau[1]"), vref("tau[2]")];
    let run = |rtol: Option<f64>, tolerance: Option<f64>| {
        let fmu = Fmu::instantiate();
        if let Some(r) = rtol {
            assert_eq!(fmu.set(&[vref("rtol")], &[r]), OK);
        }
        unsafe {
            let (defined, tol) = tolerance.map_or((0, 0.0), |t| (1, t));
            assert_eq!(fmi2SetupExperiment(fmu.c, defined, tol, 0.0, 0, 0.0), OK);
            assert_eq!(fmi2EnterInitializationMode(fmu.c), OK);
            assert_eq!(fmi2ExitInitializationMode(fmu.c), OK);
        }
        assert_eq!(fmu.set(&tau_vr, &[0.7, -0.4]), OK);
        for k in 0..40 {
            assert_eq!(unsafe { fmi2DoStep(fmu.c, k as f64 * 0.025, 0.025, 1) }, OK);
        }
        fmu.outputs()
    };
    let default = run(None, None);
    let loose = run(None, Some(1e-4));
    let loose_param = run(Some(1e-4), None);
    assert_eq!(loose, loose_param, "the master's tolerance is rtol");
    assert_ne!(
        loose, default,
        "a loose tolerance changes the result (the test can fail)"
    );
    let set = run(Some(1e-10), Some(1e-4));
    let set_alone = run(Some(1e-10), None);
    assert_eq!(
        set, set_alone,
        "a set rtol wins over the master's tolerance"
    );
}

/// A communication step the integrator cannot cover within its step budget
/// is discarded with the reason (bounded work per call), and the instance
/// reports how far it got.
#[test]
fn an_enormous_step_is_discarded_with_bounded_work() {
    let fmu = Fmu::start(&[(vref("q0[1]"), 1.0)]);
    let started = std::time::Instant::now();
    let status = unsafe { fmi2DoStep(fmu.c, 0.0, 1e9, 1) };
    let elapsed = started.elapsed().as_secs_f64();
    assert_eq!(status, ffi::fmi2Status_fmi2Discard);
    assert!(
        fmu.instance
            .log
            .contains(&["at most 100000 integrator steps per fmi2DoStep"]),
        "{:?}",
        fmu.instance.log.lines()
    );
    let mut last = f64::NAN;
    let kind = ffi::fmi2StatusKind_fmi2LastSuccessfulTime;
    assert_eq!(unsafe { fmi2GetRealStatus(fmu.c, kind, &mut last) }, OK);
    assert!(last > 0.0 && last < 1e9, "{last}");
    eprintln!("discarded after {elapsed:.2} s at t = {last:.1} s");
}

/// `fmi2Reset` and the same run again equal a fresh instance bit for bit:
/// the integrator's step size and first-same-as-last stage start afresh.
#[test]
fn reset_then_the_same_run_equals_a_fresh_instance() {
    let run = |fmu: &mut Fmu| -> Vec<[f64; 5]> {
        assert_eq!(fmu.set(&[vref("q0[1]"), vref("b[2]")], &[1.2, 0.03]), OK);
        unsafe {
            assert_eq!(fmi2SetupExperiment(fmu.c, 0, 0.0, 0.0, 0, 0.0), OK);
            assert_eq!(fmi2EnterInitializationMode(fmu.c), OK);
            assert_eq!(fmi2ExitInitializationMode(fmu.c), OK);
        }
        fmu.t = 0.0;
        (0..80)
            .map(|k| {
                let tau = [0.3 * math::sin(k as f64 * 0.1), -0.2];
                assert_eq!(fmu.set(&[vref("tau[1]"), vref("tau[2]")], &tau), OK);
                fmu.step(0.025);
                fmu.outputs()
            })
            .collect()
    };
    let mut fmu = Fmu::instantiate();
    let first = run(&mut fmu);
    assert_eq!(unsafe { fmi2Reset(fmu.c) }, OK);
    let again = run(&mut fmu);
    let new = run(&mut Fmu::instantiate());
    assert_eq!(first, again, "after fmi2Reset");
    assert_eq!(first, new, "a fresh instance");
}

impl Fmu {
    /// `n` steps of `h` with a torque that changes every step (the FSAL
    /// stage is dropped then) or holds (kept): the outputs as bits.
    fn drive(&mut self, n: usize, h: f64) -> Vec<[u64; 5]> {
        let tau = [vref("tau[1]"), vref("tau[2]")];
        (0..n)
            .map(|k| {
                let level = if k % 3 == 0 {
                    0.1 * math::sin(k as f64)
                } else {
                    0.0
                };
                assert_eq!(self.set(&tau, &[level, -0.5 * level]), OK);
                self.step(h);
                self.outputs().map(f64::to_bits)
            })
            .collect()
    }

    fn serialized_state(&self) -> Vec<u8> {
        let mut s: ffi::fmi2FMUstate = ptr::null_mut();
        let mut size = 0;
        unsafe {
            assert_eq!(fmi2GetFMUstate(self.c, &mut s), OK);
            assert_eq!(fmi2SerializedFMUstateSize(self.c, s, &mut size), OK);
            let mut bytes = vec![0u8; size];
            assert_eq!(
                fmi2SerializeFMUstate(self.c, s, bytes.as_mut_ptr() as *mut _, size),
                OK
            );
            assert_eq!(fmi2FreeFMUstate(self.c, &mut s), OK);
            bytes
        }
    }

    fn load_state(&mut self, bytes: &[u8], t: f64) {
        let mut s: ffi::fmi2FMUstate = ptr::null_mut();
        unsafe {
            assert_eq!(
                fmi2DeSerializeFMUstate(self.c, bytes.as_ptr() as *const _, bytes.len(), &mut s),
                OK
            );
            assert_eq!(
                fmi2SetFMUstate(self.c, s),
                OK,
                "{:?}",
                self.instance.log.lines()
            );
            assert_eq!(fmi2FreeFMUstate(self.c, &mut s), OK);
        }
        self.t = t;
    }
}

#[test]
fn a_saved_plant_continues_bit_for_bit_here_and_in_a_fresh_instance() {
    let h = 0.025;
    let mut fmu = Fmu::start(&swing());
    fmu.drive(37, h);
    let (bytes, t) = (fmu.serialized_state(), fmu.t);
    let reference = fmu.drive(80, h);
    fmu.load_state(&bytes, t);
    assert_eq!(fmu.drive(80, h), reference, "same instance");
    let mut fresh = Fmu::instantiate();
    fresh.load_state(&bytes, t);
    assert_eq!(fresh.drive(80, h), reference, "fresh instance");
    // A state from before initialization: the parameters come back too.
    let early = Fmu::instantiate();
    assert_eq!(early.set(&[vref("q0[1]")], &[0.3]), OK);
    let before = early.serialized_state();
    let mut other = Fmu::instantiate();
    other.load_state(&before, 0.0);
    unsafe {
        assert_eq!(fmi2SetupExperiment(other.c, 0, 0.0, 0.0, 0, 0.0), OK);
        assert_eq!(fmi2EnterInitializationMode(other.c), OK);
        assert_eq!(fmi2ExitInitializationMode(other.c), OK);
    }
    assert_eq!(other.outputs()[0], 0.3);
}
