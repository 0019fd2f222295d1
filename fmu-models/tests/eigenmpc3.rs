//! The EigenMPC3 FMU through its FMI 2.0 C functions: it solves like the
//! library's controller, drives the 3-link chain onto its in-phase
//! eigenmode and goes nearly torque-free, takes the start values of
//! `start_values`, refuses non-physical models naming the parameter; the
//! checked-in model description and the built shared library.

use eigenmpc::integrate::{Tolerances, simulate_accurate};
use eigenmpc::mechanics::{PlanarChain, PlanarChainParams, Vector, state_energy};
use eigenmpc::mpc::Variant;
use eigenmpc::mpc::closed_loop::{distance_to_path, mode_and_chart, run};
use eigenmpc_fmu_models::controller::ControllerProduct;
use eigenmpc_fmu_models::controller::start_values::start_values;
/// The FMU's C functions over the model, as the FMU binary exports them
/// (one model per test binary: the symbols are unmangled).
mod fmi2_exports {
    fmi2_slave::export_fmi2!(eigenmpc_fmu_models::products::EigenMpc3Fmu);
}
use eigenmpc_fmu_models::products::{EigenMpc3, EigenMpc3Fmu};
use fmi2_exports::*;
use fmi2_slave::testing::TestInstance;
use fmi2_slave::{Model, Value, ffi, xml};
use nalgebra::SVector;
use std::path::PathBuf;

const OK: ffi::fmi2Status = ffi::fmi2Status_fmi2OK;
const ERROR: ffi::fmi2Status = ffi::fmi2Status_fmi2Error;
const DT: f64 = 0.025;
const Z0: [f64; 6] = [0.05, 0.05, 0.05, 0.0, 0.0, 0.0];

fn vref(name: &str) -> u32 {
    EigenMpc3Fmu::description()
        .variable(name)
        .unwrap_or_else(|| panic!("no variable {name}"))
        .value_reference
}

fn state_vr() -> [u32; 6] {
    ["q[1]", "q[2]", "q[3]", "qd[1]", "qd[2]", "qd[3]"].map(vref)
}

struct Fmu {
    c: ffi::fmi2Component,
    instance: TestInstance,
    t: f64,
}

impl Fmu {
    fn instantiate() -> Self {
        let instance = TestInstance::new::<EigenMpc3Fmu>(Some(fmi2Instantiate), "controller3");
        Self {
            c: instance.component,
            instance,
            t: 0.0,
        }
    }

    /// Instantiated, start values set, initialized at `z0`; the status of
    /// fmi2ExitInitializationMode.
    fn start(values: &[(String, Value)], z0: [f64; 6]) -> (Self, ffi::fmi2Status) {
        let fmu = Self::instantiate();
        for (name, v) in values {
            let status = match v {
                Value::Real(x) => fmu.set(&[vref(name)], &[*x]),
                Value::Integer(i) => unsafe { fmi2SetInteger(fmu.c, &vref(name), 1, i) },
                Value::Boolean(_) => unreachable!("no Boolean variables"),
            };
            assert_eq!(status, OK, "{name}: {:?}", fmu.instance.log.lines());
        }
        let status = unsafe {
            assert_eq!(fmi2SetupExperiment(fmu.c, 0, 0.0, 0.0, 0, 0.0), OK);
            assert_eq!(fmi2EnterInitializationMode(fmu.c), OK);
            assert_eq!(fmu.set(&state_vr(), &z0), OK);
            fmi2ExitInitializationMode(fmu.c)
        };
        (fmu, status)
    }

    fn set(&self, vr: &[u32], v: &[f64]) -> ffi::fmi2Status {
        unsafe { fmi2SetReal(self.c, vr.as_ptr(), vr.len(), v.as_ptr()) }
    }

    fn tau(&self) -> [f64; 3] {
        let vr = ["tau[1]", "tau[2]", "tau[3]"].map(vref);
        let mut v = [f64::NAN; 3];
        assert_eq!(
            unsafe { fmi2GetReal(self.c, vr.as_ptr(), 3, v.as_mut_ptr()) },
            OK
        );
        v
    }

    fn step(&mut self, z: &SVector<f64, 6>) -> [f64; 3] {
        assert_eq!(self.set(&state_vr(), z.as_slice()), OK);
        let status = unsafe { fmi2DoStep(self.c, self.t, DT, 1) };
        assert_eq!(status, OK, "{:?}", self.instance.log.lines());
        self.t += DT;
        self.tau()
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        unsafe { fmi2FreeInstance(self.c) }
    }
}

#[test]
fn solves_like_the_library_controller() {
    let mut controller = EigenMpc3::settings(Variant::Curved).build::<6>().unwrap();
    let native = run(
        &mut controller,
        &PlanarChain::<3>::default(),
        &SVector::from(Z0),
        0.5,
    )
    .unwrap();
    let (mut fmu, status) = Fmu::start(&[], Z0);
    assert_eq!(status, OK);
    assert_eq!(
        fmu.tau().to_vec(),
        native[0].tau.as_slice(),
        "first solve at init"
    );
    // the step from t_k with the state at t_k outputs the torque of t_k
    for (k, sample) in native.iter().enumerate() {
        let tau = fmu.step(&sample.state);
        assert_eq!(tau.to_vec(), sample.tau.as_slice(), "sample {k}");
    }
}

/// The 3-link curved controller against the 3-link chain (Dormand-Prince,
/// torque held over each 25 ms sample), from q = 0.05 rad at rest, E_ref =
/// 14 J: reaches the 5 % band and ends nearly torque-free.
#[test]
fn drives_the_three_link_chain_onto_its_eigenmode() {
    let plant = PlanarChain::<3>::default();
    let (mut fmu, status) = Fmu::start(&[], Z0);
    assert_eq!(status, OK);
    let mut z = SVector::<f64, 6>::from(Z0);
    let (mut energies, mut torques, mut path) = (vec![], vec![], vec![]);
    let seconds = 60.0;
    let samples = (seconds / DT).round() as usize;
    for _ in 0..samples {
        // master: the state at t_k in, step the controller, hold its torque over [t_k, t_k+1]
        let tau = fmu.step(&z);
        torques.push(tau);
        z = simulate_accurate::<_, 3, 6>(
            &plant,
            &z,
            &Vector::<3>::from(tau),
            DT,
            Tolerances::default(),
        )
        .unwrap();
        energies.push(state_energy::<_, 3, 6>(&plant, &z));
        path.push(Vector::<3>::new(z[0], z[1], z[2]));
    }
    let band = energies
        .iter()
        .rposition(|e| (e - 14.0).abs() > 0.7)
        .map_or(0.0, |i| (i + 1) as f64 * DT);
    let last = samples - (5.0 / DT) as usize;
    let rms: Vec<f64> = (0..3)
        .map(|j| {
            (torques[last..].iter().map(|t| t[j] * t[j]).sum::<f64>() / (samples - last) as f64)
                .sqrt()
        })
        .collect();
    let final_e = *energies.last().unwrap();
    let (mode, _) = mode_and_chart::<_, 3, 6>(&plant, 0, 14.0, 9).unwrap();
    let distance = (path[last..]
        .iter()
        .map(|q| distance_to_path(q, &mode.path).powi(2))
        .sum::<f64>()
        / (samples - last) as f64)
        .sqrt();
    println!(
        "3-link curved 14 J: 5 % band for good at {band:.3} s, final E {final_e:.4} J, RMS tau \
         last 5 s {rms:.4?} N m, RMS distance to the mode last 5 s {distance:.4} rad"
    );
    assert!(distance < 0.02, "distance to the mode {distance}");
    assert!(band > 0.0 && band < 50.0, "5 % band at {band} s");
    assert!((final_e - 14.0).abs() < 0.2, "final energy {final_e}");
    assert!(rms.iter().all(|&r| r < 0.03), "RMS torque {rms:?}");
}

#[test]
fn start_values_of_a_robot_load_and_build_its_controller() {
    // a 3-link chain of uneven point masses, its mode at 9 J
    let params = PlanarChainParams::<3>::point_masses([1.2, 0.8, 0.5], [0.9, 0.7, 0.6], 9.81);
    let system = PlanarChain::new(params).unwrap();
    let (_, chart) = mode_and_chart::<_, 3, 6>(&system, 0, 9.0, 7).unwrap();
    let c: [f64; 3] = chart.eigenvector.into();
    let values = start_values(&params, 9.0, &c, &chart.coefficients).unwrap();
    let names: Vec<&str> = values.iter().map(|(n, _)| n.as_str()).collect();
    for name in [
        "E_ref", "m[3]", "l[1]", "g", "r[2]", "I[1]", "gr[3]", "cf[2]", "c[3]",
    ] {
        assert!(names.contains(&name), "{name} in {names:?}");
    }
    // E_ref, the model, c[j], the chart and chart_source = parameters
    assert_eq!(names.len(), 1 + (10 * 3 + 2) + 3 + 30 + 1);
    assert!(
        names.contains(&"chart.coef[3,9]"),
        "zero-padded to 10 powers"
    );
    let (fmu, status) = Fmu::start(&values, Z0);
    assert_eq!(status, OK, "{:?}", fmu.instance.log.lines());
    let instance = unsafe { &*(fmu.c as *const fmi2_slave::Instance<EigenMpc3Fmu>) };
    let model = instance.model().unwrap();
    assert_eq!(model.controller().system().params(), &params);
    assert_eq!(model.controller().config().cost.e_ref, 9.0);
    // a chart of another mode is refused, naming the mismatch
    let mut wrong = c;
    wrong.swap(0, 1);
    let err = start_values(&params, 9.0, &wrong, &chart.coefficients).unwrap_err();
    assert!(err.contains("do not belong together"), "{err}");
}

#[test]
fn non_physical_models_are_refused_naming_the_parameter() {
    let (fmu, status) = Fmu::start(&[("r[3]".to_string(), Value::Real(0.0))], Z0);
    assert_eq!(status, ERROR);
    assert!(
        fmu.instance.log.contains(&[
            "fmi2ExitInitializationMode",
            "model parameter I[3] = 0 is invalid"
        ]),
        "{:?}",
        fmu.instance.log.lines()
    );
    let fmu = Fmu::instantiate();
    assert_eq!(fmu.set(&[vref("gr[2]")], &[-1.0]), ERROR);
    assert!(
        fmu.instance
            .log
            .contains(&["gr[2] = -1 is below its minimum"])
    );
    // a zero eigenvector, when the reference comes from the parameters
    let mut zero: Vec<(String, Value)> = ["c[1]", "c[2]", "c[3]"]
        .map(|n| (n.to_string(), Value::Real(0.0)))
        .into();
    zero.push((
        "chart_source".into(),
        Value::Integer(eigenmpc_fmu_models::enums::CHART_SOURCE_PARAMETERS),
    ));
    let (fmu, status) = Fmu::start(&zero, Z0);
    assert_eq!(status, ERROR);
    assert!(fmu.instance.log.contains(&["eigenvector c = (0, 0, 0)"]));
}

#[test]
fn checked_in_model_description_matches_the_table() {
    let d = EigenMpc3Fmu::description();
    d.validate().unwrap();
    let generated = xml::model_description_xml(&d);
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../modelDescription/EigenMPC3.xml");
    let checked_in = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        checked_in == generated,
        "{} is out of date with the variable table: run `cargo run --release -p fmu-build -- --update-checked-in` and commit it",
        path.display()
    );
}
