//! The host's `fmi2CallbackLogger` as the core logger's [`LogSink`], and the
//! FMI 2.0 values of the core's [`Status`].

use crate::ffi;
use fmu_core::logger::{LogSink, Status, to_cstring};
use std::ffi::CString;

/// The `fmi2Status` of a status.
pub trait ToFfi {
    /// The C value.
    fn to_ffi(self) -> ffi::fmi2Status;
}

impl ToFfi for Status {
    fn to_ffi(self) -> ffi::fmi2Status {
        match self {
            Status::Ok => ffi::fmi2Status_fmi2OK,
            Status::Warning => ffi::fmi2Status_fmi2Warning,
            Status::Discard => ffi::fmi2Status_fmi2Discard,
            Status::Error => ffi::fmi2Status_fmi2Error,
            Status::Fatal => ffi::fmi2Status_fmi2Fatal,
        }
    }
}

/// The host's logger callback and environment from `fmi2Instantiate`.
pub struct Fmi2Sink {
    callback: unsafe extern "C" fn(
        ffi::fmi2ComponentEnvironment,
        ffi::fmi2String,
        ffi::fmi2Status,
        ffi::fmi2String,
        ffi::fmi2String,
        ...
    ),
    environment: ffi::fmi2ComponentEnvironment,
}

// SAFETY: the callback and the environment pointer belong to the host, which
// by the FMI standard may drive an instance from any thread (never from two at
// once); the sink is only used by the instance that owns it.
unsafe impl Send for Fmi2Sink {}

impl Fmi2Sink {
    /// The sink of `callback` (None when the host gave no logger).
    pub fn boxed(
        callback: ffi::fmi2CallbackLogger,
        environment: ffi::fmi2ComponentEnvironment,
    ) -> Option<Box<dyn LogSink>> {
        callback.map(|callback| {
            Box::new(Self {
                callback,
                environment,
            }) as Box<dyn LogSink>
        })
    }
}

impl LogSink for Fmi2Sink {
    fn deliver(&self, instance: &CString, status: Status, category: &str, message: &str) {
        // The message is the printf format: '%' escaped, no variadic
        // arguments, so hosts that format and hosts that print the raw
        // string both show the text.
        let message = to_cstring(&message.replace('%', "%%"));
        let category = to_cstring(category);
        // SAFETY: the host promised a valid logger in fmi2Instantiate.
        unsafe {
            (self.callback)(
                self.environment,
                instance.as_ptr(),
                status.to_ffi(),
                category.as_ptr(),
                message.as_ptr(),
            );
        }
    }
}
