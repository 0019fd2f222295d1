//! The DoublePendulum FMU through its FMI 2.0 C functions: physics (energy
//! conservation, work of the torque, damping), independence from the
//! communication step, parameter checks, the checked-in model description,
//! and the built shared library (exported symbols, dynamic loading).

use double_pendulum_fmu::fmi2_exports::*;
use double_pendulum_fmu::*;
use fmi2_slave::testing::{LogCapture, TestInstance};
use fmi2_slave::{Model, ffi, xml};
use std::ffi::CString;
use std::path::PathBuf;
use std::ptr;

const OK: ffi::fmi2Status = ffi::fmi2Status_fmi2OK;
const ERROR: ffi::fmi2Status = ffi::fmi2Status_fmi2Error;
const OUTPUTS: [u32; 5] = [VR_Q1, VR_Q2, VR_QD1, VR_QD2, VR_ENERGY];

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
            unsafe { fmi2GetReal(self.c, OUTPUTS.as_ptr(), 5, v.as_mut_ptr()) },
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

const SWING: [(u32, f64); 4] = [
    (VR_Q0_1, 1.2),
    (VR_Q0_2, -0.7),
    (VR_QD0_1, 0.5),
    (VR_QD0_2, 1.5),
];

#[test]
fn free_run_of_60_s_conserves_energy() {
    let mut fmu = Fmu::start(&SWING);
    let e0 = fmu.outputs()[4];
    // E0 from the paper's formula: V = g (m1 + m2) l1 (1 - cos q1) + g m2 l2 (1 - cos(q1 + q2)), T = 1/2 qd'M qd
    let (q1, q2, w1, w2) = (1.2f64, -0.7f64, 0.5f64, 1.5f64);
    let v = 9.81 * 2.0 * (1.0 - q1.cos()) + 9.81 * (1.0 - (q1 + q2).cos());
    let m = [
        [3.0 + 2.0 * q2.cos(), 1.0 + q2.cos()],
        [1.0 + q2.cos(), 1.0],
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
    let mut fine = Fmu::start(&SWING);
    let mut coarse = Fmu::start(&SWING);
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
    let mut fmu = Fmu::start(&SWING);
    let e0 = fmu.outputs()[4];
    let mut work = 0.0;
    for k in 0..500 {
        let tau = [
            3.0 * (0.37 * k as f64).sin(),
            -2.0 * (0.23 * k as f64).cos(),
        ];
        assert_eq!(fmu.set(&[VR_TAU1, VR_TAU2], &tau), OK);
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
    let mut fmu = Fmu::start(&[SWING[0], SWING[1], (VR_DAMPING1, 0.2), (VR_DAMPING2, 0.1)]);
    let mut e = fmu.outputs()[4];
    for _ in 0..100 {
        fmu.step(0.05);
        let e_next = fmu.outputs()[4];
        assert!(e_next <= e + 1e-12, "energy rose: {e} -> {e_next}");
        e = e_next;
    }
    assert!(e < 0.7 * Fmu::start(&SWING[..2]).outputs()[4]);
}

#[test]
fn parameters_scale_the_model() {
    // Hanging at rest with q0 = (pi/2, 0): V = g (m1 + m2) l1 + g m2 l2
    let fmu = Fmu::start(&[
        (VR_Q0_1, std::f64::consts::FRAC_PI_2),
        (VR_M1, 2.0),
        (VR_M2, 0.5),
        (VR_L1, 1.5),
        (VR_L2, 0.8),
        (VR_G, 3.0),
    ]);
    let expected = 3.0 * 2.5 * 1.5 + 3.0 * 0.5 * 0.8;
    assert!((fmu.outputs()[4] - expected).abs() < 1e-12);
}

#[test]
fn invalid_parameters_and_inputs_are_rejected() {
    for (vr, v, needle) in [
        (VR_M1, 0.0, "m[1] = 0 is below its minimum"),
        (VR_L2, -1.0, "l[2] = -1 is below its minimum"),
        (VR_G, f64::NAN, "g = NaN is not a finite number"),
        (VR_RTOL, 1.0, "rtol = 1 is above its maximum"),
        (
            VR_TAU1,
            f64::INFINITY,
            "tau[1] = inf is not a finite number",
        ),
        (
            VR_Q0_1,
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
        fmu.set(&[VR_M1], &[2.0]),
        ERROR,
        "fixed parameter in step mode"
    );
    let mut fmu = Fmu::start(&[]);
    fmu.step(0.1);
    assert_eq!(fmu.set(&[VR_ENERGY], &[2.0]), ERROR, "output");
    assert!(
        fmu.instance
            .log
            .contains(&["energy (value reference 6, causality Output"])
    );
}

/// The plant's cdylib built for this test run.
fn library() -> PathBuf {
    fmi2_slave::testing::test_cdylib("double_pendulum_fmu")
}

#[test]
fn shared_library_exports_all_34_functions() {
    fmi2_slave::testing::assert_exports_fmi2_cs(&library());
}

#[test]
fn loaded_library_runs_like_the_linked_model() {
    // dlopen the cdylib as a host does and compare with the in-process run.
    let lib = unsafe { ffi::Fmi2Binding::new(library()) }.expect("load the FMU library");
    let log = LogCapture::new();
    let callbacks = log.callbacks();
    let name = CString::new("loaded").unwrap();
    let guid = CString::new(xml::guid(&DoublePendulumFmu::description())).unwrap();
    let mut linked = Fmu::start(&SWING);
    unsafe {
        let instantiate = lib.fmi2Instantiate.as_ref().unwrap();
        let c = instantiate(
            name.as_ptr(),
            1,
            guid.as_ptr(),
            ptr::null(),
            &callbacks,
            0,
            0,
        );
        assert!(!c.is_null());
        let set = lib.fmi2SetReal.as_ref().unwrap();
        for (vr, v) in SWING {
            assert_eq!(set(c, &vr, 1, &v), OK);
        }
        assert_eq!(lib.fmi2EnterInitializationMode.as_ref().unwrap()(c), OK);
        assert_eq!(lib.fmi2ExitInitializationMode.as_ref().unwrap()(c), OK);
        let step = lib.fmi2DoStep.as_ref().unwrap();
        let mut t = 0.0;
        for _ in 0..100 {
            assert_eq!(step(c, t, 0.01, 1), OK);
            t += 0.01;
            linked.step(0.01);
        }
        let mut v = [0.0; 5];
        assert_eq!(
            lib.fmi2GetReal.as_ref().unwrap()(c, OUTPUTS.as_ptr(), 5, v.as_mut_ptr()),
            OK
        );
        assert_eq!(v, linked.outputs());
        // an error through the loaded library is logged and reported
        assert_eq!(step(c, 5.0, 0.01, 1), ERROR);
        assert!(log.contains(&["differs from the FMU's time"]));
        lib.fmi2FreeInstance.as_ref().unwrap()(c);
    }
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
        "{} is out of date with the variable table: run `cargo run -p fmu-build` and commit it",
        path.display()
    );
}
