//! FMU archives: `modelDescription.xml`, one binary per platform under
//! `binaries/<platform>/`, `documentation/index.html` and `resources/`.

use crate::platform::{FmiVersion, LINUX64, Platform};
use anyhow::Result;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use zip::write::SimpleFileOptions;

/// The library name of the one FMU binary (`eigenmpc-robot-fmu`'s
/// `[lib] name`); its file name is the platform's
/// ([`Platform::library`]).
pub const ROBOT_LIB_NAME: &str = "eigenmpc_robot";

/// File name of the FMU binary on the host (linux64).
pub const ROBOT_LIBRARY: &str = "libeigenmpc_robot.so";

/// Where `fmu-build` puts the stripped host (linux64) FMU binary under the
/// FMU folder `fmu_dir` (`target/fmu`): `robot/linux64/`; the other
/// platforms' beside it ([`Platform::robot_binary_path`]).
pub fn robot_binary_path(fmu_dir: &Path) -> PathBuf {
    LINUX64.robot_binary_path(fmu_dir)
}

/// One platform's binary of an FMU.
pub struct Binary<'a> {
    /// Its platform.
    pub platform: &'static Platform,
    /// Its bytes.
    pub bytes: &'a [u8],
}

/// Writes the FMU archive `path` of FMI `version` of `model_identifier`: its
/// description, its binaries (one per platform), its documentation page and
/// `resources` (file name, bytes).
pub fn write_fmu(
    path: &Path,
    version: FmiVersion,
    model_identifier: &str,
    xml: &str,
    binaries: &[Binary<'_>],
    html: &str,
    resources: &[(&str, &[u8])],
) -> Result<()> {
    let file = std::fs::File::create(path)?;
    let mut zip = zip::ZipWriter::new(file);
    let opts = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    let exe = opts.unix_permissions(0o755);
    zip.start_file("modelDescription.xml", opts)?;
    zip.write_all(xml.as_bytes())?;
    // A platform this FMI version has no name for is left out.
    for binary in binaries {
        if let Some(path) = binary.platform.archive_path(version, model_identifier) {
            zip.start_file(path, exe)?;
            zip.write_all(binary.bytes)?;
        }
    }
    zip.start_file("documentation/index.html", opts)?;
    zip.write_all(html.as_bytes())?;
    for (name, bytes) in resources {
        zip.start_file(format!("resources/{name}"), opts)?;
        zip.write_all(bytes)?;
    }
    zip.finish()?;
    Ok(())
}
