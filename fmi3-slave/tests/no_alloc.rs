//! Real-time discipline: `fmi3SetFloat64`, `fmi3DoStep`, `fmi3GetFloat64`,
//! `fmi3GetInt32` and `fmi3GetBoolean` on arrays do not allocate once the
//! instance is in Step Mode (counted by a global allocator, armed only on
//! the test's thread).

mod common;

use common::*;
use fmi3_slave::layout::{BOOLEAN_VR_OFFSET, INTEGER_VR_OFFSET};
use fmi3_slave::testing::LogCapture;
use fmi3_slave::{Model, ffi, instance::instantiation_token};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::ffi::CString;
use std::ptr;
use std::sync::atomic::{AtomicUsize, Ordering};

mod exports {
    fmi3_slave::export_fmi3!(crate::common::Chain);
}
use exports::*;

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    static ARMED: Cell<bool> = const { Cell::new(false) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if ARMED.try_with(|a| a.get()).unwrap_or(false) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, p: *mut u8, layout: Layout) {
        unsafe { System.dealloc(p, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

const OK: ffi::fmi3Status = ffi::fmi3Status_fmi3OK;

#[test]
fn steps_and_array_access_do_not_allocate() {
    let log = LogCapture::new();
    let name = CString::new("chain").unwrap();
    let token = CString::new(instantiation_token(&Chain::description())).unwrap();
    let c = unsafe {
        fmi3InstantiateCoSimulation(
            name.as_ptr(),
            token.as_ptr(),
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
    assert!(!c.is_null());
    unsafe {
        assert_eq!(
            fmi3EnterInitializationMode(c, false, 0.0, 0.0, false, 0.0),
            OK
        );
        assert_eq!(fmi3ExitInitializationMode(c), OK);
    }
    let (h, mut t) = (0.001, 0.0);
    let mut out = [0.0; 2 * N + 1];
    let mut steps = 0i32;
    let mut hold = [true];
    let vrs = [X, V, ENERGY];
    let steps_vr = INTEGER_VR_OFFSET + STEPS;
    let hold_vr = BOOLEAN_VR_OFFSET + HOLD;
    ARMED.with(|a| a.set(true));
    for n in 0..200 {
        let f = [0.1 * n as f64, 0.0, -1.0];
        let (mut e, mut term, mut early, mut last) = (false, false, false, 0.0);
        unsafe {
            assert_eq!(fmi3SetFloat64(c, &F, 1, f.as_ptr(), N), OK);
            assert_eq!(
                fmi3DoStep(c, t, h, true, &mut e, &mut term, &mut early, &mut last),
                OK
            );
            assert_eq!(
                fmi3GetFloat64(c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr(), out.len()),
                OK
            );
            assert_eq!(fmi3GetInt32(c, &steps_vr, 1, &mut steps, 1), OK);
            assert_eq!(fmi3GetBoolean(c, &hold_vr, 1, hold.as_mut_ptr(), 1), OK);
        }
        t += h;
    }
    ARMED.with(|a| a.set(false));
    assert_eq!(
        ALLOCATIONS.load(Ordering::Relaxed),
        0,
        "allocations in step mode"
    );
    assert_eq!(steps, 200);
    assert!(!hold[0]);
    assert!(out.iter().all(|x| x.is_finite()));
    unsafe { fmi3FreeInstance(c) };
}
