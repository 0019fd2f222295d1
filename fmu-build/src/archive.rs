//! FMU archives: `modelDescription.xml`, the binary under
//! `binaries/<platform>/`, `documentation/index.html` and `resources/`.

use anyhow::Result;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use zip::write::SimpleFileOptions;

/// Where the FMU binaries go inside the archive (FMI 2.0 platform name).
pub const PLATFORM: &str = "linux64";

/// File name of the exported robots' binary (`eigenmpc-robot-fmu`).
pub const ROBOT_LIBRARY: &str = "libeigenmpc_robot.so";

/// Where `fmu-build` puts the stripped exported robots' binary under the
/// FMU folder `fmu_dir` (`target/fmu`): `robot/<platform>/`.
pub fn robot_binary_path(fmu_dir: &Path) -> PathBuf {
    fmu_dir.join("robot").join(PLATFORM).join(ROBOT_LIBRARY)
}

/// Writes the FMU archive `path` of `model_identifier`: its description,
/// its binary, its documentation page and `resources` (file name, bytes).
pub fn write_fmu(
    path: &Path,
    model_identifier: &str,
    xml: &str,
    binary: &[u8],
    html: &str,
    resources: &[(&str, &[u8])],
) -> Result<()> {
    let file = std::fs::File::create(path)?;
    let mut zip = zip::ZipWriter::new(file);
    let opts = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    let exe = opts.unix_permissions(0o755);
    zip.start_file("modelDescription.xml", opts)?;
    zip.write_all(xml.as_bytes())?;
    zip.start_file(format!("binaries/{PLATFORM}/{model_identifier}.so"), exe)?;
    zip.write_all(binary)?;
    zip.start_file("documentation/index.html", opts)?;
    zip.write_all(html.as_bytes())?;
    for (name, bytes) in resources {
        zip.start_file(format!("resources/{name}"), opts)?;
        zip.write_all(bytes)?;
    }
    zip.finish()?;
    Ok(())
}
