//! Exporting a robot as a controller FMU, a plant FMU and the SSP that
//! couples them (`eigenmpc export`, and the demo for joint counts without a
//! shipped FMU pair), and the shipped FMUs themselves (`fmu-build`: exports
//! of the robot files in `robots/` under their own names), without compiling
//! anything. Both FMUs carry the one
//! prebuilt binary of `eigenmpc-robot-fmu` and tell it what they are in
//! `resources/eigenmpc-export.json`; each is loaded and stepped before
//! [`export`] returns.

pub use crate::archive::robot_binary_path;
use crate::archive::{self, ROBOT_LIB_NAME, ROBOT_LIBRARY};
use crate::platform::{PLATFORMS, Platform};
use crate::ssp::{self, SspSpec};
use anyhow::{Context, bail};
use eigenmpc::mechanics::{MechanicalSystem, PlanarChain};
use eigenmpc::modes::{Family, linear_modes};
use eigenmpc::mpc::closed_loop::mode_and_chart;
use eigenmpc_fmu_models::controller::precomputed::FAMILY_FILE;
use eigenmpc_fmu_models::exported::{ExportSpec, Kind, RobotExport, SPEC_FILE, family_resource};
pub use eigenmpc_fmu_models::exported::{Named, PairNames};
use std::path::{Path, PathBuf};

/// What to export.
pub struct ExportOptions<'a> {
    /// The FMUs' names and descriptions ([`PairNames::of_robot`] for a
    /// user's robot).
    pub names: PairNames,
    /// The SSP archive's name (`<ssp>.ssp`).
    pub ssp: &'a str,
    /// `E_ref` (J) and the energy of the controller's chart.
    pub energy: f64,
    /// The mode family of the chart.
    pub family: Family,
    /// Torque bound (N m).
    pub tau_max: f64,
    /// Degree of the chart polynomials.
    pub chart_degree: usize,
    /// The exported robots' FMU binary.
    pub binary: &'a Path,
}

/// The files an export wrote.
pub struct Exported {
    /// The controller FMU's `modelIdentifier` and archive.
    pub controller: (String, PathBuf),
    /// The plant FMU's `modelIdentifier` and archive.
    pub plant: (String, PathBuf),
    /// The SSP archive.
    pub ssp: PathBuf,
    /// What each FMU is: the controller's and the plant's specs.
    pub specs: [ExportSpec; 2],
    /// The platforms the FMUs carry a binary for (FMI 2.0 names).
    pub platforms: Vec<&'static str>,
}

/// The default energy of an export: 10 % of the potential energy with every
/// link upright.
pub fn default_energy<const N: usize>(system: &PlanarChain<N>) -> f64 {
    let mut upright = system.equilibrium();
    upright[0] += std::f64::consts::PI;
    0.1 * system.potential(&upright)
}

/// Writes the controller FMU, the plant FMU and their SSP of `system` into
/// `out` (created if missing), each FMU validated by loading and stepping it.
pub fn export<const N: usize, const S: usize>(
    system: &PlanarChain<N>,
    options: &ExportOptions<'_>,
    out: &Path,
) -> anyhow::Result<Exported> {
    for named in [&options.names.controller, &options.names.plant] {
        check_name(&named.model_name).context("FMU name")?;
    }
    let binaries = platform_binaries(options.binary)
        .into_iter()
        .map(|(platform, path)| {
            std::fs::read(&path)
                .with_context(|| format!("reading {}", path.display()))
                .map(|bytes| (platform, bytes))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let family = options.family;
    let energy = options.energy;
    let eigenvector = linear_modes(system)?
        .get(family.index())
        .with_context(|| format!("a {N}-joint chain has no {family} family"))?
        .eigenvector;
    let (_, chart) =
        mode_and_chart::<_, N, S>(system, family.index(), energy, options.chart_degree)
            .with_context(|| format!("{family} eigenmode at {energy} J"))?;
    let [controller, plant] = RobotExport {
        names: &options.names,
        model: system.params(),
        e_ref: energy,
        eigenvector: &std::array::from_fn(|j| eigenvector[j]),
        chart: &chart.coefficients,
        tau_max: options.tau_max,
    }
    .specs()
    .map_err(anyhow::Error::msg)?;
    // The controller's mode family, computed now so that no instance has
    // to (0.5 to 2.5 s for 4 to 6 joints at fmi2ExitInitializationMode).
    let family = family_resource::<N, S>(&controller)
        .map_err(anyhow::Error::msg)
        .context("the controller's mode family")?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let mut paths = vec![];
    for (spec, family) in [(&controller, family.as_deref()), (&plant, None)] {
        let resources: Vec<(&str, &[u8])> = family
            .map(|f| (FAMILY_FILE, f.as_bytes()))
            .into_iter()
            .collect();
        let path = write_fmu(out, spec, &binaries, &resources)?;
        validate(&path, spec, family.is_some())
            .with_context(|| format!("validating {}", path.display()))?;
        paths.push(path);
    }
    let ssp = ssp::package(
        out,
        &SspSpec {
            name: options.ssp,
            controller: &controller.model_name,
            plant: &plant.model_name,
            joints: N,
        },
    )?;
    let plant_path = paths.pop().context("plant archive")?;
    let controller_path = paths.pop().context("controller archive")?;
    Ok(Exported {
        controller: (controller.model_name.clone(), controller_path),
        plant: (plant.model_name.clone(), plant_path),
        ssp,
        specs: [controller, plant],
        platforms: binaries.iter().map(|(p, _)| p.fmi2).collect(),
    })
}

/// `lab-double-pendulum-A0` -> `LabDoublePendulumA0`.
pub fn camel_case(stem: &str) -> String {
    stem.split(|c: char| !c.is_ascii_alphanumeric())
        .filter(|w| !w.is_empty())
        .map(|w| {
            let mut chars = w.chars();
            chars
                .next()
                .map(|c| c.to_ascii_uppercase().to_string() + chars.as_str())
                .unwrap_or_default()
        })
        .collect()
}

/// A name usable as `modelIdentifier` (C identifier, file name); the
/// error quotes the name (the caller says which name it is).
pub fn check_name(name: &str) -> anyhow::Result<()> {
    let ok = name.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !ok {
        bail!("'{name}': an FMU name starts with a letter and has only letters, digits and _");
    }
    Ok(())
}

/// The exported robots' binary: `--binary`, else `fmu-build`'s stripped
/// copy (`target/fmu/robot/linux64/`) or cargo's build next to this
/// executable.
pub fn find_binary(given: Option<&Path>) -> anyhow::Result<PathBuf> {
    if let Some(path) = given {
        if !path.is_file() {
            bail!("--binary {}: no such file", path.display());
        }
        return Ok(path.to_path_buf());
    }
    let exe = std::env::current_exe().context("locating the eigenmpc executable")?;
    let dir = exe.parent().context("the executable's folder")?;
    let candidates = [
        archive::robot_binary_path(&dir.join("../fmu")),
        dir.join(ROBOT_LIBRARY),
        dir.join("../release").join(ROBOT_LIBRARY),
    ];
    candidates
        .iter()
        .find(|p| p.is_file())
        .cloned()
        .with_context(|| {
            format!(
                "no exported-robot FMU binary ({ROBOT_LIBRARY}) next to {}: build it with \
                 `cargo run -p fmu-build` or give --binary FILE",
                exe.display()
            )
        })
}

/// The FMU binary of every platform `fmu-build` built: `host` (the host's,
/// which an export loads to validate) first, then each other platform's
/// found beside it (`robot/<platform>/` next to `robot/linux64/`).
pub fn platform_binaries(host: &Path) -> Vec<(&'static Platform, PathBuf)> {
    let robot_dir = host.parent().and_then(Path::parent);
    let mut found = vec![(PLATFORMS[0], host.to_path_buf())];
    for platform in &PLATFORMS[1..] {
        if let Some(dir) = robot_dir {
            let path = dir
                .join(platform.fmi2)
                .join(platform.library(ROBOT_LIB_NAME));
            if path.is_file() {
                found.push((*platform, path));
            }
        }
    }
    found
}

/// Writes `<out>/<model_name>.fmu` of `spec` with its `binaries` (one per
/// platform), with `resources` besides the spec.
fn write_fmu(
    out: &Path,
    spec: &ExportSpec,
    binaries: &[(&'static Platform, Vec<u8>)],
    resources: &[(&str, &[u8])],
) -> anyhow::Result<PathBuf> {
    let description = spec.description().map_err(anyhow::Error::msg)?;
    let xml = fmi2_slave::xml::model_description_xml(&description);
    let kind = match spec.kind {
        Kind::Controller => eigenmpc_fmu_models::controller::docs::documentation_html(spec.joints),
        Kind::Plant => eigenmpc_fmu_models::plant::docs::documentation_html(spec.joints),
    };
    let intro = format!(
        "<p>{}</p>{kind}<p><b>Export.</b> Written by <code>eigenmpc export</code> (the shipped \
         FMUs by <code>fmu-build</code>, from the robot files in <code>robots/</code>): the \
         robot's parameters are this FMU's start values; <code>resources/{SPEC_FILE}</code> \
         tells the one FMU binary what it is.</p>",
        fmi2_slave::xml::escape(&spec.description)
    );
    let html = fmi2_slave::xml::documentation_html(&description, &intro);
    let json = serde_json::to_string_pretty(spec)?;
    let path = out.join(format!("{}.fmu", spec.model_name));
    let mut files = vec![(SPEC_FILE, json.as_bytes())];
    files.extend_from_slice(resources);
    let binaries: Vec<archive::Binary<'_>> = binaries
        .iter()
        .map(|(platform, bytes)| archive::Binary { platform, bytes })
        .collect();
    archive::write_fmu(&path, &spec.model_name, &xml, &binaries, &html, &files)?;
    Ok(path)
}

/// Loads the archive as a host does (unpacked into a temporary folder, the
/// binary opened, `fmuResourceLocation` a `file:` URI) and runs one second
/// of co-simulation from the start values; `family`: the controller must
/// take the mode family of its resources (its log says so).
fn validate(fmu: &Path, spec: &ExportSpec, family: bool) -> anyhow::Result<()> {
    use fmi2_slave::ffi;
    let dir = std::env::temp_dir().join(format!(
        "eigenmpc-export-{}-{}",
        std::process::id(),
        spec.model_name
    ));
    std::fs::create_dir_all(&dir)?;
    let result = (|| -> anyhow::Result<()> {
        let mut zip = zip::ZipArchive::new(std::fs::File::open(fmu)?)?;
        zip.extract(&dir)?;
        let library = dir.join(PLATFORMS[0].archive_path(&spec.model_name));
        let xml = std::fs::read_to_string(dir.join("modelDescription.xml"))?;
        let guid = xml
            .split("guid=\"")
            .nth(1)
            .and_then(|r| r.split('"').next())
            .context("no guid in modelDescription.xml")?;
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
            let dt = 0.025;
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
                let taken = log
                    .lines()
                    .iter()
                    .any(|l| l.message.contains("the one computed at export"));
                if family && !taken {
                    let lines: Vec<String> =
                        log.lines().iter().map(|l| l.message.clone()).collect();
                    bail!(
                        "the controller did not take the exported mode family: {}",
                        lines.join("; ")
                    );
                }
                let step = sym!(fmi2DoStep);
                for k in 0..40 {
                    ok(step(instance, k as f64 * dt, dt, 1), "fmi2DoStep")?;
                }
                ok(sym!(fmi2Terminate)(instance), "fmi2Terminate")
            })();
            sym!(fmi2FreeInstance)(instance);
            run
        }
    })();
    std::fs::remove_dir_all(&dir).ok();
    result
}

/// `file:///...` of a folder, percent-encoding what a URI path cannot hold.
fn file_uri(path: &Path) -> String {
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

    #[test]
    fn names_from_file_names() {
        assert_eq!(camel_case("lab-double-pendulum-A0"), "LabDoublePendulumA0");
        assert_eq!(camel_case("six_link rigid"), "SixLinkRigid");
        assert!(check_name("SixLink_2").is_ok());
        assert!(check_name("2link").is_err());
        assert!(check_name("a-b").is_err());
        assert!(check_name("").is_err());
    }

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
