//! Test support: a host-side `logMessage` callback that records messages,
//! for driving an FMU through its C functions in tests.

use crate::ffi;
use std::ffi::{CStr, c_void};
use std::sync::Mutex;

/// One message the FMU sent to the host.
#[derive(Clone, Debug, PartialEq)]
pub struct LogLine {
    /// `fmi3Status` of the message.
    pub status: ffi::fmi3Status,
    /// Log category.
    pub category: String,
    /// The text.
    pub message: String,
}

/// Records every message an FMU instance logs. Keep it alive (and pinned:
/// it is boxed) as long as the instance.
#[derive(Debug, Default)]
pub struct LogCapture {
    lines: Mutex<Vec<LogLine>>,
}

unsafe extern "C" fn capture(
    environment: ffi::fmi3InstanceEnvironment,
    status: ffi::fmi3Status,
    category: ffi::fmi3String,
    message: ffi::fmi3String,
) {
    if environment.is_null() || category.is_null() || message.is_null() {
        return;
    }
    // SAFETY: environment is the LogCapture given as instanceEnvironment;
    // strings are NUL-terminated by the Logger.
    unsafe {
        let capture = &*(environment as *const LogCapture);
        let line = LogLine {
            status,
            category: CStr::from_ptr(category).to_string_lossy().into_owned(),
            message: CStr::from_ptr(message).to_string_lossy().into_owned(),
        };
        if let Ok(mut lines) = capture.lines.lock() {
            lines.push(line);
        }
    }
}

impl LogCapture {
    /// A new, empty capture.
    pub fn new() -> Box<Self> {
        Box::default()
    }

    /// The `logMessage` argument of `fmi3InstantiateCoSimulation`.
    pub fn callback(&self) -> ffi::fmi3LogMessageCallback {
        Some(capture)
    }

    /// The `instanceEnvironment` argument that goes with [`LogCapture::callback`].
    pub fn environment(&self) -> ffi::fmi3InstanceEnvironment {
        self as *const LogCapture as *mut c_void
    }

    /// All messages so far.
    pub fn lines(&self) -> Vec<LogLine> {
        self.lines.lock().map(|l| l.clone()).unwrap_or_default()
    }

    /// True if some message contains all of `needles`.
    pub fn contains(&self, needles: &[&str]) -> bool {
        self.lines()
            .iter()
            .any(|l| needles.iter().all(|n| l.message.contains(n)))
    }

    /// Forgets the messages so far.
    pub fn clear(&self) {
        if let Ok(mut l) = self.lines.lock() {
            l.clear();
        }
    }
}
