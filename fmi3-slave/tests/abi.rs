//! The FMI 3.0 plumbing driven through the C functions `export_fmi3!`
//! generates for the chain of masses (tests/common): life cycle, arrays in
//! row-major order, refused values, call order, tunables, FMU state, null
//! pointers and panics.

mod common;

use common::*;
use fmi3_slave::layout::{BOOLEAN_VR_OFFSET, INTEGER_VR_OFFSET, TIME_VALUE_REFERENCE};
use fmi3_slave::testing::LogCapture;
use fmi3_slave::{Model, ffi, instance::instantiation_token};
use std::ffi::CString;
use std::ptr;

mod exports {
    fmi3_slave::export_fmi3!(crate::common::Chain);
}
use exports::*;

const OK: ffi::fmi3Status = ffi::fmi3Status_fmi3OK;
const ERROR: ffi::fmi3Status = ffi::fmi3Status_fmi3Error;

// FMI 3.0 value references of the chain.
const INT_STEPS: u32 = INTEGER_VR_OFFSET + STEPS;
const INT_PANIC_AT: u32 = INTEGER_VR_OFFSET + PANIC_AT;
const ENUM_INTEGRATOR: u32 = INTEGER_VR_OFFSET + INTEGRATOR;
const BOOL_HOLD: u32 = BOOLEAN_VR_OFFSET + HOLD;

/// A call on an instance, for tables of cases.
type Call = Box<dyn Fn(&Fmu) -> ffi::fmi3Status>;

/// The outputs of one `fmi3DoStep`.
#[derive(Debug, PartialEq)]
struct Step {
    status: ffi::fmi3Status,
    event_handling_needed: bool,
    terminate: bool,
    early_return: bool,
    last_successful_time: f64,
}

/// An instance with its log capture (freed on drop).
struct Fmu {
    c: ffi::fmi3Instance,
    log: Box<LogCapture>,
}

fn token() -> String {
    instantiation_token(&Chain::description())
}

fn instantiate(
    token: &str,
    event_mode_used: bool,
    early_return_allowed: bool,
    log: &LogCapture,
) -> ffi::fmi3Instance {
    let name = CString::new("chain").unwrap();
    let token = CString::new(token).unwrap();
    let resources = CString::new("/nonexistent/resources/").unwrap();
    unsafe {
        fmi3InstantiateCoSimulation(
            name.as_ptr(),
            token.as_ptr(),
            resources.as_ptr(),
            false,
            false,
            event_mode_used,
            early_return_allowed,
            ptr::null(),
            0,
            log.environment(),
            log.callback(),
            None,
        )
    }
}

impl Fmu {
    fn new() -> Self {
        let log = LogCapture::new();
        let c = instantiate(&token(), false, false, &log);
        assert!(!c.is_null(), "instantiate: {:?}", log.lines());
        Self { c, log }
    }

    fn enter(&self) -> ffi::fmi3Status {
        unsafe { fmi3EnterInitializationMode(self.c, false, 0.0, 0.0, true, 10.0) }
    }

    fn init(&self) {
        assert_eq!(self.enter(), OK);
        assert_eq!(unsafe { fmi3ExitInitializationMode(self.c) }, OK);
    }

    fn set(&self, vr: &[u32], v: &[f64]) -> ffi::fmi3Status {
        unsafe { fmi3SetFloat64(self.c, vr.as_ptr(), vr.len(), v.as_ptr(), v.len()) }
    }

    fn get(&self, vr: &[u32], n: usize) -> (ffi::fmi3Status, Vec<f64>) {
        let mut v = vec![f64::NAN; n];
        let s = unsafe { fmi3GetFloat64(self.c, vr.as_ptr(), vr.len(), v.as_mut_ptr(), n) };
        (s, v)
    }

    fn real(&self, vr: u32) -> f64 {
        let (s, v) = self.get(&[vr], 1);
        assert_eq!(s, OK, "{:?}", self.log.lines());
        v[0]
    }

    fn array(&self, vr: u32) -> [f64; N] {
        let (s, v) = self.get(&[vr], N);
        assert_eq!(s, OK, "{:?}", self.log.lines());
        v.try_into().unwrap()
    }

    fn int32(&self, vr: u32) -> (ffi::fmi3Status, i32) {
        let mut v = -99;
        let s = unsafe { fmi3GetInt32(self.c, &vr, 1, &mut v, 1) };
        (s, v)
    }

    fn step(&self, t: f64, h: f64) -> Step {
        let (mut e, mut term, mut early, mut last) = (true, true, true, f64::NAN);
        let status = unsafe {
            fmi3DoStep(
                self.c, t, h, false, &mut e, &mut term, &mut early, &mut last,
            )
        };
        Step {
            status,
            event_handling_needed: e,
            terminate: term,
            early_return: early,
            last_successful_time: last,
        }
    }

    /// Positions and velocities as bits (for bit-identity).
    fn bits(&self) -> Vec<u64> {
        let (s, v) = self.get(&[X, V, ENERGY], 2 * N + 1);
        assert_eq!(s, OK);
        v.iter().map(|x| x.to_bits()).collect()
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        unsafe { fmi3FreeInstance(self.c) }
    }
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + b.abs())
}

#[test]
fn version() {
    let v = unsafe { std::ffi::CStr::from_ptr(fmi3GetVersion()) };
    assert_eq!(v.to_str().unwrap(), "3.0");
}

#[test]
fn life_cycle_with_arrays_in_row_major_order() {
    let fmu = Fmu::new();
    // init[j, c]: row-major, c (position, velocity) runs fastest.
    let init = [0.1, 0.5, -0.2, 0.0, 0.3, -0.4];
    assert_eq!(fmu.set(&[INIT], &init), OK);
    assert_eq!(fmu.enter(), OK);
    // Outputs are computed in Initialization Mode from the parameters.
    assert_eq!(fmu.array(X), [0.1, -0.2, 0.3]);
    assert_eq!(fmu.array(V), [0.5, 0.0, -0.4]);
    assert_eq!(fmu.real(TIME_VALUE_REFERENCE), 0.0);
    assert_eq!(unsafe { fmi3ExitInitializationMode(fmu.c) }, OK);
    let f = [1.0, -2.0, 0.5];
    assert_eq!(fmu.set(&[F], &f), OK);
    let (s, back) = fmu.get(&[F], N);
    assert_eq!((s, back.as_slice()), (OK, &f[..]));

    // One step against the same integrator written out here.
    let h = 0.01;
    let step = fmu.step(0.0, h);
    assert_eq!(
        step,
        Step {
            status: OK,
            event_handling_needed: false,
            terminate: false,
            early_return: false,
            last_successful_time: h,
        }
    );
    let (k, m) = (100.0, 1.0);
    let mut x = [0.1, -0.2, 0.3];
    let mut v = [0.5, 0.0, -0.4];
    let a = accelerations(&x, &f, k, m);
    for j in 0..N {
        v[j] += h * a[j];
        x[j] += h * v[j];
    }
    let (gx, gv) = (fmu.array(X), fmu.array(V));
    for j in 0..N {
        assert!(close(gx[j], x[j], 1e-14), "x[{j}] {} vs {}", gx[j], x[j]);
        assert!(close(gv[j], v[j], 1e-14), "v[{j}] {} vs {}", gv[j], v[j]);
    }
    // Several variables in one call: the arrays' values follow each other.
    let (s, all) = fmu.get(&[V, ENERGY, X], 2 * N + 1);
    assert_eq!(s, OK);
    assert_eq!(&all[..N], &gv[..]);
    assert!(close(all[N], energy(&x, &v, k, m), 1e-14));
    assert_eq!(&all[N + 1..], &gx[..]);

    // Unforced, symplectic Euler keeps the energy within O(h omega) of
    // its start, without drift (omega < omega_max = 2 sqrt(k / m)).
    assert_eq!(fmu.set(&[F], &[0.0; N]), OK);
    let e0 = fmu.real(ENERGY);
    let h2 = 0.002;
    let bound = h2 * 2.0 * (k / m).sqrt();
    let mut t = h;
    let mut worst: f64 = 0.0;
    for _ in 0..1000 {
        assert_eq!(fmu.step(t, h2).status, OK);
        t += h2;
        worst = worst.max((fmu.real(ENERGY) - e0).abs() / e0);
    }
    assert!(
        worst < bound,
        "relative energy error {worst} (bound {bound})"
    );
    assert!(worst > 1e-6, "the chain moved ({worst})");
    assert!(close(
        fmu.real(TIME_VALUE_REFERENCE),
        h + 1000.0 * h2,
        1e-12
    ));
    assert_eq!(fmu.int32(INT_STEPS), (OK, 1001));

    // Hold: the chain stands still, the step counter runs on.
    let x_before = fmu.array(X);
    assert_eq!(
        unsafe { fmi3SetBoolean(fmu.c, &BOOL_HOLD, 1, [true].as_ptr(), 1) },
        OK
    );
    assert_eq!(fmu.step(t, h2).status, OK);
    t += h2;
    assert_eq!(fmu.array(X), x_before);
    let mut b = [false];
    assert_eq!(
        unsafe { fmi3GetBoolean(fmu.c, &BOOL_HOLD, 1, b.as_mut_ptr(), 1) },
        OK
    );
    assert!(b[0]);
    assert_eq!(unsafe { fmi3Terminate(fmu.c) }, OK);
    assert_eq!(fmu.array(X), x_before, "outputs readable after terminate");
    assert_eq!(fmu.step(t, h2).status, ERROR);
}

#[test]
fn enumeration_through_int64_and_the_explicit_integrator() {
    let fmu = Fmu::new();
    let mut e = 0i64;
    assert_eq!(fmu.enter(), OK);
    assert_eq!(
        unsafe { fmi3GetInt64(fmu.c, &ENUM_INTEGRATOR, 1, &mut e, 1) },
        OK
    );
    assert_eq!(e, SYMPLECTIC as i64);
    assert_eq!(
        unsafe { fmi3SetInt64(fmu.c, &ENUM_INTEGRATOR, 1, &(EXPLICIT as i64), 1) },
        OK
    );
    assert_eq!(unsafe { fmi3ExitInitializationMode(fmu.c) }, OK);
    let (h, f) = (0.02, [0.0, 0.0, 3.0]);
    assert_eq!(fmu.set(&[F], &f), OK);
    let mut x = [0.1, 0.2, 0.3];
    let mut v = [0.0; N];
    let mut t = 0.0;
    for _ in 0..50 {
        assert_eq!(fmu.step(t, h).status, OK);
        t += h;
        step(&mut x, &mut v, &f, 100.0, 1.0, h, EXPLICIT);
    }
    let gx = fmu.array(X);
    for j in 0..N {
        assert!(close(gx[j], x[j], 1e-12), "x[{j}] {} vs {}", gx[j], x[j]);
    }
}

#[test]
fn out_of_range_values_are_refused_and_the_old_values_kept() {
    let fmu = Fmu::new();
    fmu.init();
    assert_eq!(fmu.set(&[F], &[1.0, 2.0, 3.0]), OK);
    // NaN in the middle of the array: nothing of the call is stored.
    assert_eq!(fmu.set(&[F], &[7.0, f64::NAN, 9.0]), ERROR);
    assert!(fmu.log.contains(&["f[2]", "not a finite number"]));
    assert_eq!(fmu.array(F), [1.0, 2.0, 3.0], "readable in the error state");

    let fmu = Fmu::new();
    assert_eq!(fmu.set(&[K], &[-1.0]), ERROR);
    assert!(fmu.log.contains(&["k = -1 is below its minimum 0"]));
    assert_eq!(unsafe { fmi3Reset(fmu.c) }, OK);
    assert_eq!(fmu.enter(), OK);
    assert_eq!(fmu.real(K), 100.0);
    assert_eq!(
        unsafe { fmi3SetInt64(fmu.c, &ENUM_INTEGRATOR, 1, &7, 1) },
        ERROR
    );
    assert!(fmu.log.contains(&["integrator = 7 is above its maximum 2"]));

    let fmu = Fmu::new();
    assert_eq!(fmu.enter(), OK);
    let big = i64::from(i32::MAX) + 1;
    assert_eq!(
        unsafe { fmi3SetInt64(fmu.c, &ENUM_INTEGRATOR, 1, &big, 1) },
        ERROR
    );
    assert!(fmu.log.contains(&["2147483648 is not an item"]));
    let mut e = 0i64;
    assert_eq!(
        unsafe { fmi3GetInt64(fmu.c, &ENUM_INTEGRATOR, 1, &mut e, 1) },
        OK
    );
    assert_eq!(e, SYMPLECTIC as i64);
}

#[test]
fn wrong_calls_are_refused_with_a_reason() {
    let fmu = Fmu::new();
    assert_eq!(fmu.step(0.0, 0.1).status, ERROR);
    assert!(
        fmu.log
            .contains(&["fmi3DoStep", "not allowed in Instantiated"])
    );
    // In the error state only getters, state functions, reset and free.
    assert_eq!(fmu.enter(), ERROR);
    assert_eq!(unsafe { fmi3Reset(fmu.c) }, OK);
    fmu.init();
    assert_eq!(unsafe { fmi3EnterEventMode(fmu.c) }, ERROR);
    assert!(
        fmu.log
            .contains(&["fmi3EnterEventMode", "hasEventMode is false"])
    );
    let cases: Vec<(&str, Call, &[&str])> = vec![
        (
            "fixed parameter in Step Mode",
            Box::new(|f| f.set(&[MASS], &[2.0])),
            &["mass", "cannot be set in Step Mode"],
        ),
        (
            "output",
            Box::new(|f| f.set(&[X], &[0.0; N])),
            &["x (value reference 3", "cannot be set"],
        ),
        (
            "nValues not the element count",
            Box::new(|f| f.set(&[F], &[0.0; 2])),
            &["nValues = 2", "have 3 values"],
        ),
        (
            "inner array element reference",
            Box::new(|f| f.set(&[F + 1], &[0.0])),
            &["unknown value reference 1"],
        ),
        (
            "wrong type",
            Box::new(|f| f.int32(K).0),
            &["k (value reference 9) is a Float64 variable"],
        ),
        (
            "enumeration through Int32",
            Box::new(|f| f.int32(ENUM_INTEGRATOR).0),
            &["integrator", "Enumeration variable (fmi3GetInt64"],
        ),
        (
            "time",
            Box::new(|f| f.set(&[TIME_VALUE_REFERENCE], &[1.0])),
            &["time", "independent variable"],
        ),
        (
            "step size",
            Box::new(|f| f.step(0.0, 0.0).status),
            &["communicationStepSize = 0 must be finite and > 0"],
        ),
        (
            "communication point",
            Box::new(|f| f.step(0.5, 0.1).status),
            &["currentCommunicationPoint = 0.5 differs from the FMU's time 0"],
        ),
        (
            "configuration mode",
            Box::new(|f| unsafe { fmi3EnterConfigurationMode(f.c) }),
            &["no structural parameters"],
        ),
        (
            "model exchange function",
            Box::new(|f| unsafe { fmi3SetTime(f.c, 1.0) }),
            &["fmi3SetTime", "Model Exchange"],
        ),
        (
            "step mode of event mode",
            Box::new(|f| unsafe { fmi3EnterStepMode(f.c) }),
            &["fmi3EnterStepMode", "hasEventMode is false"],
        ),
    ];
    for (what, call, needles) in cases {
        let fmu = Fmu::new();
        fmu.init();
        assert_eq!(call(&fmu), ERROR, "{what}");
        assert!(fmu.log.contains(needles), "{what}: {:?}", fmu.log.lines());
    }
}

#[test]
fn tunable_parameter_between_steps_and_a_rejected_change_rolled_back() {
    let fmu = Fmu::new();
    fmu.init();
    let h = 0.05;
    assert_eq!(fmu.step(0.0, h).status, OK);
    // m / h^2 = 400: k = 200 is stable and taken over.
    assert_eq!(fmu.set(&[K], &[200.0]), OK);
    assert!(fmu.log.lines().iter().all(|l| l.status != ERROR));
    let x = fmu.array(X);
    let v = fmu.array(V);
    assert_eq!(fmu.step(h, h).status, OK);
    let (mut xe, mut ve) = (x, v);
    step(&mut xe, &mut ve, &[0.0; N], 200.0, 1.0, h, SYMPLECTIC);
    let gx = fmu.array(X);
    for j in 0..N {
        assert!(close(gx[j], xe[j], 1e-14), "stepped with k = 200");
    }
    // k = 500 would be unstable: refused by the model, the value restored.
    assert_eq!(fmu.set(&[K], &[500.0]), ERROR);
    assert!(
        fmu.log
            .contains(&["tunable parameter change rejected", "k = 500"])
    );
    assert_eq!(fmu.real(K), 200.0);
}

#[test]
fn state_save_and_restore_continue_bit_identically() {
    let fmu = Fmu::new();
    fmu.init();
    assert_eq!(fmu.set(&[F], &[0.5, 0.0, -1.0]), OK);
    let h = 0.01;
    let mut t = 0.0;
    for _ in 0..10 {
        assert_eq!(fmu.step(t, h).status, OK);
        t += h;
    }
    let mut state: ffi::fmi3FMUState = ptr::null_mut();
    assert_eq!(unsafe { fmi3GetFMUState(fmu.c, &mut state) }, OK);
    assert!(!state.is_null());
    let t_saved = t;
    let run = |fmu: &Fmu, mut t: f64| {
        for n in 0..10 {
            if n == 5 {
                assert_eq!(fmu.set(&[F], &[0.0, 2.0, 0.0]), OK);
            }
            assert_eq!(fmu.step(t, h).status, OK);
            t += h;
        }
        fmu.bits()
    };
    let first = run(&fmu, t_saved);
    assert_eq!(unsafe { fmi3SetFMUState(fmu.c, state) }, OK);
    assert_eq!(fmu.real(TIME_VALUE_REFERENCE), t_saved);
    assert_eq!(fmu.array(F), [0.5, 0.0, -1.0], "inputs restored too");
    assert_eq!(run(&fmu, t_saved), first, "bit-identical after restore");

    // Serialized, and deserialized into a fresh instance.
    let mut size = 0usize;
    assert_eq!(
        unsafe { fmi3SerializedFMUStateSize(fmu.c, state, &mut size) },
        OK
    );
    assert!(size > 0);
    let mut bytes = vec![0u8; size];
    assert_eq!(
        unsafe { fmi3SerializeFMUState(fmu.c, state, bytes.as_mut_ptr(), size) },
        OK
    );
    let other = Fmu::new();
    let mut copy: ffi::fmi3FMUState = ptr::null_mut();
    assert_eq!(
        unsafe { fmi3DeserializeFMUState(other.c, bytes.as_ptr(), size, &mut copy) },
        OK
    );
    assert_eq!(unsafe { fmi3SetFMUState(other.c, copy) }, OK);
    assert_eq!(
        run(&other, t_saved),
        first,
        "bit-identical in another instance"
    );
    assert_eq!(other.int32(INT_STEPS), (OK, 20));

    // A corrupt buffer is refused with the reason.
    bytes[size - 1] ^= 0x40;
    let mut bad: ffi::fmi3FMUState = ptr::null_mut();
    assert_eq!(
        unsafe { fmi3DeserializeFMUState(other.c, bytes.as_ptr(), size, &mut bad) },
        ERROR
    );
    assert!(other.log.contains(&["checksum mismatch"]));
    assert!(bad.is_null());

    for s in [&mut state, &mut copy] {
        assert_eq!(unsafe { fmi3FreeFMUState(fmu.c, s) }, OK);
        assert!(s.is_null());
    }
}

#[test]
fn null_pointers_and_panics_do_not_cross_the_abi() {
    let null: ffi::fmi3Instance = ptr::null_mut();
    unsafe {
        assert_eq!(
            fmi3EnterInitializationMode(null, false, 0.0, 0.0, false, 0.0),
            ERROR
        );
        assert_eq!(
            fmi3DoStep(
                null,
                0.0,
                0.1,
                false,
                ptr::null_mut(),
                ptr::null_mut(),
                ptr::null_mut(),
                ptr::null_mut()
            ),
            ERROR
        );
        assert_eq!(
            fmi3GetFloat64(null, ptr::null(), 0, ptr::null_mut(), 0),
            ERROR
        );
        assert_eq!(fmi3SetDebugLogging(null, true, 0, ptr::null()), ERROR);
        assert_eq!(fmi3GetFMUState(null, ptr::null_mut()), ERROR);
        fmi3FreeInstance(null);
    }
    // Instantiation with NULL arguments returns NULL and says why.
    let log = LogCapture::new();
    let c = unsafe {
        fmi3InstantiateCoSimulation(
            ptr::null(),
            ptr::null(),
            ptr::null(),
            false,
            false,
            false,
            false,
            ptr::null(),
            0,
            log.environment(),
            log.callback(),
            None,
        )
    };
    assert!(c.is_null());
    assert!(log.contains(&["instanceName is NULL"]));
    let c = unsafe {
        fmi3InstantiateCoSimulation(
            c"x".as_ptr(),
            ptr::null(),
            ptr::null(),
            false,
            false,
            false,
            false,
            ptr::null(),
            0,
            ptr::null_mut(),
            None,
            None,
        )
    };
    assert!(c.is_null(), "no token, no logger: still no crash");

    let cases: Vec<(&str, Call)> = vec![
        (
            "valueReferences",
            Box::new(|f| unsafe { fmi3GetFloat64(f.c, ptr::null(), 1, [0.0].as_mut_ptr(), 1) }),
        ),
        (
            "values",
            Box::new(|f| unsafe { fmi3SetFloat64(f.c, &F, 1, ptr::null(), 3) }),
        ),
        (
            "values",
            Box::new(|f| unsafe { fmi3GetBoolean(f.c, &BOOL_HOLD, 1, ptr::null_mut(), 1) }),
        ),
        (
            "eventHandlingNeeded",
            Box::new(|f| unsafe {
                let (mut b, mut t) = (false, 0.0);
                fmi3DoStep(
                    f.c,
                    0.0,
                    0.1,
                    false,
                    ptr::null_mut(),
                    &mut b,
                    &mut b,
                    &mut t,
                )
            }),
        ),
        (
            "lastSuccessfulTime",
            Box::new(|f| unsafe {
                let (mut a, mut b, mut e) = (false, false, false);
                fmi3DoStep(
                    f.c,
                    0.0,
                    0.1,
                    false,
                    &mut a,
                    &mut b,
                    &mut e,
                    ptr::null_mut(),
                )
            }),
        ),
        (
            "FMUState",
            Box::new(|f| unsafe { fmi3GetFMUState(f.c, ptr::null_mut()) }),
        ),
        (
            "FMUState",
            Box::new(|f| unsafe { fmi3SetFMUState(f.c, ptr::null_mut()) }),
        ),
        (
            "size",
            Box::new(|f| unsafe {
                let mut s: ffi::fmi3FMUState = ptr::null_mut();
                fmi3GetFMUState(f.c, &mut s);
                let r = fmi3SerializedFMUStateSize(f.c, s, ptr::null_mut());
                fmi3FreeFMUState(f.c, &mut s);
                r
            }),
        ),
        (
            "serializedState",
            Box::new(|f| unsafe {
                let mut s: ffi::fmi3FMUState = ptr::null_mut();
                fmi3DeserializeFMUState(f.c, ptr::null(), 10, &mut s)
            }),
        ),
        (
            "categories",
            Box::new(|f| unsafe { fmi3SetDebugLogging(f.c, true, 2, ptr::null()) }),
        ),
        (
            "values",
            Box::new(|f| unsafe { fmi3GetString(f.c, &F, 1, ptr::null_mut(), 1) }),
        ),
    ];
    for (what, call) in cases {
        let fmu = Fmu::new();
        fmu.init();
        assert_eq!(call(&fmu), ERROR, "{what}");
        assert!(
            fmu.log.contains(&[what, "NULL"]),
            "{what}: {:?}",
            fmu.log.lines()
        );
    }

    // A panic in the model is fmi3Error with the message, and the
    // instance can be reset and run again.
    let fmu = Fmu::new();
    assert_eq!(unsafe { fmi3SetInt32(fmu.c, &INT_PANIC_AT, 1, &1, 1) }, OK);
    fmu.init();
    assert_eq!(fmu.step(0.0, 0.1).status, OK);
    assert_eq!(fmu.step(0.1, 0.1).status, ERROR);
    assert!(
        fmu.log
            .contains(&["fmi3DoStep: internal error: deliberate test panic"])
    );
    assert_eq!(unsafe { fmi3Reset(fmu.c) }, OK);
    fmu.init();
    assert_eq!(fmu.step(0.0, 0.1).status, OK);
}

#[test]
fn types_without_variables() {
    let fmu = Fmu::new();
    fmu.init();
    unsafe {
        assert_eq!(
            fmi3GetFloat32(fmu.c, ptr::null(), 0, ptr::null_mut(), 0),
            OK
        );
        assert_eq!(fmi3SetUInt64(fmu.c, ptr::null(), 0, ptr::null(), 0), OK);
        assert_eq!(fmi3GetClock(fmu.c, ptr::null(), 0, ptr::null_mut()), OK);
        assert_eq!(
            fmi3GetBinary(fmu.c, ptr::null(), 0, ptr::null_mut(), ptr::null_mut(), 0),
            OK
        );
    }
    let mut x = 0f32;
    assert_eq!(unsafe { fmi3GetFloat32(fmu.c, &X, 1, &mut x, 1) }, ERROR);
    assert!(
        fmu.log
            .contains(&["x (value reference 3) is a Float64 variable, not Float32"])
    );

    let fmu = Fmu::new();
    fmu.init();
    let mut c = false;
    assert_eq!(unsafe { fmi3GetClock(fmu.c, &777, 1, &mut c) }, ERROR);
    assert!(
        fmu.log
            .contains(&["unknown value reference 777 (this FMU has no Clock variables)"])
    );

    let fmu = Fmu::new();
    let s = c"text".as_ptr();
    assert_eq!(unsafe { fmi3SetString(fmu.c, &5, 1, &s, 1) }, ERROR);
    assert!(fmu.log.contains(&["no String variables"]));
}

#[test]
fn instantiation_is_checked() {
    let log = LogCapture::new();
    assert!(instantiate("{not-the-token}", false, false, &log).is_null());
    assert!(log.contains(&["instantiationToken {not-the-token} does not match"]));

    let log = LogCapture::new();
    assert!(instantiate(&token(), true, false, &log).is_null());
    assert!(log.contains(&["eventModeUsed = true", "hasEventMode = false"]));

    // earlyReturnAllowed is accepted; steps never return early.
    let log = LogCapture::new();
    let c = instantiate(&token(), false, true, &log);
    assert!(!c.is_null());
    unsafe { fmi3FreeInstance(c) };

    // Model Exchange and Scheduled Execution: NULL with the reason.
    let log = LogCapture::new();
    let c = unsafe {
        fmi3InstantiateModelExchange(
            c"me".as_ptr(),
            ptr::null(),
            ptr::null(),
            false,
            false,
            log.environment(),
            log.callback(),
        )
    };
    assert!(c.is_null());
    assert!(log.contains(&["fmi3InstantiateModelExchange", "Co-Simulation only"]));
    let c = unsafe {
        fmi3InstantiateScheduledExecution(
            c"se".as_ptr(),
            ptr::null(),
            ptr::null(),
            false,
            false,
            log.environment(),
            log.callback(),
            None,
            None,
            None,
        )
    };
    assert!(c.is_null());
}

#[test]
fn debug_logging_categories() {
    let fmu = Fmu::new();
    let cats = [c"logAll".as_ptr()];
    assert_eq!(
        unsafe { fmi3SetDebugLogging(fmu.c, true, 1, cats.as_ptr()) },
        OK
    );
    fmu.init();
    assert_eq!(fmu.step(0.0, 0.25).status, OK);
    let trace = fmu.log.lines();
    assert!(
        trace.iter().any(|l| l.category == "logAll"
            && l.message.contains(
                "fmi3DoStep(currentCommunicationPoint = 0, communicationStepSize = 0.25)"
            )),
        "{trace:?}"
    );
    // Only events: no more call traces.
    let cats = [c"logEvents".as_ptr()];
    assert_eq!(
        unsafe { fmi3SetDebugLogging(fmu.c, true, 1, cats.as_ptr()) },
        OK
    );
    fmu.log.clear();
    assert_eq!(fmu.step(0.25, 0.25).status, OK);
    assert_eq!(unsafe { fmi3Terminate(fmu.c) }, OK);
    let lines = fmu.log.lines();
    assert!(lines.iter().all(|l| l.category == "logEvents"), "{lines:?}");
    assert!(lines.iter().any(|l| l.message == "terminated"));

    let bad = [c"logNothing".as_ptr()];
    assert_eq!(
        unsafe { fmi3SetDebugLogging(fmu.c, true, 1, bad.as_ptr()) },
        ERROR
    );
    assert!(fmu.log.contains(&["unknown log category \"logNothing\""]));
}

#[test]
fn a_discarded_step_asks_to_terminate() {
    let fmu = Fmu::new();
    fmu.init();
    assert_eq!(fmu.step(0.0, 0.1).status, OK);
    // 1e6 N on the last mass moves it by about 1e6 h^2 = 1e4 m in a step.
    assert_eq!(fmu.set(&[F], &[0.0, 0.0, 1e6]), OK);
    let x = fmu.array(X);
    let s = fmu.step(0.1, 0.1);
    assert_eq!(s.status, ffi::fmi3Status_fmi3Discard);
    assert!(s.terminate, "terminateSimulation after a discarded step");
    assert_eq!(s.last_successful_time, 0.1);
    assert!(!s.early_return && !s.event_handling_needed);
    assert_eq!(fmu.array(X), x, "outputs of the last successful time");
    assert_eq!(fmu.real(TIME_VALUE_REFERENCE), 0.1);
    // Only terminate (or reset, or a saved state) after a discard.
    assert_eq!(fmu.step(0.1, 0.1).status, ERROR);
    assert!(
        fmu.log
            .contains(&["not allowed in Step Mode after a discarded step"])
    );

    // After an error, the outputs of the step keep the last successful time.
    let fmu = Fmu::new();
    fmu.init();
    assert_eq!(fmu.step(0.0, 0.1).status, OK);
    let s = fmu.step(0.0, 0.1);
    assert_eq!(s.status, ERROR);
    assert_eq!(s.last_successful_time, 0.1);
}
