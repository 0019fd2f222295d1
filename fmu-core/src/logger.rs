//! Logging to the host, filtered by the log categories the host switches
//! (`fmi2SetDebugLogging`): the filter is here, the host's callback is a
//! [`LogSink`] of the FMI version in use (`fmi2_slave::sink`).
//!
//! Errors are always reported (they explain an `fmi2Error`). Warnings are
//! reported while debug logging is off; once a host switches logging on with
//! an explicit category list, every category (`logStatusWarning`,
//! `logEvents`, `logAll`) is reported only if listed. `logAll` enables all.

use std::cell::Cell;
use std::ffi::CString;

/// Where the messages a [`Logger`] lets through go: the host's logger
/// callback of one FMI version.
pub trait LogSink: Send {
    /// Delivers one message of `instance` (as given at instantiation).
    fn deliver(&self, instance: &CString, status: Status, category: &str, message: &str);
}

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
        "Warnings: why a call returned fmi2Warning or fmi2Discard; notices (status OK) of documented behaviour a call carried out",
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

/// The host's logger with the instance's category switches.
pub struct Logger {
    sink: Option<Box<dyn LogSink>>,
    instance_name: CString,
    logging_on: bool,
    /// Explicit category list given by the host (`None`: all categories).
    enabled: Option<[bool; 4]>,
    /// Set when a warning was logged during the current call, so the call
    /// returns `fmi2Warning`.
    warned: Cell<bool>,
}

impl Logger {
    /// A logger delivering to `sink` (may be absent: then nothing is logged).
    pub fn new(sink: Option<Box<dyn LogSink>>, instance_name: &str, logging_on: bool) -> Self {
        Self {
            sink,
            instance_name: to_cstring(instance_name),
            logging_on,
            enabled: None,
            warned: Cell::new(false),
        }
    }

    /// A logger that discards everything (tests of the safe API).
    pub fn silent(instance_name: &str) -> Self {
        Self::new(None, instance_name, false)
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
        if self.sink.is_none() {
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
        if let Some(sink) = &self.sink {
            sink.deliver(&self.instance_name, status, c.name(), message);
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

    /// Logs a notice under `logStatusWarning` at status OK, the call's own
    /// status: for behaviour that is documented and was carried out (some
    /// masters stop at the first `fmi2Warning`, and a message a host shows
    /// as a warning must come with one).
    pub fn notice(&self, message: &str) {
        self.log(Category::StatusWarning, Status::Ok, message);
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
    pub fn take_warned(&self) -> bool {
        self.warned.replace(false)
    }
}

/// `s` as a C string (interior NULs become spaces).
pub fn to_cstring(s: &str) -> CString {
    CString::new(s.replace('\0', " ")).unwrap_or_default()
}
