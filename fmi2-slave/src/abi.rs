//! The C entry points, generic over the model. [`crate::export_fmi2!`]
//! instantiates them as `#[no_mangle]` functions in the final cdylib crate.
//!
//! Every entry point checks its pointers, converts C arrays into slices and
//! runs the call under `catch_unwind`, so a panic becomes `fmi2Error` with a
//! log line instead of unwinding into the host.

use crate::ffi;
use crate::instance::Instance;
use crate::logger::{Logger, Status};
use crate::model::Model;
use crate::sink::{Fmi2Sink, ToFfi};
use crate::state::{self, FmuState};
use crate::variables::BaseType;
use fmu_core::abi::{guarded, live_state, slice, slice_mut, store_state};
use std::ffi::{CStr, c_char};
use std::panic::catch_unwind;
use std::ptr;

const ERROR: ffi::fmi2Status = ffi::fmi2Status_fmi2Error;

/// Runs `body` on the instance behind `c`, catching panics.
///
/// # Safety
/// `c` is null or a pointer returned by [`instantiate`] for the same `M` and
/// not yet freed, used by one thread at a time.
unsafe fn call<M: Model>(
    c: ffi::fmi2Component,
    func: &'static str,
    body: impl FnOnce(&mut Instance<M>) -> Status,
) -> ffi::fmi2Status {
    // SAFETY: see the function's contract.
    unsafe { guarded(c as *mut Instance<M>, func, body, |inst, m| inst.fail(m)) }
        .map_or(ERROR, |status| status.to_ffi())
}

fn null<M: Model>(instance: &mut Instance<M>, func: &str, what: &str) -> Status {
    instance.fail(&format!("{func}: argument {what} is a NULL pointer"))
}

/// `fmi2GetTypesPlatform`.
pub fn get_types_platform() -> *const c_char {
    ffi::fmi2TypesPlatform.as_ptr() as *const c_char
}

/// `fmi2GetVersion`.
pub fn get_version() -> *const c_char {
    ffi::fmi2Version.as_ptr() as *const c_char
}

/// `fmi2Instantiate`.
///
/// # Safety
/// Arguments as the FMI 2.0 standard defines them (strings null or
/// NUL-terminated, `functions` null or valid).
pub unsafe fn instantiate<M: Model>(
    instance_name: ffi::fmi2String,
    fmu_type: ffi::fmi2Type,
    guid: ffi::fmi2String,
    resource_location: ffi::fmi2String,
    functions: *const ffi::fmi2CallbackFunctions,
    _visible: ffi::fmi2Boolean,
    logging_on: ffi::fmi2Boolean,
) -> ffi::fmi2Component {
    let result = catch_unwind(|| {
        if functions.is_null() {
            return ptr::null_mut();
        }
        // SAFETY: non-null, valid by contract; copied because the host need
        // not keep the struct alive.
        let functions = unsafe { *functions };
        // SAFETY: null or NUL-terminated by contract.
        let c_str = |s: ffi::fmi2String| {
            (!s.is_null()).then(|| unsafe { CStr::from_ptr(s) }.to_string_lossy().into_owned())
        };
        let name = c_str(instance_name);
        let log = Logger::new(
            Fmi2Sink::boxed(functions.logger, functions.componentEnvironment),
            name.as_deref().unwrap_or(""),
            logging_on != 0,
        );
        if name.is_none() {
            log.error("fmi2Instantiate: instanceName is NULL");
            return ptr::null_mut();
        }
        if fmu_type != ffi::fmi2Type_fmi2CoSimulation {
            log.error("fmi2Instantiate: this FMU supports Co-Simulation only (fmuType must be fmi2CoSimulation)");
            return ptr::null_mut();
        }
        let Some(guid) = c_str(guid) else {
            log.error("fmi2Instantiate: fmuGUID is NULL");
            return ptr::null_mut();
        };
        // An unusable location is no error for an FMU that needs no
        // resources: the description says (Model::description_for).
        let resources =
            c_str(resource_location).and_then(|uri| crate::resources::resource_dir(&uri));
        match Instance::<M>::with_resources(log, &guid, resources) {
            Some(instance) => Box::into_raw(Box::new(instance)) as ffi::fmi2Component,
            None => ptr::null_mut(),
        }
    });
    result.unwrap_or(ptr::null_mut())
}

/// `fmi2FreeInstance`.
///
/// # Safety
/// `c` is null or a live instance of `M`; it is invalid afterwards.
pub unsafe fn free_instance<M: Model>(c: ffi::fmi2Component) {
    if !c.is_null() {
        // SAFETY: see the function's contract. A panic in a destructor is
        // swallowed: there is nobody left to report it to.
        let _ = catch_unwind(|| drop(unsafe { Box::from_raw(c as *mut Instance<M>) }));
    }
}

/// `fmi2SetDebugLogging`.
///
/// # Safety
/// `c` as for `call`; `categories` null or `n` NUL-terminated strings.
pub unsafe fn set_debug_logging<M: Model>(
    c: ffi::fmi2Component,
    logging_on: ffi::fmi2Boolean,
    n: usize,
    categories: *const ffi::fmi2String,
) -> ffi::fmi2Status {
    const F: &str = "fmi2SetDebugLogging";
    unsafe {
        call::<M>(c, F, |inst| {
            let Some(cats) = slice(categories, n) else {
                return null(inst, F, "categories");
            };
            let mut names = Vec::with_capacity(cats.len());
            for &s in cats {
                if s.is_null() {
                    return null(inst, F, "categories[i]");
                }
                names.push(CStr::from_ptr(s).to_string_lossy().into_owned());
            }
            let refs: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
            inst.set_debug_logging(logging_on != 0, &refs)
        })
    }
}

/// `fmi2SetupExperiment`.
///
/// # Safety
/// `c` as for `call`.
pub unsafe fn setup_experiment<M: Model>(
    c: ffi::fmi2Component,
    tolerance_defined: ffi::fmi2Boolean,
    tolerance: ffi::fmi2Real,
    start_time: ffi::fmi2Real,
    stop_time_defined: ffi::fmi2Boolean,
    stop_time: ffi::fmi2Real,
) -> ffi::fmi2Status {
    unsafe {
        call::<M>(c, "fmi2SetupExperiment", |inst| {
            inst.setup_experiment(
                (tolerance_defined != 0).then_some(tolerance),
                start_time,
                (stop_time_defined != 0).then_some(stop_time),
            )
        })
    }
}

/// `fmi2EnterInitializationMode`.
///
/// # Safety
/// `c` as for `call`.
pub unsafe fn enter_initialization_mode<M: Model>(c: ffi::fmi2Component) -> ffi::fmi2Status {
    unsafe {
        call::<M>(c, "fmi2EnterInitializationMode", |inst| {
            inst.enter_initialization_mode()
        })
    }
}

/// `fmi2ExitInitializationMode`.
///
/// # Safety
/// `c` as for `call`.
pub unsafe fn exit_initialization_mode<M: Model>(c: ffi::fmi2Component) -> ffi::fmi2Status {
    unsafe {
        call::<M>(c, "fmi2ExitInitializationMode", |inst| {
            inst.exit_initialization_mode()
        })
    }
}

/// `fmi2Terminate`.
///
/// # Safety
/// `c` as for `call`.
pub unsafe fn terminate<M: Model>(c: ffi::fmi2Component) -> ffi::fmi2Status {
    unsafe { call::<M>(c, "fmi2Terminate", |inst| inst.terminate()) }
}

/// `fmi2Reset`.
///
/// # Safety
/// `c` as for `call`.
pub unsafe fn reset<M: Model>(c: ffi::fmi2Component) -> ffi::fmi2Status {
    unsafe { call::<M>(c, "fmi2Reset", |inst| inst.reset()) }
}

/// `fmi2GetReal`.
///
/// # Safety
/// `c` as for `call`; `vr` and `value` null or arrays of `n` elements.
pub unsafe fn get_real<M: Model>(
    c: ffi::fmi2Component,
    vr: *const ffi::fmi2ValueReference,
    n: usize,
    value: *mut ffi::fmi2Real,
) -> ffi::fmi2Status {
    const F: &str = "fmi2GetReal";
    unsafe {
        call::<M>(c, F, |inst| match (slice(vr, n), slice_mut(value, n)) {
            (Some(vr), Some(value)) => inst.get_real(vr, value),
            (None, _) => null(inst, F, "vr"),
            (_, None) => null(inst, F, "value"),
        })
    }
}

/// `fmi2SetReal`.
///
/// # Safety
/// `c` as for `call`; `vr` and `value` null or arrays of `n` elements.
pub unsafe fn set_real<M: Model>(
    c: ffi::fmi2Component,
    vr: *const ffi::fmi2ValueReference,
    n: usize,
    value: *const ffi::fmi2Real,
) -> ffi::fmi2Status {
    const F: &str = "fmi2SetReal";
    unsafe {
        call::<M>(c, F, |inst| match (slice(vr, n), slice(value, n)) {
            (Some(vr), Some(value)) => inst.set_real(vr, value),
            (None, _) => null(inst, F, "vr"),
            (_, None) => null(inst, F, "value"),
        })
    }
}

/// `fmi2GetInteger`.
///
/// # Safety
/// `c` as for `call`; `vr` and `value` null or arrays of `n` elements.
pub unsafe fn get_integer<M: Model>(
    c: ffi::fmi2Component,
    vr: *const ffi::fmi2ValueReference,
    n: usize,
    value: *mut ffi::fmi2Integer,
) -> ffi::fmi2Status {
    const F: &str = "fmi2GetInteger";
    unsafe {
        call::<M>(c, F, |inst| match (slice(vr, n), slice_mut(value, n)) {
            (Some(vr), Some(value)) => inst.get_integer(vr, value),
            (None, _) => null(inst, F, "vr"),
            (_, None) => null(inst, F, "value"),
        })
    }
}

/// `fmi2SetInteger`.
///
/// # Safety
/// `c` as for `call`; `vr` and `value` null or arrays of `n` elements.
pub unsafe fn set_integer<M: Model>(
    c: ffi::fmi2Component,
    vr: *const ffi::fmi2ValueReference,
    n: usize,
    value: *const ffi::fmi2Integer,
) -> ffi::fmi2Status {
    const F: &str = "fmi2SetInteger";
    unsafe {
        call::<M>(c, F, |inst| match (slice(vr, n), slice(value, n)) {
            (Some(vr), Some(value)) => inst.set_integer(vr, value),
            (None, _) => null(inst, F, "vr"),
            (_, None) => null(inst, F, "value"),
        })
    }
}

/// `fmi2GetBoolean` (C booleans are `int`: written as 0/1).
///
/// # Safety
/// `c` as for `call`; `vr` and `value` null or arrays of `n` elements.
pub unsafe fn get_boolean<M: Model>(
    c: ffi::fmi2Component,
    vr: *const ffi::fmi2ValueReference,
    n: usize,
    value: *mut ffi::fmi2Boolean,
) -> ffi::fmi2Status {
    const F: &str = "fmi2GetBoolean";
    unsafe {
        call::<M>(c, F, |inst| match (slice(vr, n), slice_mut(value, n)) {
            (Some(vr), Some(value)) => inst.get(F, BaseType::Boolean, vr, |k, v| {
                if let crate::Value::Boolean(b) = v {
                    value[k] = b as ffi::fmi2Boolean;
                }
            }),
            (None, _) => null(inst, F, "vr"),
            (_, None) => null(inst, F, "value"),
        })
    }
}

/// `fmi2SetBoolean` (any non-zero C value is true).
///
/// # Safety
/// `c` as for `call`; `vr` and `value` null or arrays of `n` elements.
pub unsafe fn set_boolean<M: Model>(
    c: ffi::fmi2Component,
    vr: *const ffi::fmi2ValueReference,
    n: usize,
    value: *const ffi::fmi2Boolean,
) -> ffi::fmi2Status {
    const F: &str = "fmi2SetBoolean";
    unsafe {
        call::<M>(c, F, |inst| match (slice(vr, n), slice(value, n)) {
            (Some(vr), Some(value)) => inst.set(F, BaseType::Boolean, vr, |k| {
                crate::Value::Boolean(value[k] != 0)
            }),
            (None, _) => null(inst, F, "vr"),
            (_, None) => null(inst, F, "value"),
        })
    }
}

/// `fmi2GetString`.
///
/// # Safety
/// `c` as for `call`; `vr` null or an array of `n` elements.
pub unsafe fn get_string<M: Model>(
    c: ffi::fmi2Component,
    vr: *const ffi::fmi2ValueReference,
    n: usize,
    value: *mut ffi::fmi2String,
) -> ffi::fmi2Status {
    const F: &str = "fmi2GetString";
    unsafe {
        call::<M>(c, F, |inst| match slice(vr, n) {
            Some(_) if n > 0 && value.is_null() => null(inst, F, "value"),
            Some(vr) => inst.string_access(F, vr, false),
            None => null(inst, F, "vr"),
        })
    }
}

/// `fmi2SetString`.
///
/// # Safety
/// `c` as for `call`; `vr` null or an array of `n` elements.
pub unsafe fn set_string<M: Model>(
    c: ffi::fmi2Component,
    vr: *const ffi::fmi2ValueReference,
    n: usize,
    value: *const ffi::fmi2String,
) -> ffi::fmi2Status {
    const F: &str = "fmi2SetString";
    unsafe {
        call::<M>(c, F, |inst| match slice(vr, n) {
            Some(_) if n > 0 && value.is_null() => null(inst, F, "value"),
            Some(vr) => inst.string_access(F, vr, true),
            None => null(inst, F, "vr"),
        })
    }
}

/// Any function this FMU does not implement: `fmi2Error` with a log line.
///
/// # Safety
/// `c` as for `call`.
pub unsafe fn unsupported<M: Model>(
    c: ffi::fmi2Component,
    func: &'static str,
    why: &'static str,
) -> ffi::fmi2Status {
    unsafe { call::<M>(c, func, |inst| inst.unsupported(func, why)) }
}

/// A status query this FMU cannot answer (`fmi2GetStatus`,
/// `fmi2GetIntegerStatus`, `fmi2GetStringStatus`): `fmi2Discard` with a
/// warning line, the instance stays usable; a NULL `value` is an error.
///
/// # Safety
/// `c` as for `call`.
pub unsafe fn status_unavailable<M: Model>(
    c: ffi::fmi2Component,
    func: &'static str,
    why: &'static str,
    value_is_null: bool,
) -> ffi::fmi2Status {
    unsafe {
        call::<M>(c, func, |inst| {
            if value_is_null {
                null(inst, func, "value")
            } else {
                inst.status_unavailable(func, why)
            }
        })
    }
}

/// `fmi2DoStep`.
///
/// # Safety
/// `c` as for `call`.
pub unsafe fn do_step<M: Model>(
    c: ffi::fmi2Component,
    t: ffi::fmi2Real,
    h: ffi::fmi2Real,
    _no_set_fmu_state_prior: ffi::fmi2Boolean,
) -> ffi::fmi2Status {
    unsafe { call::<M>(c, "fmi2DoStep", |inst| inst.do_step(t, h)) }
}

/// `fmi2GetRealStatus`: only `fmi2LastSuccessfulTime`.
///
/// # Safety
/// `c` as for `call`; `value` null or writable.
pub unsafe fn get_real_status<M: Model>(
    c: ffi::fmi2Component,
    kind: ffi::fmi2StatusKind,
    value: *mut ffi::fmi2Real,
) -> ffi::fmi2Status {
    const F: &str = "fmi2GetRealStatus";
    unsafe {
        call::<M>(c, F, |inst| {
            if value.is_null() {
                return null(inst, F, "value");
            }
            if kind != ffi::fmi2StatusKind_fmi2LastSuccessfulTime {
                return inst.status_unavailable(F, "only fmi2LastSuccessfulTime is a Real status");
            }
            match inst.last_successful_time() {
                Ok(t) => {
                    *value = t;
                    Status::Ok
                }
                Err(s) => s,
            }
        })
    }
}

/// `fmi2GetBooleanStatus`: only `fmi2Terminated`.
///
/// # Safety
/// `c` as for `call`; `value` null or writable.
pub unsafe fn get_boolean_status<M: Model>(
    c: ffi::fmi2Component,
    kind: ffi::fmi2StatusKind,
    value: *mut ffi::fmi2Boolean,
) -> ffi::fmi2Status {
    const F: &str = "fmi2GetBooleanStatus";
    unsafe {
        call::<M>(c, F, |inst| {
            if value.is_null() {
                return null(inst, F, "value");
            }
            if kind != ffi::fmi2StatusKind_fmi2Terminated {
                return inst.status_unavailable(F, "only fmi2Terminated is a Boolean status");
            }
            match inst.terminate_requested() {
                Ok(b) => {
                    *value = b as ffi::fmi2Boolean;
                    Status::Ok
                }
                Err(s) => s,
            }
        })
    }
}

/// The name of the FMU-state argument in FMI 2.0, for messages.
const STATE: &str = "FMUstate";

/// `fmi2GetFMUstate`.
///
/// # Safety
/// `c` as for `call`; `s` null or writable.
pub unsafe fn get_fmu_state<M: Model>(
    c: ffi::fmi2Component,
    s: *mut ffi::fmi2FMUstate,
) -> ffi::fmi2Status {
    const F: &str = "fmi2GetFMUstate";
    unsafe {
        call::<M>(c, F, |inst| {
            if s.is_null() {
                return null(inst, F, "FMUstate");
            }
            match inst.save_state(F) {
                Ok(saved) => match store_state(s, saved, STATE) {
                    Ok(()) => Status::Ok,
                    Err(e) => inst.state_argument_error(&format!("{F}: {e}")),
                },
                Err(status) => status,
            }
        })
    }
}

/// `fmi2SetFMUstate`.
///
/// # Safety
/// `c` as for `call`.
pub unsafe fn set_fmu_state<M: Model>(
    c: ffi::fmi2Component,
    s: ffi::fmi2FMUstate,
) -> ffi::fmi2Status {
    const F: &str = "fmi2SetFMUstate";
    unsafe {
        call::<M>(c, F, |inst| match live_state(s, STATE) {
            Ok(saved) => {
                let saved = saved.clone();
                inst.restore_state(F, &saved)
            }
            Err(e) => inst.state_argument_error(&format!("{F}: {e}")),
        })
    }
}

/// `fmi2FreeFMUstate`: frees `*s` and sets it to NULL (`*s == NULL`: nothing).
///
/// # Safety
/// `c` as for `call`; `s` null or writable.
pub unsafe fn free_fmu_state<M: Model>(
    c: ffi::fmi2Component,
    s: *mut ffi::fmi2FMUstate,
) -> ffi::fmi2Status {
    const F: &str = "fmi2FreeFMUstate";
    unsafe {
        call::<M>(c, F, |inst| {
            if s.is_null() {
                return null(inst, F, "FMUstate");
            }
            let p = *s as *mut FmuState;
            if p.is_null() {
                return inst.state_call_ok(F);
            }
            if state::free(p) {
                *s = ptr::null_mut();
                inst.state_call_ok(F)
            } else {
                inst.state_argument_error(&format!(
                    "{F}: *FMUstate is not a live state of this FMU (freed twice, or from elsewhere)"
                ))
            }
        })
    }
}

/// `fmi2SerializedFMUstateSize`.
///
/// # Safety
/// `c` as for `call`; `size` null or writable.
pub unsafe fn serialized_fmu_state_size<M: Model>(
    c: ffi::fmi2Component,
    s: ffi::fmi2FMUstate,
    size: *mut usize,
) -> ffi::fmi2Status {
    const F: &str = "fmi2SerializedFMUstateSize";
    unsafe {
        call::<M>(c, F, |inst| {
            if size.is_null() {
                return null(inst, F, "size");
            }
            match live_state(s, STATE) {
                Ok(saved) => {
                    *size = saved.bytes().len();
                    inst.state_call_ok(F)
                }
                Err(e) => inst.state_argument_error(&format!("{F}: {e}")),
            }
        })
    }
}

/// `fmi2SerializeFMUstate`: writes the state into `bytes[..size]`; `size`
/// must be at least [`serialized_fmu_state_size`]'s.
///
/// # Safety
/// `c` as for `call`; `bytes` null or `size` writable bytes.
pub unsafe fn serialize_fmu_state<M: Model>(
    c: ffi::fmi2Component,
    s: ffi::fmi2FMUstate,
    bytes: *mut ffi::fmi2Byte,
    size: usize,
) -> ffi::fmi2Status {
    const F: &str = "fmi2SerializeFMUstate";
    unsafe {
        call::<M>(c, F, |inst| {
            let saved = match live_state(s, STATE) {
                Ok(saved) => saved,
                Err(e) => return inst.state_argument_error(&format!("{F}: {e}")),
            };
            let n = saved.bytes().len();
            if size < n {
                return inst.state_argument_error(&format!(
                    "{F}: the buffer has {size} bytes, the state needs {n} \
                     (fmi2SerializedFMUstateSize)"
                ));
            }
            let Some(out) = slice_mut(bytes as *mut u8, n) else {
                return null(inst, F, "serializedState");
            };
            out.copy_from_slice(saved.bytes());
            inst.state_call_ok(F)
        })
    }
}

/// `fmi2DeSerializeFMUstate`: a new state (or the live one in `*s`) from
/// `bytes[..size]`, checked before anything is stored.
///
/// # Safety
/// `c` as for `call`; `bytes` null or `size` readable bytes; `s` null or writable.
pub unsafe fn deserialize_fmu_state<M: Model>(
    c: ffi::fmi2Component,
    bytes: *const ffi::fmi2Byte,
    size: usize,
    s: *mut ffi::fmi2FMUstate,
) -> ffi::fmi2Status {
    const F: &str = "fmi2DeSerializeFMUstate";
    unsafe {
        call::<M>(c, F, |inst| {
            if s.is_null() {
                return null(inst, F, "FMUstate");
            }
            let Some(input) = slice(bytes as *const u8, size) else {
                return null(inst, F, "serializedState");
            };
            match inst.deserialize_state(F, input) {
                Ok(saved) => match store_state(s, saved, STATE) {
                    Ok(()) => Status::Ok,
                    Err(e) => inst.state_argument_error(&format!("{F}: {e}")),
                },
                Err(status) => status,
            }
        })
    }
}
