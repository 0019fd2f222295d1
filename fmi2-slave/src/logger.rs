//! Logging through the host's `fmi2CallbackLogger`, filtered by the log
//! categories switched with `fmi2SetDebugLogging`.
//!
//! Errors are always reported (they explain an `fmi2Error`). Warnings are
//! reported while debug logging is off; once a host switches logging on with
//! an explicit category list, every category (`logStatusWarning`,
//! `logEvents`, `logAll`) is reported only if listed. `logAll` enables all.

use crate::ffi;
use std::cell::Cell;
use std::ffi::CString;

/// Log categories of the FMU (`<LogCategories>` of the model description).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Category {
    /// Messages explaining an `fmi2Error` / `fmi2Fatal`.
    StatusError,
    /// Messages explaining an `fmi2Warning` / `fmi2Discard`.
    StatusWarning,
    /// Life-cycle events (initialization, termination, reset) and model events.
    Events,
    /// Everything, including a trace of every FMI call.
    All,
}

/// Category names and descriptions, in the order of [`Category`].
pub const LOG_CATEGORIES: [(&str, &str); 4] = [
    ("logStatusError", "Errors: why a call returned fmi2Error"),
    (
        "logStatusWarning",
        "Warnings: why a call returned fmi2Warning or fmi2Discard",
    ),
    (
        "logEvents",
        "Life-cycle events: initialization, termination, reset, parameter changes",
    ),
    ("logAll", "Everything, including a trace of every FMI call"),
];

impl Category {
    fn index(self) -> usize {
        self as usize
    }

    /// The category name as the host sees it.
    pub fn name(self) -> &'static str {
        LOG_CATEGORIES[self.index()].0
    }

    /// The category with that name.
    pub fn from_name(name: &str) -> Option<Self> {
        [
            Category::StatusError,
            Category::StatusWarning,
            Category::Events,
            Category::All,
        ]
        .into_iter()
        .find(|c| c.name() == name)
    }
}

/// Status of an FMI call (`fmi2Status`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Status {
    /// `fmi2OK`.
    Ok,
    /// `fmi2Warning`.
    Warning,
    /// `fmi2Discard`.
    Discard,
    /// `fmi2Error`.
    Error,
    /// `fmi2Fatal`.
    Fatal,
}

impl Status {
    /// The C value.
    pub fn to_ffi(self) -> ffi::fmi2Status {
        match self {
            Status::Ok => ffi::fmi2Status_fmi2OK,
            Status::Warning => ffi::fmi2Status_fmi2Warning,
            Status::Discard => ffi::fmi2Status_fmi2Discard,
            Status::Error => ffi::fmi2Status_fmi2Error,
            Status::Fatal => ffi::fmi2Status_fmi2Fatal,
        }
    }
}

/// The host's logger with the instance's category switches.
pub struct Logger {
    callback: ffi::fmi2CallbackLogger,
    environment: ffi::fmi2ComponentEnvironment,
    instance_name: CString,
    logging_on: bool,
    /// Explicit category list given by the host (`None`: all categories).
    enabled: Option<[bool; 4]>,
    /// Set when a warning was logged during the current call, so the call
    /// returns `fmi2Warning`.
    warned: Cell<bool>,
}

// SAFETY: the callback and the environment pointer belong to the host, which
// by the FMI standard may drive an instance from any thread (never from two at
// once); the logger is only used by the instance that owns it.
unsafe impl Send for Logger {}

impl Logger {
    /// A logger calling `callback` (may be absent: then nothing is logged).
    pub fn new(
        callback: ffi::fmi2CallbackLogger,
        environment: ffi::fmi2ComponentEnvironment,
        instance_name: &str,
        logging_on: bool,
    ) -> Self {
        Self {
            callback,
            environment,
            instance_name: to_cstring(instance_name),
            logging_on,
            enabled: None,
            warned: Cell::new(false),
        }
    }

    /// A logger that discards everything (tests of the safe API).
    pub fn silent(instance_name: &str) -> Self {
        Self::new(None, std::ptr::null_mut(), instance_name, false)
    }

    /// The instance name.
    pub fn instance_name(&self) -> &str {
        self.instance_name.to_str().unwrap_or("")
    }

    /// `fmi2SetDebugLogging`: switches logging and selects categories
    /// (an empty list selects all). Unknown names are returned as an error.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[&str]) -> Result<(), String> {
        let mut enabled = [false; 4];
        for name in categories {
            match Category::from_name(name) {
                Some(c) => enabled[c.index()] = true,
                None => {
                    let known: Vec<&str> = LOG_CATEGORIES.iter().map(|c| c.0).collect();
                    return Err(format!(
                        "unknown log category {name:?} (known: {})",
                        known.join(", ")
                    ));
                }
            }
        }
        self.logging_on = on;
        self.enabled = if categories.is_empty() {
            None
        } else {
            Some(enabled)
        };
        Ok(())
    }

    /// Whether a message of category `c` would reach the host (check before
    /// formatting expensive trace messages).
    pub fn enabled(&self, c: Category) -> bool {
        if self.callback.is_none() {
            return false;
        }
        match c {
            Category::StatusError => true,
            _ if !self.logging_on => c == Category::StatusWarning,
            _ => match self.enabled {
                None => true,
                Some(e) => e[c.index()] || e[Category::All.index()],
            },
        }
    }

    /// Sends `message` with `status` in category `c`, if enabled.
    pub fn log(&self, c: Category, status: Status, message: &str) {
        if !self.enabled(c) {
            return;
        }
        let Some(callback) = self.callback else {
            return;
        };
        // The message is the printf format: '%' escaped, no variadic
        // arguments, so hosts that format and hosts that print the raw
        // string both show the text.
        let message = to_cstring(&message.replace('%', "%%"));
        let category = to_cstring(c.name());
        // SAFETY: the host promised a valid logger in fmi2Instantiate.
        unsafe {
            callback(
                self.environment,
                self.instance_name.as_ptr(),
                status.to_ffi(),
                category.as_ptr(),
                message.as_ptr(),
            );
        }
    }

    /// Logs an error (always reported).
    pub fn error(&self, message: &str) {
        self.log(Category::StatusError, Status::Error, message);
    }

    /// Logs a warning and makes the current call return `fmi2Warning`.
    pub fn warning(&self, message: &str) {
        self.warned.set(true);
        self.log(Category::StatusWarning, Status::Warning, message);
    }

    /// Logs a warning under `logStatusWarning` without changing the call's
    /// status: for behaviour that is documented and was carried out (some
    /// masters stop at the first `fmi2Warning`).
    pub fn notice(&self, message: &str) {
        self.log(Category::StatusWarning, Status::Warning, message);
    }

    /// Logs an event (`logEvents`).
    pub fn event(&self, message: &str) {
        self.log(Category::Events, Status::Ok, message);
    }

    /// Logs a call trace (`logAll`); the closure only runs when enabled.
    pub fn trace(&self, message: impl FnOnce() -> String) {
        if self.enabled(Category::All) {
            self.log(Category::All, Status::Ok, &message());
        }
    }

    /// Clears and returns the "warned during this call" flag.
    pub(crate) fn take_warned(&self) -> bool {
        self.warned.replace(false)
    }
}

fn to_cstring(s: &str) -> CString {
    CString::new(s.replace('\0', " ")).unwrap_or_default()
}
