//! Each exported archive is loaded as a host loads it before the export
//! returns: unpacked into a temporary folder, the host platform's binary
//! opened, instantiated with its resources, initialized from its start
//! values and stepped for one second. A controller must take the mode
//! family of its resources (its log says so).

use crate::platform::{FmiVersion, PLATFORMS};
use anyhow::{Context, bail};
use eigenmpc_fmu_models::exported::ExportSpec;
use std::path::Path;

/// The communication step of the check (s) and the steps (one second).
const STEP: f64 = 0.025;
const STEPS: usize = 40;

/// Loads and steps the archive `fmu` of FMI `version` (see the module).
pub fn archive(
    fmu: &Path,
    version: FmiVersion,
    spec: &ExportSpec,
    family: bool,
) -> anyhow::Result<()> {
    let dir = std::env::temp_dir().join(format!(
        "eigenmpc-export-{}-{}-{version:?}",
        std::process::id(),
        spec.model_name
    ));
    std::fs::create_dir_all(&dir)?;
    let result = (|| -> anyhow::Result<()> {
        let mut zip = zip::ZipArchive::new(std::fs::File::open(fmu)?)?;
        zip.extract(&dir)?;
        match version {
            FmiVersion::Fmi2 => fmi2(&dir, spec, family),
            FmiVersion::Fmi3 => fmi3(&dir, spec, family),
        }
    })();
    std::fs::remove_dir_all(&dir).ok();
    result
}

/// The value of attribute `key` (`guid`, `instantiationToken`) of the
/// unpacked archive's model description.
fn attribute(dir: &Path, key: &str) -> anyhow::Result<String> {
    let xml = std::fs::read_to_string(dir.join("modelDescription.xml"))?;
    xml.split(&format!("{key}=\""))
        .nth(1)
        .and_then(|r| r.split('"').next())
        .map(str::to_string)
        .with_context(|| format!("no {key} in modelDescription.xml"))
}

/// A controller that should have taken the exported mode family says so in
/// its log (`lines`).
fn family_taken(lines: &[String], family: bool) -> anyhow::Result<()> {
    if family
        && !lines
            .iter()
            .any(|l| l.contains("the one computed at export"))
    {
        bail!(
            "the controller did not take the exported mode family: {}",
            lines.join("; ")
        );
    }
    Ok(())
}

/// The host platform's binary in an archive of FMI `version` (the host is
/// named in both versions).
fn host_binary(version: FmiVersion, model_identifier: &str) -> String {
    PLATFORMS[0]
        .archive_path(version, model_identifier)
        .expect("the host platform has a folder in every FMI version")
}

fn fmi2(dir: &Path, spec: &ExportSpec, family: bool) -> anyhow::Result<()> {
    use fmi2_slave::ffi;
    let guid = attribute(dir, "guid")?;
    let guid = guid.as_str();
    let library = dir.join(host_binary(FmiVersion::Fmi2, &spec.model_name));
    // SAFETY: the binary is ours (eigenmpc-robot-fmu): loading runs no
    // foreign initialisers.
    let lib = unsafe { ffi::Fmi2Binding::new(&library) }
        .with_context(|| format!("loading {}", library.display()))?;
    let log = fmi2_slave::testing::LogCapture::new();
    let callbacks = log.callbacks();
    let c_name = std::ffi::CString::new(spec.model_name.as_str())?;
    let c_guid = std::ffi::CString::new(guid)?;
    let uri = std::ffi::CString::new(file_uri(&dir.join("resources")))?;
    // The binding's symbols are fn pointers: copy each out.
    macro_rules! sym {
        ($name:ident) => {
            *lib.$name
                .as_ref()
                .map_err(|e| anyhow::anyhow!("{}: {e}", stringify!($name)))?
        };
    }
    let ok = |status: ffi::fmi2Status, call: &str| -> anyhow::Result<()> {
        if status != ffi::fmi2Status_fmi2OK {
            let lines: Vec<String> = log.lines().iter().map(|l| l.message.clone()).collect();
            bail!("{call} returned {status}: {}", lines.join("; "));
        }
        Ok(())
    };
    // SAFETY: the FMI 2.0 calling sequence with valid arguments; the
    // callbacks and strings outlive the instance.
    unsafe {
        let instance = sym!(fmi2Instantiate)(
            c_name.as_ptr(),
            ffi::fmi2Type_fmi2CoSimulation,
            c_guid.as_ptr(),
            uri.as_ptr(),
            &callbacks,
            0,
            1,
        );
        if instance.is_null() {
            let lines: Vec<String> = log.lines().iter().map(|l| l.message.clone()).collect();
            bail!("fmi2Instantiate failed: {}", lines.join("; "));
        }
        let run = (|| -> anyhow::Result<()> {
            ok(
                sym!(fmi2SetupExperiment)(instance, 0, 0.0, 0.0, 0, 0.0),
                "fmi2SetupExperiment",
            )?;
            ok(
                sym!(fmi2EnterInitializationMode)(instance),
                "fmi2EnterInitializationMode",
            )?;
            ok(
                sym!(fmi2ExitInitializationMode)(instance),
                "fmi2ExitInitializationMode",
            )?;
            let lines: Vec<String> = log.lines().iter().map(|l| l.message.clone()).collect();
            family_taken(&lines, family)?;
            let step = sym!(fmi2DoStep);
            for k in 0..STEPS {
                ok(step(instance, k as f64 * STEP, STEP, 1), "fmi2DoStep")?;
            }
            ok(sym!(fmi2Terminate)(instance), "fmi2Terminate")
        })();
        sym!(fmi2FreeInstance)(instance);
        run
    }
}

fn fmi3(dir: &Path, spec: &ExportSpec, family: bool) -> anyhow::Result<()> {
    use fmi3_slave::ffi;
    let token = std::ffi::CString::new(attribute(dir, "instantiationToken")?)?;
    let library = dir.join(host_binary(FmiVersion::Fmi3, &spec.model_name));
    // SAFETY: the binary is ours (eigenmpc-robot-fmu): loading runs no
    // foreign initialisers.
    let lib = unsafe { libloading::Library::new(&library) }
        .with_context(|| format!("loading {}", library.display()))?;
    macro_rules! sym {
        ($ty:ident, $name:literal) => {{
            // SAFETY: the symbol has the standard's type `$ty`.
            let f: libloading::Symbol<ffi::$ty> = unsafe { lib.get($name.as_bytes()) }
                .with_context(|| format!("{} not exported", $name))?;
            (*f).with_context(|| format!("{} is null", $name))?
        }};
    }
    let log = fmi3_slave::testing::LogCapture::new();
    let name = std::ffi::CString::new(spec.model_name.as_str())?;
    // FMI 3.0 passes the resources as a path ending with a separator.
    let resources = std::ffi::CString::new(format!(
        "{}{}",
        dir.join("resources").display(),
        std::path::MAIN_SEPARATOR
    ))?;
    let ok = |status: ffi::fmi3Status, call: &str| -> anyhow::Result<()> {
        if status != ffi::fmi3Status_fmi3OK {
            let lines: Vec<String> = log.lines().iter().map(|l| l.message.clone()).collect();
            bail!("{call} returned {status}: {}", lines.join("; "));
        }
        Ok(())
    };
    let instantiate = sym!(
        fmi3InstantiateCoSimulationTYPE,
        "fmi3InstantiateCoSimulation"
    );
    let enter = sym!(
        fmi3EnterInitializationModeTYPE,
        "fmi3EnterInitializationMode"
    );
    let exit = sym!(fmi3ExitInitializationModeTYPE, "fmi3ExitInitializationMode");
    let step = sym!(fmi3DoStepTYPE, "fmi3DoStep");
    let terminate = sym!(fmi3TerminateTYPE, "fmi3Terminate");
    let free = sym!(fmi3FreeInstanceTYPE, "fmi3FreeInstance");
    // SAFETY: the FMI 3.0 calling sequence with valid arguments; the log
    // capture and the strings outlive the instance.
    unsafe {
        let instance = instantiate(
            name.as_ptr(),
            token.as_ptr(),
            resources.as_ptr(),
            false,
            true,
            false,
            false,
            std::ptr::null(),
            0,
            log.environment(),
            log.callback(),
            None,
        );
        if instance.is_null() {
            let lines: Vec<String> = log.lines().iter().map(|l| l.message.clone()).collect();
            bail!("fmi3InstantiateCoSimulation failed: {}", lines.join("; "));
        }
        let run = (|| -> anyhow::Result<()> {
            ok(
                enter(instance, false, 0.0, 0.0, false, 0.0),
                "fmi3EnterInitializationMode",
            )?;
            ok(exit(instance), "fmi3ExitInitializationMode")?;
            let lines: Vec<String> = log.lines().iter().map(|l| l.message.clone()).collect();
            family_taken(&lines, family)?;
            let (mut event, mut terminate_now, mut early, mut last) = (false, false, false, 0.0);
            for k in 0..STEPS {
                ok(
                    step(
                        instance,
                        k as f64 * STEP,
                        STEP,
                        true,
                        &mut event,
                        &mut terminate_now,
                        &mut early,
                        &mut last,
                    ),
                    "fmi3DoStep",
                )?;
            }
            ok(terminate(instance), "fmi3Terminate")
        })();
        free(instance);
        run
    }
}

/// `file:///...` of a folder, percent-encoding what a URI path cannot hold.
pub(crate) fn file_uri(path: &Path) -> String {
    let mut uri = String::from("file://");
    for b in path.display().to_string().bytes() {
        if b.is_ascii_alphanumeric() || b"/-_.~".contains(&b) {
            uri.push(b as char);
        } else {
            uri.push_str(&format!("%{b:02X}"));
        }
    }
    uri
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    #[test]
    fn uris_of_folders() {
        assert_eq!(
            file_uri(Path::new("/tmp/a b/resources")),
            "file:///tmp/a%20b/resources"
        );
        assert_eq!(
            fmi2_slave::resources::resource_dir(&file_uri(Path::new("/tmp/a b%/r"))),
            Some(PathBuf::from("/tmp/a b%/r"))
        );
    }
}
