//! The host's `fmi3LogMessageCallback` as the core logger's [`LogSink`], and
//! the FMI 3.0 values of the core's [`Status`].

use crate::ffi;
use fmu_core::logger::{LogSink, Status, to_cstring};
use std::ffi::CString;

/// The `fmi3Status` of a status.
pub trait ToFfi {
    /// The C value.
    fn to_ffi(self) -> ffi::fmi3Status;
}

impl ToFfi for Status {
    fn to_ffi(self) -> ffi::fmi3Status {
        match self {
            Status::Ok => ffi::fmi3Status_fmi3OK,
            Status::Warning => ffi::fmi3Status_fmi3Warning,
            Status::Discard => ffi::fmi3Status_fmi3Discard,
            Status::Error => ffi::fmi3Status_fmi3Error,
            Status::Fatal => ffi::fmi3Status_fmi3Fatal,
        }
    }
}

/// The host's `logMessage` callback and `instanceEnvironment` from
/// `fmi3InstantiateCoSimulation`.
pub struct Fmi3Sink {
    callback: unsafe extern "C" fn(
        ffi::fmi3InstanceEnvironment,
        ffi::fmi3Status,
        ffi::fmi3String,
        ffi::fmi3String,
    ),
    environment: ffi::fmi3InstanceEnvironment,
}

// SAFETY: the callback and the environment pointer belong to the host, which
// by the FMI standard may drive an instance from any thread (never from two at
// once); the sink is only used by the instance that owns it.
unsafe impl Send for Fmi3Sink {}

impl Fmi3Sink {
    /// The sink of `callback` (None when the host gave no callback).
    pub fn boxed(
        callback: ffi::fmi3LogMessageCallback,
        environment: ffi::fmi3InstanceEnvironment,
    ) -> Option<Box<dyn LogSink>> {
        callback.map(|callback| {
            Box::new(Self {
                callback,
                environment,
            }) as Box<dyn LogSink>
        })
    }
}

impl LogSink for Fmi3Sink {
    fn deliver(&self, _instance: &CString, status: Status, category: &str, message: &str) {
        // FMI 3.0's logMessage takes the plain text (no printf format, no
        // instance name: the environment identifies the instance).
        let message = to_cstring(message);
        let category = to_cstring(category);
        // SAFETY: the host promised a valid callback at instantiation.
        unsafe {
            (self.callback)(
                self.environment,
                status.to_ffi(),
                category.as_ptr(),
                message.as_ptr(),
            );
        }
    }
}
