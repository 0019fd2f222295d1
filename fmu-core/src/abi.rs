//! Helpers of the C entry points that do not depend on the FMI version:
//! C arrays as slices, a call on an instance pointer with panics caught, and
//! the host's FMU-state pointers. `fmi2-slave` and `fmi3-slave` build their
//! functions on them.

use crate::logger::Status;
use crate::state::{self, FmuState};
use std::any::Any;
use std::ffi::c_void;
use std::panic::{AssertUnwindSafe, catch_unwind};

/// The message of a caught panic.
pub fn panic_message(payload: &(dyn Any + Send)) -> &str {
    payload
        .downcast_ref::<&str>()
        .copied()
        .or_else(|| payload.downcast_ref::<String>().map(|s| s.as_str()))
        .unwrap_or("unknown panic")
}

/// Runs `body` on the object behind `p`, catching panics: a panic becomes
/// `fail(object, "<func>: internal error: <message>")`. `None` when `p` is
/// null (there is no object, so no logger to explain it).
///
/// # Safety
/// `p` is null or points to a live `T` that nothing else uses during the
/// call.
pub unsafe fn guarded<T>(
    p: *mut T,
    func: &str,
    body: impl FnOnce(&mut T) -> Status,
    fail: impl FnOnce(&mut T, &str) -> Status,
) -> Option<Status> {
    if p.is_null() {
        return None;
    }
    // SAFETY: see the function's contract.
    match catch_unwind(AssertUnwindSafe(|| body(unsafe { &mut *p }))) {
        Ok(status) => Some(status),
        Err(payload) => {
            // SAFETY: the closure that held the borrow has been consumed.
            let object = unsafe { &mut *p };
            let message = format!("{func}: internal error: {}", panic_message(&*payload));
            Some(fail(object, &message))
        }
    }
}

/// A slice from a C array (`None` for a null pointer with `n > 0`).
///
/// # Safety
/// A non-null `p` points to `n` valid elements.
pub unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        Some(&[])
    } else if p.is_null() {
        None
    } else {
        // SAFETY: see the function's contract.
        Some(unsafe { std::slice::from_raw_parts(p, n) })
    }
}

/// A mutable slice from a C array (`None` for a null pointer with `n > 0`).
///
/// # Safety
/// A non-null `p` points to `n` writable elements.
pub unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        Some(&mut [])
    } else if p.is_null() {
        None
    } else {
        // SAFETY: see the function's contract.
        Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
    }
}

/// The live state behind a host's FMU-state pointer `s` (the argument
/// called `name` in this FMI version), or why it is none.
pub fn live_state<'a>(s: *mut c_void, name: &str) -> Result<&'a FmuState, String> {
    let p = s as *const FmuState;
    if p.is_null() {
        Err(format!("argument {name} is a NULL pointer"))
    } else if !state::is_live(p) {
        Err(format!(
            "{name} is not a live state of this FMU (freed, or from elsewhere)"
        ))
    } else {
        // SAFETY: live states are boxes this library allocated and has not freed.
        Ok(unsafe { &*p })
    }
}

/// Stores `saved` in the host's `*out`: into the live state already there
/// (a non-NULL state is overwritten, as FMI 2.0 and 3.0 say), else a new
/// one.
///
/// # Safety
/// `out` is non-null and writable.
pub unsafe fn store_state(
    out: *mut *mut c_void,
    saved: FmuState,
    name: &str,
) -> Result<(), String> {
    // SAFETY: see the function's contract.
    let current = unsafe { *out } as *mut FmuState;
    if current.is_null() {
        unsafe { *out = state::into_raw(saved) as *mut c_void };
        Ok(())
    } else if state::is_live(current) {
        // SAFETY: live, allocated by this library.
        unsafe { *current = saved };
        Ok(())
    } else {
        Err(format!(
            "*{name} is neither NULL nor a live state of this FMU"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slices_refuse_null_arrays_of_some_elements() {
        let xs = [1.0, 2.0];
        // SAFETY: the pointers are null or point to `xs`.
        unsafe {
            assert_eq!(slice(xs.as_ptr(), 2), Some(&xs[..]));
            assert_eq!(slice::<f64>(std::ptr::null(), 2), None);
            assert_eq!(slice::<f64>(std::ptr::null(), 0), Some(&[][..]));
            assert!(slice_mut::<f64>(std::ptr::null_mut(), 1).is_none());
        }
    }

    #[test]
    fn a_panic_becomes_the_failure_status_with_its_message() {
        let mut seen = String::new();
        let p: *mut String = &mut seen;
        // SAFETY: `p` points to `seen`, used by nothing else meanwhile.
        let status = unsafe {
            guarded(
                p,
                "fmiXDoStep",
                |_| panic!("index out of range"),
                |s, m| {
                    s.push_str(m);
                    Status::Error
                },
            )
        };
        assert_eq!(status, Some(Status::Error));
        assert_eq!(seen, "fmiXDoStep: internal error: index out of range");
        // SAFETY: null.
        let none = unsafe {
            guarded::<String>(
                std::ptr::null_mut(),
                "f",
                |_| Status::Ok,
                |_, _| Status::Error,
            )
        };
        assert_eq!(none, None);
    }

    #[test]
    fn fmu_states_are_stored_and_checked() {
        let mut out: *mut c_void = std::ptr::null_mut();
        let state = |b: u8| FmuState { bytes: vec![b] };
        // SAFETY: `out` is writable.
        unsafe { store_state(&mut out, state(1), "FMUState") }.unwrap();
        assert_eq!(live_state(out, "FMUState").unwrap().bytes(), &[1]);
        // A live state is overwritten in place.
        let first = out;
        unsafe { store_state(&mut out, state(2), "FMUState") }.unwrap();
        assert_eq!(out, first);
        assert_eq!(live_state(out, "FMUState").unwrap().bytes(), &[2]);
        assert!(state::free(out as *mut FmuState));
        let e = live_state(out, "FMUstate").unwrap_err();
        assert_eq!(
            e,
            "FMUstate is not a live state of this FMU (freed, or from elsewhere)"
        );
        let e = unsafe { store_state(&mut out, state(3), "FMUState") }.unwrap_err();
        assert!(e.starts_with("*FMUState is neither NULL"), "{e}");
        assert_eq!(
            live_state(std::ptr::null_mut(), "FMUState").unwrap_err(),
            "argument FMUState is a NULL pointer"
        );
    }
}
