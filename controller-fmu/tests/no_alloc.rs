//! Real-time discipline through the exported functions: once initialized,
//! the per-sample path of the EigenMPC FMU (fmi2SetReal inputs, fmi2DoStep,
//! fmi2GetReal / fmi2GetInteger outputs) and of the plain C API
//! (`eigenmpc_step`, `eigenmpc_last_step`) performs no heap allocation.
//!
//! Its own test binary: the global allocator counts the allocations of the
//! thread that switched counting on, so other tests cannot interfere.

use eigenmpc::integrate::rk4_step;
use eigenmpc::mechanics::{DoublePendulum, Vector};
use eigenmpc_fmu::capi::*;
use eigenmpc_fmu::fmi2_exports::*;
use eigenmpc_fmu::*;
use fmi2_slave::testing::LogCapture;
use fmi2_slave::{Model, ffi, xml};
use nalgebra::SVector;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::ffi::CString;
use std::ptr;

/// Counts allocations (alloc, alloc_zeroed, realloc) made while the calling
/// thread's `COUNTING` flag is set.
struct CountingAllocator;

thread_local! {
    // const-initialized Cells: reading them never allocates.
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn note() {
    // `try_with`: during thread teardown the locals may be gone.
    let _ = COUNTING.try_with(|c| {
        if c.get() {
            let _ = ALLOCATIONS.try_with(|n| n.set(n.get() + 1));
        }
    });
}

// SAFETY: forwards to the system allocator unchanged.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note();
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note();
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, p: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note();
        unsafe { System.realloc(p, layout, new_size) }
    }
    unsafe fn dealloc(&self, p: *mut u8, layout: Layout) {
        unsafe { System.dealloc(p, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

/// Value reference of `name` in the FMU's variable table.
fn vref(name: &str) -> u32 {
    EigenMpcFmu::description()
        .variable(name)
        .unwrap_or_else(|| panic!("no variable {name}"))
        .value_reference
}

/// Runs `f` with counting on; returns its result and the allocations it made.
fn counted<T>(f: impl FnOnce() -> T) -> (T, usize) {
    ALLOCATIONS.with(|n| n.set(0));
    COUNTING.with(|c| c.set(true));
    let r = f();
    COUNTING.with(|c| c.set(false));
    (r, ALLOCATIONS.with(|n| n.get()))
}

const OK: ffi::fmi2Status = ffi::fmi2Status_fmi2OK;
const Z0: [f64; 4] = [0.05, 0.05, 0.0, 0.0];
const DT: f64 = 0.025;
const SAMPLES: usize = 200;

/// The plant between samples (outside the counted region).
fn plant_step(z: &SVector<f64, 4>, tau: [f64; 2]) -> SVector<f64, 4> {
    let sys = DoublePendulum::default();
    let tau = Vector::<2>::from(tau);
    let mut z = *z;
    for _ in 0..5 {
        z = rk4_step::<_, 2, 4>(&sys, &z, &tau, DT / 5.0);
    }
    z
}

#[test]
fn the_counter_sees_allocations() {
    let (v, n) = counted(|| vec![1.0_f64; 8]);
    assert_eq!((v.len(), n), (8, 1));
}

#[test]
fn fmu_sample_path_does_not_allocate() {
    let log = LogCapture::new();
    let callbacks = Box::new(log.callbacks());
    let name = CString::new("no_alloc").unwrap();
    let guid = CString::new(xml::guid(&EigenMpcFmu::description())).unwrap();
    let state_vr = [vref("q[1]"), vref("q[2]"), vref("qd[1]"), vref("qd[2]")];
    let out_vr = [
        vref("tau[1]"),
        vref("tau[2]"),
        vref("energy"),
        vref("solve_time"),
    ];
    let int_vr = [vref("qp_iterations"), vref("solver_status")];
    let mut z = SVector::<f64, 4>::from(Z0);
    unsafe {
        let c = fmi2Instantiate(
            name.as_ptr(),
            ffi::fmi2Type_fmi2CoSimulation,
            guid.as_ptr(),
            ptr::null(),
            &*callbacks,
            0,
            0, // logging off: the host's default
        );
        assert!(!c.is_null());
        assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), OK);
        assert_eq!(fmi2EnterInitializationMode(c), OK);
        assert_eq!(fmi2SetReal(c, state_vr.as_ptr(), 4, z.as_ptr()), OK);
        assert_eq!(fmi2ExitInitializationMode(c), OK);
        let mut out = [f64::NAN; 4];
        let mut ints = [-1; 2];
        let mut t = 0.0;
        let mut worst = 0;
        let mut energy = 0.0;
        for k in 0..SAMPLES {
            let (statuses, n) = counted(|| {
                [
                    fmi2SetReal(c, state_vr.as_ptr(), 4, z.as_ptr()),
                    fmi2DoStep(c, t, DT, 1),
                    fmi2GetReal(c, out_vr.as_ptr(), 4, out.as_mut_ptr()),
                    fmi2GetInteger(c, int_vr.as_ptr(), 2, ints.as_mut_ptr()),
                ]
            });
            assert_eq!(statuses, [OK; 4], "sample {k}: {:?}", log.lines());
            assert_eq!(ints[1], STATUS_SOLVED, "sample {k}");
            assert!(ints[0] > 0 && out[3] > 0.0, "sample {k}: a solve happened");
            worst = worst.max(n);
            assert_eq!(n, 0, "sample {k}: {n} allocations in the FMU's sample path");
            energy = out[2];
            t += DT;
            z = plant_step(&z, [out[0], out[1]]);
        }
        // The loop really pumps energy (the controller is not idling).
        assert!(energy > 1.0, "energy {energy} J after {SAMPLES} samples");
        assert_eq!(worst, 0);
        assert!(log.lines().is_empty(), "{:?}", log.lines());
        fmi2FreeInstance(c);
    }
}

#[test]
fn c_api_step_does_not_allocate() {
    let config = eigenmpc_config_default(VARIANT_CURVED);
    let mut z = SVector::<f64, 4>::from(Z0);
    unsafe {
        let mpc = eigenmpc_create(&config, ptr::null(), ptr::null_mut(), 0);
        assert!(!mpc.is_null());
        let mut tau = [f64::NAN; 2];
        let mut info = EigenMpcStepInfo {
            status: -5,
            qp_iterations: 0,
            solve_time: 0.0,
            energy: f64::NAN,
            model_updates: 0,
            adapt_refused: 0,
            adapt_reverts: 0,
            adaptation_status: 0,
            supervisor_events: 0,
        };
        for k in 0..SAMPLES {
            let ((status, last), n) = counted(|| {
                (
                    eigenmpc_step(mpc, z.as_ptr(), tau.as_mut_ptr()),
                    eigenmpc_last_step(mpc, &mut info),
                )
            });
            assert_eq!((status, last), (STATUS_SOLVED, 0), "sample {k}");
            assert!(info.qp_iterations > 0, "sample {k}: a solve happened");
            assert_eq!(n, 0, "sample {k}: {n} allocations in eigenmpc_step");
            z = plant_step(&z, tau);
        }
        assert!(info.energy > 1.0, "energy {} J", info.energy);
        eigenmpc_free(mpc);
    }
}

/// With `adapt` (real-time: never waiting for the worker), the steps that
/// feed the identification, post a new model and swap it in allocate
/// nothing either: the worker thread builds the model and its family.
#[test]
fn c_api_step_with_adaptation_does_not_allocate() {
    let mut config = eigenmpc_config_default(VARIANT_CURVED);
    config.adapt = 1;
    config.adapt_realtime = 1;
    config.adapt_period = 0.25;
    // a plant the model does not know: 10 % longer links
    let plant = eigenmpc::mechanics::PlanarChain::new(
        eigenmpc::mechanics::PlanarChainParams::point_masses([1.0, 1.0], [1.1, 1.1], 9.81),
    )
    .unwrap();
    let mut z = SVector::<f64, 4>::new(1.0, 0.5, 0.0, 0.0);
    unsafe {
        let mpc = eigenmpc_create(&config, ptr::null(), ptr::null_mut(), 0);
        assert!(!mpc.is_null());
        let mut tau = [f64::NAN; 2];
        let mut info = EigenMpcStepInfo::default();
        // Models are taken once the loop is steady (issue 19): run until one
        // was swapped in and watched for 10 s more (the supervisor's path).
        let mut taken_at = None;
        for k in 0..8000 {
            let (status, n) = counted(|| eigenmpc_step(mpc, z.as_ptr(), tau.as_mut_ptr()));
            assert!(status >= 0, "sample {k}");
            assert_eq!(n, 0, "sample {k}: {n} allocations in eigenmpc_step");
            z = rk4_step::<_, 2, 4>(&plant, &z, &Vector::<2>::from(tau), 0.025);
            // the worker gets time to compute, as in real time
            std::thread::sleep(std::time::Duration::from_micros(200));
            assert_eq!(eigenmpc_last_step(mpc, &mut info), 0);
            if info.model_updates > 0 && taken_at.is_none() {
                taken_at = Some(k);
            }
            if taken_at.is_some_and(|t| k > t + 400) {
                break;
            }
        }
        assert!(info.model_updates > 0, "a model was swapped in");
        eigenmpc_free(mpc);
    }
}
