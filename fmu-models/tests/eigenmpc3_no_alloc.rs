//! Real-time discipline of the 3-joint controller: once initialized, the
//! per-sample path (fmi2SetReal inputs, fmi2DoStep, fmi2GetReal /
//! fmi2GetInteger outputs) performs no heap allocation. Its own test binary:
//! the global allocator counts the allocations of the thread that switched
//! counting on.

use eigenmpc::integrate::rk4_step;
use eigenmpc::mechanics::{PlanarChain, Vector};
/// The FMU's C functions over the model, as the FMU binary exports them
/// (one model per test binary: the symbols are unmangled).
mod fmi2_exports {
    fmi2_slave::export_fmi2!(eigenmpc_fmu_models::products::EigenMpc3Fmu);
}
use eigenmpc_fmu_models::products::EigenMpc3Fmu;
use fmi2_exports::*;
use fmi2_slave::testing::TestInstance;
use fmi2_slave::{Model, ffi};
use nalgebra::SVector;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct CountingAllocator;

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn note() {
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

fn counted<T>(f: impl FnOnce() -> T) -> (T, usize) {
    ALLOCATIONS.with(|n| n.set(0));
    COUNTING.with(|c| c.set(true));
    let r = f();
    COUNTING.with(|c| c.set(false));
    (r, ALLOCATIONS.with(|n| n.get()))
}

const OK: ffi::fmi2Status = ffi::fmi2Status_fmi2OK;
const DT: f64 = 0.025;

fn vref(name: &str) -> u32 {
    EigenMpc3Fmu::description()
        .variable(name)
        .unwrap_or_else(|| panic!("no variable {name}"))
        .value_reference
}

#[test]
fn the_counter_sees_allocations() {
    let (v, n) = counted(|| vec![1.0_f64; 8]);
    assert_eq!((v.len(), n), (8, 1));
}

#[test]
fn fmu_sample_path_does_not_allocate() {
    let fmu = TestInstance::new::<EigenMpc3Fmu>(Some(fmi2Instantiate), "no_alloc");
    let c = fmu.component;
    let state_vr = ["q[1]", "q[2]", "q[3]", "qd[1]", "qd[2]", "qd[3]"].map(vref);
    let out_vr = ["tau[1]", "tau[2]", "tau[3]", "energy", "solve_time"].map(vref);
    let int_vr = ["qp_iterations", "solver_status"].map(vref);
    let plant = PlanarChain::<3>::default();
    let mut z = SVector::<f64, 6>::from([0.05, 0.05, 0.05, 0.0, 0.0, 0.0]);
    unsafe {
        assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), OK);
        assert_eq!(fmi2EnterInitializationMode(c), OK);
        assert_eq!(fmi2SetReal(c, state_vr.as_ptr(), 6, z.as_ptr()), OK);
        assert_eq!(fmi2ExitInitializationMode(c), OK);
        let (mut out, mut ints, mut t) = ([f64::NAN; 5], [-1; 2], 0.0);
        for k in 0..200 {
            let (statuses, n) = counted(|| {
                [
                    fmi2SetReal(c, state_vr.as_ptr(), 6, z.as_ptr()),
                    fmi2DoStep(c, t, DT, 1),
                    fmi2GetReal(c, out_vr.as_ptr(), 5, out.as_mut_ptr()),
                    fmi2GetInteger(c, int_vr.as_ptr(), 2, ints.as_mut_ptr()),
                ]
            });
            assert_eq!(statuses, [OK; 4], "sample {k}: {:?}", fmu.log.lines());
            assert!(ints[0] > 0 && ints[1] == 0, "sample {k}: a solve happened");
            assert_eq!(n, 0, "sample {k}: {n} allocations in the FMU's sample path");
            t += DT;
            let tau = Vector::<3>::new(out[0], out[1], out[2]);
            for _ in 0..5 {
                z = rk4_step::<_, 3, 6>(&plant, &z, &tau, DT / 5.0);
            }
        }
        assert!(out[3] > 0.5, "energy {} J after 200 samples", out[3]);
        fmi2FreeInstance(c);
    }
}
