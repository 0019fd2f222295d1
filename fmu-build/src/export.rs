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
pub use crate::platform::FmiVersion;
use crate::platform::{PLATFORMS, Platform};
use crate::ssp::{self, SspSpec};
use crate::validate;
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
    /// Also FMI 3.0 archives (`fmi3/<name>.fmu`) beside the FMI 2.0 ones
    /// (`<name>.fmu`, always written: the SSP couples them).
    pub fmi3: bool,
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
    /// Every archive written (controller and plant, per FMI version).
    pub archives: Vec<PathBuf>,
    /// The platforms the FMUs carry a binary for, by name; those FMI 2.0
    /// has no name for say "(FMI 3.0 only)".
    pub platforms: Vec<String>,
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
    let Specs {
        specs: [controller, plant],
        family,
    } = specs::<N, S>(system, options)?;
    let versions: &[FmiVersion] = if options.fmi3 {
        &[FmiVersion::Fmi2, FmiVersion::Fmi3]
    } else {
        &[FmiVersion::Fmi2]
    };
    let mut archives = vec![];
    for &version in versions {
        for (spec, family) in [(&controller, family.as_deref()), (&plant, None)] {
            let resources: Vec<(&str, &[u8])> = family
                .map(|f| (FAMILY_FILE, f.as_bytes()))
                .into_iter()
                .collect();
            let path = version.archive(out, &spec.model_name);
            let dir = path.parent().context("archive folder")?;
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
            write_fmu(&path, version, spec, &binaries, &resources)?;
            validate::archive(&path, version, spec, family.is_some())
                .with_context(|| format!("validating {}", path.display()))?;
            archives.push(path);
        }
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
    Ok(Exported {
        controller: (
            controller.model_name.clone(),
            FmiVersion::Fmi2.archive(out, &controller.model_name),
        ),
        plant: (
            plant.model_name.clone(),
            FmiVersion::Fmi2.archive(out, &plant.model_name),
        ),
        ssp,
        specs: [controller, plant],
        archives,
        platforms: binaries
            .iter()
            .map(|(p, _)| match p.fmi2 {
                Some(_) => p.name.to_string(),
                None => format!("{} (FMI 3.0 only)", p.name),
            })
            .collect(),
    })
}

/// What an export's FMUs are, computed from the robot alone (no binary, no
/// archive): the controller's and the plant's specs, from which their model
/// descriptions are written, and the controller's precomputed mode family
/// (`resources/eigenmpc-family.json`). Every number in them is computed
/// with the same bits on every machine (`eigenmpc::math`, nalgebra without
/// run-time kernels), so an export's descriptions and GUIDs do not depend
/// on where it runs: `fmu-build --descriptions` writes them for the shipped
/// pairs, and `tests/same_bits.sh` compares them across machines.
pub struct Specs {
    /// The controller's and the plant's specs.
    pub specs: [ExportSpec; 2],
    /// The controller's mode family as JSON (None: the controller computes
    /// its own).
    pub family: Option<String>,
}

/// The [`Specs`] of `system` exported with `options` (its `binary` and
/// `fmi3` are not used).
pub fn specs<const N: usize, const S: usize>(
    system: &PlanarChain<N>,
    options: &ExportOptions<'_>,
) -> anyhow::Result<Specs> {
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
    Ok(Specs {
        specs: [controller, plant],
        family,
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
                .join(platform.name)
                .join(platform.library(ROBOT_LIB_NAME));
            if path.is_file() {
                found.push((*platform, path));
            }
        }
    }
    found
}

/// Writes the archive `path` of FMI `version` of `spec` with its `binaries`
/// (one per platform), with `resources` besides the spec.
fn write_fmu(
    path: &Path,
    version: FmiVersion,
    spec: &ExportSpec,
    binaries: &[(&'static Platform, Vec<u8>)],
    resources: &[(&str, &[u8])],
) -> anyhow::Result<()> {
    let description = spec.description().map_err(anyhow::Error::msg)?;
    let xml = match version {
        FmiVersion::Fmi2 => fmi2_slave::xml::model_description_xml(&description),
        FmiVersion::Fmi3 => fmi3_slave::xml::model_description_xml(&description),
    };
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
    let mut files = vec![(SPEC_FILE, json.as_bytes())];
    files.extend_from_slice(resources);
    let binaries: Vec<archive::Binary<'_>> = binaries
        .iter()
        .map(|(platform, bytes)| archive::Binary { platform, bytes })
        .collect();
    archive::write_fmu(
        path,
        version,
        &spec.model_name,
        &xml,
        &binaries,
        &html,
        &files,
    )
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
}
