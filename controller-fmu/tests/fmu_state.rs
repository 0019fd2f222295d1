//! FMU state of the controller: a state saved in a closed loop continues
//! bit for bit in the same instance, in another instance and from its
//! serialized bytes (with adaptation, the EKF, a declared measurement delay
//! and actuator lag and a wrong plant, so that the plan, the warm start,
//! the filter, the command history, the identification and an adapted
//! model and family are all part of it).

use eigenmpc::integrate::{Dopri5, Tolerances};
use eigenmpc::mechanics::{PlanarChain, PlanarChainParams, Vector, state_derivative};
use eigenmpc_fmu::fmi2_exports::*;
use eigenmpc_fmu::*;
use fmi2_slave::testing::TestInstance;
use fmi2_slave::{Model, ffi};
use nalgebra::SVector;
use std::ptr;

const OK: ffi::fmi2Status = ffi::fmi2Status_fmi2OK;
const ERROR: ffi::fmi2Status = ffi::fmi2Status_fmi2Error;
const DT: f64 = 0.025;

fn vref(name: &str) -> u32 {
    EigenMpcFmu::description()
        .variable(name)
        .unwrap_or_else(|| panic!("no variable {name}"))
        .value_reference
}

fn state_vrs() -> [u32; 4] {
    [vref("q[1]"), vref("q[2]"), vref("qd[1]"), vref("qd[2]")]
}

/// Outputs compared bit for bit after each step: torques, energy, the
/// estimate, the model count and the solver status.
fn output_vrs() -> Vec<u32> {
    let d = EigenMpcFmu::description();
    let mut vrs = vec![vref("tau[1]"), vref("tau[2]"), vref("energy")];
    vrs.extend(
        d.variables
            .iter()
            .filter(|v| v.name.starts_with("estimate.") || v.name.starts_with("chart_energy"))
            .map(|v| v.value_reference),
    );
    vrs
}

/// The wrong plant of the adaptation tests (m2 +20 %, l1 +10 %, damping).
fn plant() -> PlanarChain<2> {
    let mut p = PlanarChainParams::<2>::point_masses([1.0, 1.2], [1.1, 1.0], 9.81);
    p.joints[0].viscous = 0.05;
    p.joints[1].viscous = 0.05;
    PlanarChain::new(p).unwrap()
}

/// A controller instance in a closed loop with the plant.
struct Loop {
    fmu: TestInstance,
    ode: Dopri5<SVector<f64, 4>>,
    t: f64,
}

type Trace = Vec<(Vec<u64>, i32, i32)>;

impl Loop {
    fn instantiate() -> TestInstance {
        TestInstance::new::<EigenMpcFmu>(Some(fmi2Instantiate), "controller")
    }

    fn start(qp_solver: i32) -> Self {
        let fmu = Self::instantiate();
        let c = fmu.component;
        let z0 = [0.05, 0.05, 0.0, 0.0];
        unsafe {
            let on = 1;
            assert_eq!(fmi2SetBoolean(c, &vref("adapt"), 1, &on), OK);
            let ekf = STATE_ESTIMATOR_EKF;
            assert_eq!(fmi2SetInteger(c, &vref("state_estimator"), 1, &ekf), OK);
            assert_eq!(fmi2SetInteger(c, &vref("qp_solver"), 1, &qp_solver), OK);
            // A declared delay (fractional) and lag: the command history
            // is part of the state.
            let (delay, lag) = (0.0625, 0.05);
            assert_eq!(fmi2SetReal(c, &vref("measurement_delay"), 1, &delay), OK);
            assert_eq!(fmi2SetReal(c, &vref("actuator_time_constant"), 1, &lag), OK);
            assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), OK);
            assert_eq!(fmi2EnterInitializationMode(c), OK);
            assert_eq!(fmi2SetReal(c, state_vrs().as_ptr(), 4, z0.as_ptr()), OK);
            assert_eq!(fmi2ExitInitializationMode(c), OK, "{:?}", fmu.log.lines());
        }
        let tol = Tolerances {
            rtol: 1e-10,
            atol: 1e-10,
        };
        Self {
            fmu,
            ode: Dopri5::new(0.0, SVector::from(z0), tol),
            t: 0.0,
        }
    }

    /// `samples` closed-loop samples: the outputs after each, as bits.
    fn run(&mut self, samples: usize) -> Trace {
        let c = self.fmu.component;
        let plant = plant();
        let outputs = output_vrs();
        let mut trace = vec![];
        for _ in 0..samples {
            let z = *self.ode.state();
            let mut out = vec![0.0; outputs.len()];
            let (mut updates, mut status) = (0, 0);
            unsafe {
                if self.t > 0.0 {
                    assert_eq!(fmi2SetReal(c, state_vrs().as_ptr(), 4, z.as_ptr()), OK);
                }
                assert_eq!(fmi2DoStep(c, self.t, DT, 1), OK);
                assert_eq!(
                    fmi2GetReal(c, outputs.as_ptr(), outputs.len(), out.as_mut_ptr()),
                    OK
                );
                assert_eq!(
                    fmi2GetInteger(c, &vref("model_updates"), 1, &mut updates),
                    OK
                );
                assert_eq!(
                    fmi2GetInteger(c, &vref("solver_status"), 1, &mut status),
                    OK
                );
            }
            let tau = Vector::<2>::new(out[0], out[1]);
            self.t += DT;
            self.ode
                .advance_to(|_, z| state_derivative::<_, 2, 4>(&plant, z, &tau), self.t)
                .unwrap();
            trace.push((out.iter().map(|v| v.to_bits()).collect(), updates, status));
        }
        trace
    }

    fn save(&self) -> ffi::fmi2FMUstate {
        let mut s: ffi::fmi2FMUstate = ptr::null_mut();
        assert_eq!(unsafe { fmi2GetFMUstate(self.fmu.component, &mut s) }, OK);
        s
    }
}

fn serialize(c: ffi::fmi2Component, s: ffi::fmi2FMUstate) -> Vec<u8> {
    let mut size = 0;
    unsafe {
        assert_eq!(fmi2SerializedFMUstateSize(c, s, &mut size), OK);
        let mut bytes = vec![0u8; size];
        assert_eq!(
            fmi2SerializeFMUstate(c, s, bytes.as_mut_ptr() as *mut _, size),
            OK
        );
        bytes
    }
}

#[test]
fn a_saved_controller_continues_bit_for_bit_here_elsewhere_and_from_bytes() {
    // Both QP backends: riccati's warm start is part of the state; clarabel
    // keeps none between solves.
    for qp_solver in [QP_SOLVER_RICCATI, QP_SOLVER_CLARABEL] {
        continues_bit_for_bit(qp_solver);
    }
}

fn continues_bit_for_bit(qp_solver: i32) {
    // When the first model is taken (after the climb): the state is saved
    // a second before, while that candidate is validated and its model
    // computed (a request in flight).
    let taken = Loop::start(qp_solver)
        .run(1600)
        .iter()
        .position(|s| s.1 > 0)
        .expect("a model is taken within 40 s");
    let mut first = Loop::start(qp_solver);
    first.run(taken - 40);
    let saved = first.save();
    let (t, ode) = (first.t, first.ode.clone());
    let reference = first.run(240);
    let updates_before = reference[0].1;
    // The model posted at the look before the save is taken after it.
    assert!(
        reference.last().unwrap().1 > updates_before,
        "no model taken after the save: the test would not cover a request in flight"
    );

    // The same instance, after running on.
    unsafe { assert_eq!(fmi2SetFMUstate(first.fmu.component, saved), OK) };
    first.t = t;
    first.ode = ode.clone();
    assert_eq!(first.run(240), reference, "same instance");

    // The serialized bytes in a fresh instance (the model is rebuilt).
    let bytes = serialize(first.fmu.component, saved);
    let fresh = Loop::instantiate();
    let mut loaded: ffi::fmi2FMUstate = ptr::null_mut();
    unsafe {
        assert_eq!(
            fmi2DeSerializeFMUstate(
                fresh.component,
                bytes.as_ptr() as *const _,
                bytes.len(),
                &mut loaded
            ),
            OK
        );
        assert_eq!(
            fmi2SetFMUstate(fresh.component, loaded),
            OK,
            "{:?}",
            fresh.log.lines()
        );
    }
    let mut second = Loop { fmu: fresh, ode, t };
    assert_eq!(second.run(240), reference, "fresh instance from bytes");
    // Its own state serializes to the same bytes as the saved one.
    assert_eq!(serialize(second.fmu.component, loaded), bytes);

    unsafe {
        let mut s = saved;
        assert_eq!(fmi2FreeFMUstate(first.fmu.component, &mut s), OK);
        assert_eq!(fmi2FreeFMUstate(second.fmu.component, &mut loaded), OK);
    }
}

#[test]
fn a_state_of_another_set_up_or_fmu_is_refused() {
    let mut running = Loop::start(QP_SOLVER_RICCATI);
    running.run(4);
    let saved = running.save();
    let bytes = serialize(running.fmu.component, saved);
    // The plant FMU's bytes are another FMU's (GUID).
    let other = TestInstance::new::<EigenMpcFmu>(Some(fmi2Instantiate), "other");
    let mut foreign = bytes.clone();
    let at = 14; // first GUID byte
    foreign[at] = if foreign[at] == b'0' { b'1' } else { b'0' };
    let mut s: ffi::fmi2FMUstate = ptr::null_mut();
    unsafe {
        assert_eq!(
            fmi2DeSerializeFMUstate(
                other.component,
                foreign.as_ptr() as *const _,
                foreign.len(),
                &mut s
            ),
            ERROR
        );
    }
    assert!(other.log.contains(&["saved by the FMU with GUID"]));
    let mut s = saved;
    unsafe { assert_eq!(fmi2FreeFMUstate(running.fmu.component, &mut s), OK) };
}
