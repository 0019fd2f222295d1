//! Test support: a host-side logger that records messages, for driving an
//! FMU through its C functions in tests.

use crate::ffi;
use std::ffi::{CStr, c_void};
use std::sync::Mutex;

/// One message the FMU sent to the host.
#[derive(Clone, Debug, PartialEq)]
pub struct LogLine {
    /// `fmi2Status` of the message.
    pub status: ffi::fmi2Status,
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

/// Receives the messages of [`crate::Logger`], which passes no variadic
/// arguments (the message is the format, '%' escaped). Rust cannot define
/// C-variadic functions on stable; with no variadic arguments the variadic
/// and non-variadic C calling conventions agree for these pointer and integer
/// arguments on the supported 64-bit targets. Only for FMUs built on this crate.
unsafe extern "C" fn capture(
    environment: ffi::fmi2ComponentEnvironment,
    _instance_name: ffi::fmi2String,
    status: ffi::fmi2Status,
    category: ffi::fmi2String,
    message: ffi::fmi2String,
) {
    // SAFETY: environment is the LogCapture passed in `callbacks`; strings
    // are NUL-terminated by the Logger.
    unsafe {
        let capture = &*(environment as *const LogCapture);
        let line = LogLine {
            status,
            category: CStr::from_ptr(category).to_string_lossy().into_owned(),
            message: CStr::from_ptr(message).to_string_lossy().replace("%%", "%"),
        };
        if let Ok(mut lines) = capture.lines.lock() {
            lines.push(line);
        }
    }
}

type FixedArgLogger = unsafe extern "C" fn(
    ffi::fmi2ComponentEnvironment,
    ffi::fmi2String,
    ffi::fmi2Status,
    ffi::fmi2String,
    ffi::fmi2String,
);

impl LogCapture {
    /// A new, empty capture.
    pub fn new() -> Box<Self> {
        Box::default()
    }

    /// Callback functions for `fmi2Instantiate` that log into this capture.
    pub fn callbacks(&self) -> ffi::fmi2CallbackFunctions {
        // SAFETY: see `capture`: same argument registers for the arguments
        // the Logger passes.
        let logger: ffi::fmi2CallbackLogger = Some(unsafe {
            std::mem::transmute::<
                FixedArgLogger,
                unsafe extern "C" fn(
                    ffi::fmi2ComponentEnvironment,
                    ffi::fmi2String,
                    ffi::fmi2Status,
                    ffi::fmi2String,
                    ffi::fmi2String,
                    ...
                ),
            >(capture)
        });
        ffi::fmi2CallbackFunctions {
            logger,
            allocateMemory: None,
            freeMemory: None,
            stepFinished: None,
            componentEnvironment: self as *const LogCapture as *mut c_void,
        }
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

/// The cdylib `lib<name>.so` cargo built for the running test: it sits next
/// to the test executable in `target/<profile>/deps` (`cargo test` does not
/// copy it up to `target/<profile>`).
pub fn test_cdylib(name: &str) -> std::path::PathBuf {
    let exe = std::env::current_exe().expect("test executable path");
    let lib = exe
        .parent()
        .expect("test executable directory")
        .join(format!("lib{name}.so"));
    assert!(lib.exists(), "{} not built", lib.display());
    lib
}

/// Asserts that `library` exports all 34 FMI 2.0 common + co-simulation
/// functions and no other `fmi2*` symbol; returns every exported function
/// name (`nm -D --defined-only`, text symbols) for further checks.
pub fn assert_exports_fmi2_cs(library: &std::path::Path) -> Vec<String> {
    let out = std::process::Command::new("nm")
        .args(["-D", "--defined-only"])
        .arg(library)
        .output()
        .expect("nm (binutils) is installed");
    assert!(out.status.success(), "nm failed on {}", library.display());
    let text = String::from_utf8_lossy(&out.stdout);
    let exported: Vec<String> = text
        .lines()
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            (f.len() == 3 && f[1] == "T").then(|| f[2].to_string())
        })
        .collect();
    for name in crate::FMI2_CS_FUNCTIONS {
        assert!(exported.iter().any(|e| e == name), "{name} not exported");
    }
    let fmi: Vec<&String> = exported.iter().filter(|s| s.starts_with("fmi2")).collect();
    assert_eq!(fmi.len(), 34, "{fmi:?}");
    exported
}

/// A co-simulation instance created through an FMU's exported
/// `fmi2Instantiate`, with its log captured (test harnesses of the FMU crates).
pub struct TestInstance {
    /// The component handle.
    pub component: ffi::fmi2Component,
    /// Messages the instance logged.
    pub log: Box<LogCapture>,
    /// Kept alive for the instance's lifetime (the FMU holds a pointer).
    _callbacks: Box<ffi::fmi2CallbackFunctions>,
}

impl TestInstance {
    /// Instantiates `M` through `instantiate` (the crate's exported
    /// `fmi2Instantiate`) with the GUID of its description; panics on NULL.
    pub fn new<M: crate::Model>(instantiate: ffi::fmi2InstantiateTYPE, name: &str) -> Self {
        Self::with_resources::<M>(instantiate, name, None)
    }

    /// As [`TestInstance::new`], for an FMU unpacked with its `resources/`
    /// folder at `resources` (given to the FMU as a `file:///` URI; the
    /// GUID is that of [`crate::Model::description_for`] the folder).
    pub fn with_resources<M: crate::Model>(
        instantiate: ffi::fmi2InstantiateTYPE,
        name: &str,
        resources: Option<&std::path::Path>,
    ) -> Self {
        let log = LogCapture::new();
        let callbacks = Box::new(log.callbacks());
        let name = std::ffi::CString::new(name).expect("instance name");
        let description = M::description_for(resources).expect("description for the resources");
        let guid = std::ffi::CString::new(crate::xml::guid(&description)).expect("guid");
        let location = resources.map(|dir| {
            std::ffi::CString::new(format!("file://{}", dir.display())).expect("resource URI")
        });
        let instantiate = instantiate.expect("fmi2Instantiate");
        // SAFETY: valid NUL-terminated strings and callbacks that outlive the
        // instance (kept in the returned value).
        let component = unsafe {
            instantiate(
                name.as_ptr(),
                ffi::fmi2Type_fmi2CoSimulation,
                guid.as_ptr(),
                location.as_ref().map_or(std::ptr::null(), |l| l.as_ptr()),
                &*callbacks,
                0,
                0,
            )
        };
        assert!(!component.is_null(), "fmi2Instantiate returned NULL");
        Self {
            component,
            log,
            _callbacks: callbacks,
        }
    }
}
