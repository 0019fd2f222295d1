//! The C entry points, generic over the model. [`crate::export_fmi3!`]
//! instantiates them as `#[no_mangle]` functions in the final cdylib crate.
//!
//! Every entry point checks its pointers, converts C arrays into slices and
//! runs the call under `catch_unwind`, so a panic becomes `fmi3Error` with a
//! log line instead of unwinding into the host.

use crate::ffi;
use crate::instance::Instance;
use crate::layout::Fmi3Type;
use crate::sink::{Fmi3Sink, ToFfi};
use fmu_core::abi::{guarded, live_state, slice, slice_mut, store_state};
use fmu_core::logger::{Logger, Status};
use fmu_core::model::Model;
use fmu_core::state::{self, FmuState};
use fmu_core::variables::Value;
use std::ffi::{CStr, c_char};
use std::panic::catch_unwind;
use std::path::PathBuf;
use std::ptr;

const ERROR: ffi::fmi3Status = ffi::fmi3Status_fmi3Error;

/// Runs `body` on the instance behind `c`, catching panics.
///
/// # Safety
/// `c` is null or a pointer returned by [`instantiate_co_simulation`] for
/// the same `M` and not yet freed, used by one thread at a time.
unsafe fn call<M: Model>(
    c: ffi::fmi3Instance,
    func: &'static str,
    body: impl FnOnce(&mut Instance<M>) -> Status,
) -> ffi::fmi3Status {
    // SAFETY: see the function's contract.
    unsafe { guarded(c as *mut Instance<M>, func, body, |inst, m| inst.fail(m)) }
        .map_or(ERROR, |status| status.to_ffi())
}

fn null<M: Model>(instance: &mut Instance<M>, func: &str, what: &str) -> Status {
    instance.fail(&format!("{func}: argument {what} is a NULL pointer"))
}

/// `fmi3GetVersion`: `"3.0"`.
pub fn get_version() -> *const c_char {
    ffi::fmi3Version.as_ptr() as *const c_char
}

/// A C string argument (`None` for NULL).
///
/// # Safety
/// `s` is null or NUL-terminated.
unsafe fn c_str(s: ffi::fmi3String) -> Option<String> {
    // SAFETY: see the function's contract.
    (!s.is_null()).then(|| unsafe { CStr::from_ptr(s) }.to_string_lossy().into_owned())
}

/// The folder of FMI 3.0's `resourcePath` (an absolute path ending with a
/// separator; the separator is dropped). NULL or empty: none. A `file:`
/// URI, as some FMI 2.0-era hosts still pass, is accepted too.
pub fn resource_folder(path: &str) -> Option<PathBuf> {
    if path.is_empty() {
        return None;
    }
    if path.starts_with("file:") {
        return fmu_core::resources::resource_dir(path);
    }
    let trimmed = path.trim_end_matches(['/', std::path::MAIN_SEPARATOR]);
    Some(PathBuf::from(if trimmed.is_empty() {
        path
    } else {
        trimmed
    }))
}

/// `fmi3InstantiateCoSimulation`. Refused (NULL, with the reason logged):
/// `eventModeUsed = true` (the FMU has no Event Mode: `hasEventMode =
/// false`) and required intermediate variables (`providesIntermediateUpdate
/// = false`). `earlyReturnAllowed = true` is accepted and has no effect:
/// `fmi3DoStep` never returns early. The `intermediateUpdate` callback is
/// never called.
///
/// # Safety
/// Arguments as the FMI 3.0 standard defines them (strings null or
/// NUL-terminated, `required_intermediate` null or `n_required` elements).
#[allow(clippy::too_many_arguments)]
pub unsafe fn instantiate_co_simulation<M: Model>(
    instance_name: ffi::fmi3String,
    instantiation_token: ffi::fmi3String,
    resource_path: ffi::fmi3String,
    _visible: ffi::fmi3Boolean,
    logging_on: ffi::fmi3Boolean,
    event_mode_used: ffi::fmi3Boolean,
    early_return_allowed: ffi::fmi3Boolean,
    _required_intermediate: *const ffi::fmi3ValueReference,
    n_required: usize,
    environment: ffi::fmi3InstanceEnvironment,
    log_message: ffi::fmi3LogMessageCallback,
    _intermediate_update: ffi::fmi3IntermediateUpdateCallback,
) -> ffi::fmi3Instance {
    const F: &str = "fmi3InstantiateCoSimulation";
    let result = catch_unwind(|| {
        // SAFETY: null or NUL-terminated by contract.
        let name = unsafe { c_str(instance_name) };
        let log = Logger::new(
            Fmi3Sink::boxed(log_message, environment),
            name.as_deref().unwrap_or(""),
            logging_on,
        );
        if name.is_none() {
            log.error(&format!("{F}: instanceName is NULL"));
            return ptr::null_mut();
        }
        // SAFETY: as above.
        let Some(token) = (unsafe { c_str(instantiation_token) }) else {
            log.error(&format!("{F}: instantiationToken is NULL"));
            return ptr::null_mut();
        };
        if event_mode_used {
            log.error(&format!(
                "{F}: eventModeUsed = true, but this FMU has no Event Mode (hasEventMode = false)"
            ));
            return ptr::null_mut();
        }
        if n_required > 0 {
            log.error(&format!(
                "{F}: {n_required} required intermediate variables, but this FMU provides no \
                 intermediate update (providesIntermediateUpdate = false)"
            ));
            return ptr::null_mut();
        }
        if early_return_allowed {
            log.event(&format!(
                "{F}: earlyReturnAllowed = true accepted; fmi3DoStep never returns early"
            ));
        }
        // A missing folder is no error for an FMU that needs no resources:
        // the description says (Model::description_for).
        // SAFETY: as above.
        let resources = unsafe { c_str(resource_path) }.and_then(|p| resource_folder(&p));
        match Instance::<M>::new(log, &token, resources) {
            Some(instance) => Box::into_raw(Box::new(instance)) as ffi::fmi3Instance,
            None => ptr::null_mut(),
        }
    });
    result.unwrap_or(ptr::null_mut())
}

/// `fmi3InstantiateModelExchange` / `fmi3InstantiateScheduledExecution`:
/// NULL, with the reason sent to `log_message` when there is one.
///
/// # Safety
/// `environment` and `log_message` as the FMI 3.0 standard defines them.
pub unsafe fn instantiate_unsupported(
    func: &'static str,
    instance_name: ffi::fmi3String,
    environment: ffi::fmi3InstanceEnvironment,
    log_message: ffi::fmi3LogMessageCallback,
) -> ffi::fmi3Instance {
    let _ = catch_unwind(|| {
        // SAFETY: null or NUL-terminated by contract.
        let name = unsafe { c_str(instance_name) }.unwrap_or_default();
        let log = Logger::new(Fmi3Sink::boxed(log_message, environment), &name, false);
        log.error(&format!(
            "{func}: this FMU supports Co-Simulation only (fmi3InstantiateCoSimulation)"
        ));
    });
    ptr::null_mut()
}

/// `fmi3FreeInstance`.
///
/// # Safety
/// `c` is null or a live instance of `M`; it is invalid afterwards.
pub unsafe fn free_instance<M: Model>(c: ffi::fmi3Instance) {
    if !c.is_null() {
        // SAFETY: see the function's contract. A panic in a destructor is
        // swallowed: there is nobody left to report it to.
        let _ = catch_unwind(|| drop(unsafe { Box::from_raw(c as *mut Instance<M>) }));
    }
}

/// `fmi3SetDebugLogging`.
///
/// # Safety
/// `c` as for `call`; `categories` null or `n` NUL-terminated strings.
pub unsafe fn set_debug_logging<M: Model>(
    c: ffi::fmi3Instance,
    logging_on: ffi::fmi3Boolean,
    n: usize,
    categories: *const ffi::fmi3String,
) -> ffi::fmi3Status {
    const F: &str = "fmi3SetDebugLogging";
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
            inst.set_debug_logging(logging_on, &refs)
        })
    }
}

/// `fmi3EnterInitializationMode`.
///
/// # Safety
/// `c` as for `call`.
pub unsafe fn enter_initialization_mode<M: Model>(
    c: ffi::fmi3Instance,
    tolerance_defined: ffi::fmi3Boolean,
    tolerance: ffi::fmi3Float64,
    start_time: ffi::fmi3Float64,
    stop_time_defined: ffi::fmi3Boolean,
    stop_time: ffi::fmi3Float64,
) -> ffi::fmi3Status {
    unsafe {
        call::<M>(c, "fmi3EnterInitializationMode", |inst| {
            inst.enter_initialization_mode(
                tolerance_defined.then_some(tolerance),
                start_time,
                stop_time_defined.then_some(stop_time),
            )
        })
    }
}

/// `fmi3ExitInitializationMode`.
///
/// # Safety
/// `c` as for `call`.
pub unsafe fn exit_initialization_mode<M: Model>(c: ffi::fmi3Instance) -> ffi::fmi3Status {
    unsafe {
        call::<M>(c, "fmi3ExitInitializationMode", |inst| {
            inst.exit_initialization_mode()
        })
    }
}

/// `fmi3Terminate`.
///
/// # Safety
/// `c` as for `call`.
pub unsafe fn terminate<M: Model>(c: ffi::fmi3Instance) -> ffi::fmi3Status {
    unsafe { call::<M>(c, "fmi3Terminate", |inst| inst.terminate()) }
}

/// `fmi3Reset`.
///
/// # Safety
/// `c` as for `call`.
pub unsafe fn reset<M: Model>(c: ffi::fmi3Instance) -> ffi::fmi3Status {
    unsafe { call::<M>(c, "fmi3Reset", |inst| inst.reset()) }
}

/// A typed getter: `convert` turns each value into the C type.
///
/// # Safety
/// `c` as for `call`; `vr` null or `nvr` elements, `values` null or
/// `n_values` writable elements.
#[allow(clippy::too_many_arguments)]
unsafe fn getter<M: Model, T>(
    c: ffi::fmi3Instance,
    func: &'static str,
    ty: Fmi3Type,
    vr: *const ffi::fmi3ValueReference,
    nvr: usize,
    values: *mut T,
    n_values: usize,
    convert: impl Fn(Value) -> T,
) -> ffi::fmi3Status {
    unsafe {
        call::<M>(c, func, |inst| {
            match (slice(vr, nvr), slice_mut(values, n_values)) {
                (Some(vr), Some(out)) => inst.get(func, ty, vr, n_values, |k, v| {
                    out[k] = convert(v);
                }),
                (None, _) => null(inst, func, "valueReferences"),
                (_, None) => null(inst, func, "values"),
            }
        })
    }
}

/// A typed setter: `convert` turns each C value into a value (an error for
/// one the variable's type cannot hold).
///
/// # Safety
/// `c` as for `call`; `vr` null or `nvr` elements, `values` null or
/// `n_values` elements.
#[allow(clippy::too_many_arguments)]
unsafe fn setter<M: Model, T: Copy>(
    c: ffi::fmi3Instance,
    func: &'static str,
    ty: Fmi3Type,
    vr: *const ffi::fmi3ValueReference,
    nvr: usize,
    values: *const T,
    n_values: usize,
    convert: impl Fn(T) -> Result<Value, String>,
) -> ffi::fmi3Status {
    unsafe {
        call::<M>(c, func, |inst| {
            match (slice(vr, nvr), slice(values, n_values)) {
                (Some(vr), Some(input)) => inst.set(func, ty, vr, n_values, |k| convert(input[k])),
                (None, _) => null(inst, func, "valueReferences"),
                (_, None) => null(inst, func, "values"),
            }
        })
    }
}

/// `fmi3GetFloat64` (arrays in row-major order; `nValues` counts elements).
///
/// # Safety
/// `c` as for `call`; arrays as the FMI 3.0 standard defines them.
pub unsafe fn get_float64<M: Model>(
    c: ffi::fmi3Instance,
    vr: *const ffi::fmi3ValueReference,
    nvr: usize,
    values: *mut ffi::fmi3Float64,
    n_values: usize,
) -> ffi::fmi3Status {
    unsafe {
        getter::<M, f64>(
            c,
            "fmi3GetFloat64",
            Fmi3Type::Float64,
            vr,
            nvr,
            values,
            n_values,
            |v| match v {
                Value::Real(x) => x,
                _ => f64::NAN,
            },
        )
    }
}

/// `fmi3SetFloat64` (NaN, infinities and values outside min/max refused).
///
/// # Safety
/// `c` as for `call`; arrays as the FMI 3.0 standard defines them.
pub unsafe fn set_float64<M: Model>(
    c: ffi::fmi3Instance,
    vr: *const ffi::fmi3ValueReference,
    nvr: usize,
    values: *const ffi::fmi3Float64,
    n_values: usize,
) -> ffi::fmi3Status {
    unsafe {
        setter::<M, f64>(
            c,
            "fmi3SetFloat64",
            Fmi3Type::Float64,
            vr,
            nvr,
            values,
            n_values,
            |x| Ok(Value::Real(x)),
        )
    }
}

/// `fmi3GetInt32`.
///
/// # Safety
/// `c` as for `call`; arrays as the FMI 3.0 standard defines them.
pub unsafe fn get_int32<M: Model>(
    c: ffi::fmi3Instance,
    vr: *const ffi::fmi3ValueReference,
    nvr: usize,
    values: *mut ffi::fmi3Int32,
    n_values: usize,
) -> ffi::fmi3Status {
    unsafe {
        getter::<M, i32>(
            c,
            "fmi3GetInt32",
            Fmi3Type::Int32,
            vr,
            nvr,
            values,
            n_values,
            |v| match v {
                Value::Integer(i) => i,
                _ => 0,
            },
        )
    }
}

/// `fmi3SetInt32`.
///
/// # Safety
/// `c` as for `call`; arrays as the FMI 3.0 standard defines them.
pub unsafe fn set_int32<M: Model>(
    c: ffi::fmi3Instance,
    vr: *const ffi::fmi3ValueReference,
    nvr: usize,
    values: *const ffi::fmi3Int32,
    n_values: usize,
) -> ffi::fmi3Status {
    unsafe {
        setter::<M, i32>(
            c,
            "fmi3SetInt32",
            Fmi3Type::Int32,
            vr,
            nvr,
            values,
            n_values,
            |i| Ok(Value::Integer(i)),
        )
    }
}

/// `fmi3GetInt64`: the enumerations (FMI 3.0 accesses them as Int64).
///
/// # Safety
/// `c` as for `call`; arrays as the FMI 3.0 standard defines them.
pub unsafe fn get_int64<M: Model>(
    c: ffi::fmi3Instance,
    vr: *const ffi::fmi3ValueReference,
    nvr: usize,
    values: *mut ffi::fmi3Int64,
    n_values: usize,
) -> ffi::fmi3Status {
    unsafe {
        getter::<M, i64>(
            c,
            "fmi3GetInt64",
            Fmi3Type::Enumeration,
            vr,
            nvr,
            values,
            n_values,
            |v| match v {
                Value::Integer(i) => i64::from(i),
                _ => 0,
            },
        )
    }
}

/// `fmi3SetInt64`: the enumerations (values outside their items' range
/// refused).
///
/// # Safety
/// `c` as for `call`; arrays as the FMI 3.0 standard defines them.
pub unsafe fn set_int64<M: Model>(
    c: ffi::fmi3Instance,
    vr: *const ffi::fmi3ValueReference,
    nvr: usize,
    values: *const ffi::fmi3Int64,
    n_values: usize,
) -> ffi::fmi3Status {
    unsafe {
        setter::<M, i64>(
            c,
            "fmi3SetInt64",
            Fmi3Type::Enumeration,
            vr,
            nvr,
            values,
            n_values,
            |x| {
                i32::try_from(x)
                    .map(Value::Integer)
                    .map_err(|_| format!("{x} is not an item of the enumeration"))
            },
        )
    }
}

/// `fmi3GetBoolean`.
///
/// # Safety
/// `c` as for `call`; arrays as the FMI 3.0 standard defines them.
pub unsafe fn get_boolean<M: Model>(
    c: ffi::fmi3Instance,
    vr: *const ffi::fmi3ValueReference,
    nvr: usize,
    values: *mut ffi::fmi3Boolean,
    n_values: usize,
) -> ffi::fmi3Status {
    unsafe {
        getter::<M, bool>(
            c,
            "fmi3GetBoolean",
            Fmi3Type::Boolean,
            vr,
            nvr,
            values,
            n_values,
            |v| matches!(v, Value::Boolean(true)),
        )
    }
}

/// `fmi3SetBoolean`. The host's C `bool`s are read as bytes (any non-zero
/// byte is true), so a host that passes another value than 0 or 1 is no
/// undefined behaviour here.
///
/// # Safety
/// `c` as for `call`; arrays as the FMI 3.0 standard defines them.
pub unsafe fn set_boolean<M: Model>(
    c: ffi::fmi3Instance,
    vr: *const ffi::fmi3ValueReference,
    nvr: usize,
    values: *const ffi::fmi3Boolean,
    n_values: usize,
) -> ffi::fmi3Status {
    unsafe {
        setter::<M, u8>(
            c,
            "fmi3SetBoolean",
            Fmi3Type::Boolean,
            vr,
            nvr,
            values as *const u8,
            n_values,
            |b| Ok(Value::Boolean(b != 0)),
        )
    }
}

/// A getter or setter of a type the models do not use (Float32, Int8 ..
/// UInt64 but Int32 and Int64, String, Binary, Clock): `fmi3OK` for no value
/// references, else `fmi3Error` naming the first. `values_missing`: the
/// values pointer is NULL while values are expected.
///
/// # Safety
/// `c` as for `call`; `vr` null or `nvr` elements.
pub unsafe fn other_type<M: Model>(
    c: ffi::fmi3Instance,
    func: &'static str,
    type_name: &'static str,
    vr: *const ffi::fmi3ValueReference,
    nvr: usize,
    values_missing: bool,
    setter: bool,
) -> ffi::fmi3Status {
    unsafe {
        call::<M>(c, func, |inst| match slice(vr, nvr) {
            Some(_) if values_missing => null(inst, func, "values"),
            Some(vr) => inst.other_type_access(func, type_name, vr, setter),
            None => null(inst, func, "valueReferences"),
        })
    }
}

/// Any function this FMU does not implement: `fmi3Error` with a log line.
///
/// # Safety
/// `c` as for `call`.
pub unsafe fn unsupported<M: Model>(
    c: ffi::fmi3Instance,
    func: &'static str,
    why: &'static str,
) -> ffi::fmi3Status {
    unsafe { call::<M>(c, func, |inst| inst.unsupported(func, why)) }
}

/// `fmi3DoStep`: writes `eventHandlingNeeded = false`, `terminateSimulation`
/// (true after a discarded step), `earlyReturn = false` and
/// `lastSuccessfulTime`; all four pointers are required.
///
/// # Safety
/// `c` as for `call`; the output pointers null or writable.
#[allow(clippy::too_many_arguments)]
pub unsafe fn do_step<M: Model>(
    c: ffi::fmi3Instance,
    t: ffi::fmi3Float64,
    h: ffi::fmi3Float64,
    _no_set_fmu_state_prior: ffi::fmi3Boolean,
    event_handling_needed: *mut ffi::fmi3Boolean,
    terminate_simulation: *mut ffi::fmi3Boolean,
    early_return: *mut ffi::fmi3Boolean,
    last_successful_time: *mut ffi::fmi3Float64,
) -> ffi::fmi3Status {
    const F: &str = "fmi3DoStep";
    unsafe {
        call::<M>(c, F, |inst| {
            for (p, what) in [
                (event_handling_needed.is_null(), "eventHandlingNeeded"),
                (terminate_simulation.is_null(), "terminateSimulation"),
                (early_return.is_null(), "earlyReturn"),
                (last_successful_time.is_null(), "lastSuccessfulTime"),
            ] {
                if p {
                    return null(inst, F, what);
                }
            }
            let (status, outcome) = inst.do_step(t, h);
            *event_handling_needed = false;
            *terminate_simulation = outcome.terminate_simulation;
            *early_return = false;
            *last_successful_time = outcome.last_successful_time;
            status
        })
    }
}

/// The name of the FMU-state argument in FMI 3.0, for messages.
const STATE: &str = "FMUState";

/// `fmi3GetFMUState`.
///
/// # Safety
/// `c` as for `call`; `s` null or writable.
pub unsafe fn get_fmu_state<M: Model>(
    c: ffi::fmi3Instance,
    s: *mut ffi::fmi3FMUState,
) -> ffi::fmi3Status {
    const F: &str = "fmi3GetFMUState";
    unsafe {
        call::<M>(c, F, |inst| {
            if s.is_null() {
                return null(inst, F, "FMUState");
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

/// `fmi3SetFMUState`.
///
/// # Safety
/// `c` as for `call`.
pub unsafe fn set_fmu_state<M: Model>(
    c: ffi::fmi3Instance,
    s: ffi::fmi3FMUState,
) -> ffi::fmi3Status {
    const F: &str = "fmi3SetFMUState";
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

/// `fmi3FreeFMUState`: frees `*s` and sets it to NULL (`*s == NULL`: nothing).
///
/// # Safety
/// `c` as for `call`; `s` null or writable.
pub unsafe fn free_fmu_state<M: Model>(
    c: ffi::fmi3Instance,
    s: *mut ffi::fmi3FMUState,
) -> ffi::fmi3Status {
    const F: &str = "fmi3FreeFMUState";
    unsafe {
        call::<M>(c, F, |inst| {
            if s.is_null() {
                return null(inst, F, "FMUState");
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
                    "{F}: *FMUState is not a live state of this FMU (freed twice, or from elsewhere)"
                ))
            }
        })
    }
}

/// `fmi3SerializedFMUStateSize`.
///
/// # Safety
/// `c` as for `call`; `size` null or writable.
pub unsafe fn serialized_fmu_state_size<M: Model>(
    c: ffi::fmi3Instance,
    s: ffi::fmi3FMUState,
    size: *mut usize,
) -> ffi::fmi3Status {
    const F: &str = "fmi3SerializedFMUStateSize";
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

/// `fmi3SerializeFMUState`: writes the state into `bytes[..size]`; `size`
/// must be at least [`serialized_fmu_state_size`]'s.
///
/// # Safety
/// `c` as for `call`; `bytes` null or `size` writable bytes.
pub unsafe fn serialize_fmu_state<M: Model>(
    c: ffi::fmi3Instance,
    s: ffi::fmi3FMUState,
    bytes: *mut ffi::fmi3Byte,
    size: usize,
) -> ffi::fmi3Status {
    const F: &str = "fmi3SerializeFMUState";
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
                     (fmi3SerializedFMUStateSize)"
                ));
            }
            let Some(out) = slice_mut(bytes, n) else {
                return null(inst, F, "serializedState");
            };
            out.copy_from_slice(saved.bytes());
            inst.state_call_ok(F)
        })
    }
}

/// `fmi3DeserializeFMUState`: a new state (or the live one in `*s`) from
/// `bytes[..size]`, checked before anything is stored.
///
/// # Safety
/// `c` as for `call`; `bytes` null or `size` readable bytes; `s` null or writable.
pub unsafe fn deserialize_fmu_state<M: Model>(
    c: ffi::fmi3Instance,
    bytes: *const ffi::fmi3Byte,
    size: usize,
    s: *mut ffi::fmi3FMUState,
) -> ffi::fmi3Status {
    const F: &str = "fmi3DeserializeFMUState";
    unsafe {
        call::<M>(c, F, |inst| {
            if s.is_null() {
                return null(inst, F, "FMUState");
            }
            let Some(input) = slice(bytes, size) else {
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

#[cfg(test)]
mod tests {
    use super::resource_folder;
    use std::path::PathBuf;

    #[test]
    fn resource_paths() {
        assert_eq!(
            resource_folder("/tmp/fmu/resources/"),
            Some(PathBuf::from("/tmp/fmu/resources"))
        );
        assert_eq!(
            resource_folder("/tmp/fmu/resources"),
            Some(PathBuf::from("/tmp/fmu/resources"))
        );
        assert_eq!(
            resource_folder("file:///tmp/my%20fmu/resources/"),
            Some(PathBuf::from("/tmp/my fmu/resources"))
        );
        assert_eq!(resource_folder(""), None);
        assert_eq!(resource_folder("/"), Some(PathBuf::from("/")));
    }
}
