//! `fmu-build`: the packaging tool (xtask style).
//!
//! `cargo run -p fmu-build` release-builds every FMU crate (one
//! `cargo build --release -p <crate>` each), writes each FMU's
//! `modelDescription.xml` from its variable table (also into the checked-in
//! `modelDescription/`), zips `target/fmu/<modelIdentifier>.fmu`
//! (`modelDescription.xml`, `binaries/linux64/<modelIdentifier>.so`,
//! `documentation/index.html`; the binary stripped of debug information,
//! which is kept apart in `target/fmu/<modelIdentifier>.so.debug`), the
//! closed loops as SSP archives (`target/fmu/EigenMPC-DoublePendulum.ssp`,
//! [`ssp`]), generates `include/eigenmpc.h` (the plain C
//! API with cbindgen, config `cbindgen.toml`, and every FMU's value-reference
//! and enumeration constants from its variable table) next to the standard
//! FMI 2.0 headers, and rewrites the README's FMU variable tables from the
//! variable tables.
//!
//! Adding an FMU is one entry in [`FMUS`].

use fmu_build::archive;
use fmu_build::ssp;

use anyhow::{Context, Result, bail};
use std::path::PathBuf;
use std::process::Command;

/// One FMU: its cargo package and what the build produces.
struct FmuSpec {
    /// `modelIdentifier` (FMU and shared-library file name).
    model_identifier: &'static str,
    /// Cargo package that builds the cdylib.
    package: &'static str,
    /// Package directory relative to the workspace root.
    dir: &'static str,
    /// File name of the cdylib cargo writes.
    library: &'static str,
    /// Binary of the package that writes modelDescription.xml and index.html.
    describe: &'static str,
    /// Prefix of the FMU's constants (value references, enumeration items,
    /// a C API's constants) in the C header.
    header_prefix: &'static str,
    /// Whether the crate has a plain C API for cbindgen.
    c_api: bool,
    /// Items that keep their name in the header (a plain C API's types).
    header_unprefixed: &'static [&'static str],
}

/// The FMUs this workspace ships.
const FMUS: &[FmuSpec] = &[
    FmuSpec {
        model_identifier: "DoublePendulum",
        package: "double-pendulum-fmu",
        dir: "plant",
        library: "libdouble_pendulum_fmu.so",
        describe: "double-pendulum-describe",
        header_prefix: "DOUBLE_PENDULUM_",
        c_api: false,
        header_unprefixed: &[],
    },
    FmuSpec {
        model_identifier: "EigenMPC",
        package: "eigenmpc-fmu",
        dir: "controller-fmu",
        library: "libeigenmpc_fmu.so",
        describe: "eigenmpc-describe",
        header_prefix: "EIGENMPC_",
        c_api: true,
        // The plain C API (controller-fmu/src/capi.rs) keeps its names.
        header_unprefixed: &["EigenMpc", "EigenMpcConfig", "EigenMpcStepInfo"],
    },
    FmuSpec {
        model_identifier: "TriplePendulum",
        package: "triple-pendulum-fmu",
        dir: "plant3",
        library: "libtriple_pendulum_fmu.so",
        describe: "triple-pendulum-describe",
        header_prefix: "TRIPLE_PENDULUM_",
        c_api: false,
        header_unprefixed: &[],
    },
    FmuSpec {
        model_identifier: "EigenMPC3",
        package: "eigenmpc3-fmu",
        dir: "controller3-fmu",
        library: "libeigenmpc3_fmu.so",
        describe: "eigenmpc3-describe",
        header_prefix: "EIGENMPC3_",
        c_api: false,
        header_unprefixed: &[],
    },
];

struct Workspace {
    root: PathBuf,
    target: PathBuf,
}

fn cargo() -> String {
    std::env::var("CARGO").unwrap_or_else(|_| "cargo".into())
}

fn workspace() -> Result<Workspace> {
    let out = Command::new(cargo())
        .args(["metadata", "--format-version", "1"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .context("running cargo metadata")?;
    if !out.status.success() {
        bail!(
            "cargo metadata failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout)?;
    let path = |key: &str| -> Result<PathBuf> {
        Ok(PathBuf::from(
            meta[key]
                .as_str()
                .with_context(|| format!("no {key} in cargo metadata"))?,
        ))
    };
    Ok(Workspace {
        root: path("workspace_root")?,
        target: path("target_directory")?,
    })
}

fn release_build(ws: &Workspace, fmu: &FmuSpec) -> Result<()> {
    println!("== cargo build --release -p {}", fmu.package);
    let status = Command::new(cargo())
        .args(["build", "--release", "-p", fmu.package])
        .current_dir(&ws.root)
        .status()
        .context("running cargo build")?;
    if !status.success() {
        bail!("release build of {} failed", fmu.package);
    }
    Ok(())
}

/// Runs the FMU's describe binary; returns (modelDescription.xml, index.html).
fn describe(ws: &Workspace, fmu: &FmuSpec) -> Result<(String, String)> {
    let dir = ws
        .target
        .join("fmu")
        .join(format!("{}.sources", fmu.model_identifier));
    std::fs::create_dir_all(&dir)?;
    let bin = ws.target.join("release").join(fmu.describe);
    let status = Command::new(&bin)
        .arg(&dir)
        .status()
        .with_context(|| format!("running {}", bin.display()))?;
    if !status.success() {
        bail!("{} failed", bin.display());
    }
    Ok((
        std::fs::read_to_string(dir.join("modelDescription.xml"))?,
        std::fs::read_to_string(dir.join("index.html"))?,
    ))
}

/// The FMU's binary without debug information (the release profile keeps
/// it for profiling: 20-26 MB against 2-3 MB), which goes to
/// `target/fmu/<modelIdentifier>.so.debug`, linked by `.gnu_debuglink` for
/// debuggers. Needs binutils' `objcopy` (Debian `binutils`, installed with
/// gcc by `tests/run.sh`).
fn stripped_binary(ws: &Workspace, library: &str, name: &str) -> Result<Vec<u8>> {
    let library = ws.target.join("release").join(library);
    let dir = ws.target.join("fmu");
    let debug = dir.join(format!("{name}.so.debug"));
    let stripped = dir.join(format!("{name}.so"));
    let objcopy = |args: &[&std::ffi::OsStr]| -> Result<()> {
        let status = Command::new("objcopy")
            .args(args)
            .status()
            .context("running objcopy (Debian package binutils) to strip the FMU binary")?;
        if !status.success() {
            bail!("objcopy {args:?} failed");
        }
        Ok(())
    };
    objcopy(&[
        "--only-keep-debug".as_ref(),
        library.as_os_str(),
        debug.as_os_str(),
    ])?;
    objcopy(&[
        "--strip-unneeded".as_ref(),
        format!("--add-gnu-debuglink={}", debug.display()).as_ref(),
        library.as_os_str(),
        stripped.as_os_str(),
    ])?;
    let binary =
        std::fs::read(&stripped).with_context(|| format!("reading {}", stripped.display()))?;
    std::fs::remove_file(&stripped)?;
    Ok(binary)
}

fn package(ws: &Workspace, fmu: &FmuSpec, xml: &str, html: &str) -> Result<PathBuf> {
    let binary = stripped_binary(ws, fmu.library, fmu.model_identifier)?;
    let path = ws
        .target
        .join("fmu")
        .join(format!("{}.fmu", fmu.model_identifier));
    archive::write_fmu(&path, fmu.model_identifier, xml, &binary, html, &[])?;
    Ok(path)
}

/// The exported robots' binary (`eigenmpc export` copies it into every
/// FMU it writes), stripped, at [`archive::robot_binary_path`].
fn robot_binary(ws: &Workspace) -> Result<PathBuf> {
    let robot = FmuSpec {
        model_identifier: "eigenmpc_robot",
        package: "eigenmpc-robot-fmu",
        dir: "robot-fmu",
        library: "libeigenmpc_robot.so",
        describe: "",
        header_prefix: "",
        c_api: false,
        header_unprefixed: &[],
    };
    release_build(ws, &robot)?;
    let binary = stripped_binary(ws, robot.library, robot.model_identifier)?;
    let path = archive::robot_binary_path(&ws.target.join("fmu"));
    std::fs::create_dir_all(path.parent().context("robot binary folder")?)?;
    std::fs::write(&path, binary)?;
    Ok(path)
}

/// Updates the checked-in model description; true if it changed.
fn update_checked_in(ws: &Workspace, fmu: &FmuSpec, xml: &str) -> Result<bool> {
    let dir = ws.root.join("modelDescription");
    std::fs::create_dir_all(&dir)?;
    let path = dir.join(format!("{}.xml", fmu.model_identifier));
    let old = std::fs::read_to_string(&path).unwrap_or_default();
    if old == xml {
        return Ok(false);
    }
    std::fs::write(&path, xml)?;
    Ok(true)
}

/// `include/eigenmpc.h` with cbindgen, plus the standard FMI 2.0 headers it
/// includes.
fn header(ws: &Workspace) -> Result<PathBuf> {
    let include = ws.root.join("include");
    std::fs::create_dir_all(&include)?;
    for h in [
        "fmi2Functions.h",
        "fmi2FunctionTypes.h",
        "fmi2TypesPlatform.h",
    ] {
        std::fs::copy(
            ws.root.join("fmi2-slave/fmi-standard2/headers").join(h),
            include.join(h),
        )
        .with_context(|| format!("copying {h} from fmi2-slave/fmi-standard2/headers"))?;
    }
    let out = include.join("eigenmpc.h");
    let mut text = Vec::new();
    let mut first = true;
    for fmu in FMUS.iter().filter(|f| f.c_api) {
        let mut config = cbindgen::Config::from_file(ws.root.join("cbindgen.toml"))
            .map_err(|e| anyhow::anyhow!("cbindgen.toml: {e}"))?;
        config.export.prefix = Some(fmu.header_prefix.into());
        for name in fmu.header_unprefixed {
            config
                .export
                .rename
                .insert(name.to_string(), name.to_string());
        }
        config.export.renaming_overrides_prefixing = true;
        if !first {
            // One include guard and preamble for the whole header.
            config.include_guard = None;
            config.header = None;
            config.autogen_warning = None;
            config.includes.clear();
            config.no_includes = true;
        }
        first = false;
        let bindings = cbindgen::Builder::new()
            .with_config(config)
            .with_crate(ws.root.join(fmu.dir))
            .generate()
            .map_err(|e| anyhow::anyhow!("cbindgen on {}: {e}", fmu.package))?;
        bindings.write(&mut text);
    }
    let mut text = String::from_utf8(text)?;
    // The value references and enumeration items, from the variable tables,
    // inside the include guard.
    let guard_end = text
        .rfind("#endif")
        .context("no include guard in the cbindgen output")?;
    let mut defines = String::from("\n");
    for fmu in FMUS {
        defines.push_str(
            &eigenmpc_fmu_models::products::c_defines(fmu.model_identifier, fmu.header_prefix)
                .map_err(|e| anyhow::anyhow!(e))?,
        );
        defines.push('\n');
    }
    text.insert_str(guard_end, &defines);
    std::fs::write(&out, text)?;
    Ok(out)
}

/// Rewrites the README's FMU variable tables; true if they changed.
fn update_readme(ws: &Workspace) -> Result<bool> {
    let path = ws.root.join("README.md");
    let old = std::fs::read_to_string(&path)?;
    let new = eigenmpc_fmu_models::readme::update(&old).map_err(|e| anyhow::anyhow!(e))?;
    if new == old {
        return Ok(false);
    }
    std::fs::write(&path, new)?;
    Ok(true)
}

fn main() -> Result<()> {
    let ws = workspace()?;
    std::fs::create_dir_all(ws.target.join("fmu"))?;
    for fmu in FMUS {
        release_build(&ws, fmu)?;
        let (xml, html) = describe(&ws, fmu)?;
        if update_checked_in(&ws, fmu, &xml)? {
            println!(
                "updated modelDescription/{}.xml from the variable table: commit it",
                fmu.model_identifier
            );
        }
        let path = package(&ws, fmu, &xml, &html)?;
        println!("wrote {}", path.display());
    }
    let robot = robot_binary(&ws)?;
    println!(
        "wrote {} (the binary of `eigenmpc export`)",
        robot.display()
    );
    for spec in ssp::SSPS {
        let path = ssp::package(&ws.target.join("fmu"), spec)?;
        println!("wrote {}", path.display());
    }
    let h = header(&ws)?;
    println!("wrote {}", h.display());
    if update_readme(&ws)? {
        println!("updated the FMU variable tables of README.md: commit it");
    }
    Ok(())
}
