//! The TriplePendulum FMU through its FMI 2.0 C functions: the 3-link
//! chain of the core (energy, work of the torque, rigid links), a start
//! from rest at the tolerance limits, the checked-in model description and
//! the built shared library.

use eigenmpc::integrate::{Tolerances, simulate_accurate};
use eigenmpc::math;
use eigenmpc::mechanics::{Joint, Link, PlanarChain, PlanarChainParams, Vector, state_energy};
use fmi2_slave::testing::TestInstance;
use fmi2_slave::{Model, ffi, xml};
use nalgebra::SVector;
use std::path::PathBuf;
/// The FMU's C functions over the model, as the FMU binary exports them
/// (one model per test binary: the symbols are unmangled).
mod fmi2_exports {
    fmi2_slave::export_fmi2!(eigenmpc_fmu_models::products::TriplePendulumFmu);
}
use eigenmpc_fmu_models::products::TriplePendulumFmu;
use fmi2_exports::*;

const OK: ffi::fmi2Status = ffi::fmi2Status_fmi2OK;

fn vref(name: &str) -> u32 {
    TriplePendulumFmu::description()
        .variable(name)
        .unwrap_or_else(|| panic!("no variable {name}"))
        .value_reference
}

struct Fmu {
    c: ffi::fmi2Component,
    instance: TestInstance,
    t: f64,
}

impl Fmu {
    fn start(params: &[(&str, f64)]) -> Self {
        let instance = TestInstance::new::<TriplePendulumFmu>(Some(fmi2Instantiate), "chain");
        let fmu = Self {
            c: instance.component,
            instance,
            t: 0.0,
        };
        for &(name, v) in params {
            assert_eq!(fmu.set(&[vref(name)], &[v]), OK, "{name}");
        }
        unsafe {
            assert_eq!(fmi2SetupExperiment(fmu.c, 0, 0.0, 0.0, 0, 0.0), OK);
            assert_eq!(fmi2EnterInitializationMode(fmu.c), OK);
            assert_eq!(
                fmi2ExitInitializationMode(fmu.c),
                OK,
                "{:?}",
                fmu.instance.log.lines()
            );
        }
        fmu
    }

    fn set(&self, vr: &[u32], v: &[f64]) -> ffi::fmi2Status {
        unsafe { fmi2SetReal(self.c, vr.as_ptr(), vr.len(), v.as_ptr()) }
    }

    fn set_tau(&self, tau: [f64; 3]) {
        let vr = [vref("tau[1]"), vref("tau[2]"), vref("tau[3]")];
        assert_eq!(self.set(&vr, &tau), OK);
    }

    /// q[1..3], qd[1..3], energy.
    fn outputs(&self) -> [f64; 7] {
        let names = ["q[1]", "q[2]", "q[3]", "qd[1]", "qd[2]", "qd[3]", "energy"];
        let vr: Vec<u32> = names.iter().map(|n| vref(n)).collect();
        let mut v = [f64::NAN; 7];
        assert_eq!(
            unsafe { fmi2GetReal(self.c, vr.as_ptr(), 7, v.as_mut_ptr()) },
            OK
        );
        v
    }

    fn step(&mut self, h: f64) -> ffi::fmi2Status {
        let s = unsafe { fmi2DoStep(self.c, self.t, h, 1) };
        self.t += h;
        s
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        unsafe { fmi2FreeInstance(self.c) }
    }
}

const SWING: [(&str, f64); 6] = [
    ("q0[1]", 0.9),
    ("q0[2]", -0.6),
    ("q0[3]", 0.4),
    ("qd0[1]", 0.3),
    ("qd0[2]", -1.0),
    ("qd0[3]", 1.5),
];

#[test]
fn free_run_conserves_energy_and_torques_do_their_work() {
    let mut fmu = Fmu::start(&SWING);
    let e0 = fmu.outputs()[6];
    let z0 = SVector::<f64, 6>::from([0.9, -0.6, 0.4, 0.3, -1.0, 1.5]);
    let expected = state_energy::<_, 3, 6>(&PlanarChain::<3>::default(), &z0);
    assert!((e0 - expected).abs() < 1e-12, "{e0} vs {expected}");
    let mut worst: f64 = 0.0;
    for _ in 0..2000 {
        assert_eq!(fmu.step(0.01), OK);
        worst = worst.max(((fmu.outputs()[6] - e0) / e0).abs());
    }
    println!("3-link 20 s free run: max relative energy drift {worst:.2e}");
    assert!(worst < 1e-8, "relative energy drift {worst}");
    // dE = tau . dq exactly for torques held over a step (frictionless)
    let mut fmu = Fmu::start(&SWING);
    let mut work = 0.0;
    for k in 0..300 {
        let x = k as f64;
        let tau = [math::sin(0.3 * x), -0.7 * math::cos(0.2 * x), 0.4];
        fmu.set_tau(tau);
        let before = fmu.outputs();
        assert_eq!(fmu.step(0.01), OK);
        let after = fmu.outputs();
        work += (0..3).map(|j| tau[j] * (after[j] - before[j])).sum::<f64>();
    }
    let gain = fmu.outputs()[6] - e0;
    assert!(gain.abs() > 0.05, "torques did work: {gain}");
    assert!(
        (gain - work).abs() < 1e-8 * e0,
        "gain {gain} vs work {work}"
    );
}

#[test]
fn rigid_links_motors_and_friction_give_the_core_model() {
    let params = [
        ("m[1]", 0.8),
        ("m[2]", 0.6),
        ("m[3]", 0.3),
        ("l[1]", 0.4),
        ("l[2]", 0.3),
        ("l[3]", 0.25),
        ("r[1]", 0.2),
        ("r[3]", 0.1),
        ("I[1]", 0.05),
        ("I[2]", 0.04),
        ("Ir[2]", 1e-4),
        ("Ir[3]", 2e-4),
        ("gr[2]", 6.0),
        ("gr[3]", 4.0),
        ("b[1]", 0.002),
        ("cf[3]", 0.01),
        ("k[2]", 0.5),
        ("q_rest[2]", 0.2),
    ];
    let mut all = params.to_vec();
    all.extend(SWING);
    let mut fmu = Fmu::start(&all);
    fmu.set_tau([0.02, -0.01, 0.005]);
    // r[2] at the tip, I[3] a point mass at r[3]: the sentinels
    let links = [
        Link::with_inertia_about_joint(0.8, 0.4, 0.2, 0.05),
        Link::with_inertia_about_joint(0.6, 0.3, 0.3, 0.04),
        Link {
            mass: 0.3,
            length: 0.25,
            com: 0.1,
            inertia: 0.0,
        },
    ];
    let mut joints = [Joint::default(); 3];
    joints[0].viscous = 0.002;
    joints[1].rotor_inertia = 1e-4;
    joints[1].gear_ratio = 6.0;
    joints[1].stiffness = 0.5;
    joints[1].rest_angle = 0.2;
    joints[2].rotor_inertia = 2e-4;
    joints[2].gear_ratio = 4.0;
    joints[2].coulomb = 0.01;
    let system = PlanarChain::new(PlanarChainParams {
        links,
        joints,
        gravity: 9.81,
        coulomb_sharpness: 100.0,
    })
    .unwrap();
    for _ in 0..50 {
        assert_eq!(fmu.step(0.02), OK);
    }
    let z0 = SVector::<f64, 6>::from([0.9, -0.6, 0.4, 0.3, -1.0, 1.5]);
    let z = simulate_accurate::<_, 3, 6>(
        &system,
        &z0,
        &Vector::<3>::new(0.02, -0.01, 0.005),
        1.0,
        Tolerances::default(),
    )
    .unwrap();
    let out = fmu.outputs();
    for k in 0..6 {
        assert!(
            (out[k] - z[k]).abs() < 1e-9,
            "state {k}: {} vs {}",
            out[k],
            z[k]
        );
    }
    let e = state_energy::<_, 3, 6>(&system, &z);
    assert!((out[6] - e).abs() < 1e-9, "{} vs {e}", out[6]);
}

/// From rest under saturated torques the first step succeeds at the limits
/// of the tolerance ranges.
#[test]
fn starts_from_rest_at_the_tolerance_limits() {
    for rtol in [1e-14, 1e-2] {
        for atol in [1e-14, 1e-2] {
            for tau in [[1.0, -1.0, 1.0], [0.0, 0.0, 1e-6]] {
                let mut fmu = Fmu::start(&[("rtol", rtol), ("atol", atol)]);
                fmu.set_tau(tau);
                assert_eq!(
                    fmu.step(0.025),
                    OK,
                    "rtol {rtol}, atol {atol}, tau {tau:?}: {:?}",
                    fmu.instance.log.lines()
                );
                let out = fmu.outputs();
                let power: f64 = (0..3).map(|j| tau[j] * out[3 + j]).sum();
                assert!(power > 0.0 && out.iter().all(|x| x.is_finite()), "{out:?}");
            }
        }
    }
}

#[test]
fn checked_in_model_description_matches_the_table() {
    let d = TriplePendulumFmu::description();
    d.validate().unwrap();
    let generated = xml::model_description_xml(&d);
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../modelDescription/TriplePendulum.xml");
    let checked_in = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        checked_in == generated,
        "{} is out of date with the variable table: run `cargo run --release -p fmu-build -- --update-checked-in` and commit it",
        path.display()
    );
}
