//! `fmu-build`: the packaging tool (xtask style).
//!
//! `cargo run -p fmu-build` release-builds the one FMU binary
//! (`eigenmpc-robot-fmu`, exporting the FMI 2.0 and FMI 3.0 functions) for
//! every platform of `fmu_build::platform` (linux64 natively, stripped, its
//! debug information kept apart in `target/fmu/eigenmpc_robot.so.debug`;
//! win64 and aarch64-linux cross-built; `FMU_PLATFORMS` narrows the list)
//! and writes every shipped pair of [`SHIPPED`] as an export of its robot
//! file, exactly as
//! `eigenmpc export --fmi 2,3` writes a user's robot:
//! `target/fmu/<modelIdentifier>.fmu` (FMI 2.0) and
//! `target/fmu/fmi3/<modelIdentifier>.fmu` (FMI 3.0), each with
//! `modelDescription.xml` from the variable table and the robot, one binary
//! per platform, `resources/` with what the instance is and the
//! controller's precomputed mode family, and `documentation/index.html`;
//! each archive is loaded and stepped before the next, and the closed loop
//! goes into an SSP archive. It checks each model description against the
//! checked-in copy in `modelDescription/` (`fmi3/` for FMI 3.0), builds the C library
//! (`libeigenmpc_fmu.so`, the plain C API: [`C_LIBRARY`]) per platform into
//! `target/fmu/c/<platform>/`, generates `include/eigenmpc.h` (the C API with
//! cbindgen, config `cbindgen.toml`, and every shipped FMU's FMI 2.0
//! value-reference and enumeration constants from its variable table) next
//! to the standard FMI 2.0 headers, and checks the book's FMU variable
//! tables (`docs/book`) against the variable tables.
//!
//! A build writes nothing git tracks: where a checked-in description or
//! table differs from the generated one (a developer changed a variable
//! table, a default or a robot file), it fails and names the developer's
//! command that rewrites them, `cargo run --release -p fmu-build --
//! --update-checked-in`. Every number in them has the same bits on every
//! machine (`eigenmpc::math`), so a user's build never finds a difference.
//!
//! `fmu-build --descriptions DIR` computes only the shipped pairs'
//! descriptions and controller mode families (from `robots/` in the
//! current folder, no build) into `DIR`: `tests/same_bits.sh` compares
//! them across machines (native, baseline x86-64 and aarch64 under qemu).
//!
//! Adding a shipped FMU pair is a robot file and one row of [`SHIPPED`]; a
//! platform is one row of `fmu_build::platform::PLATFORMS`.

use fmu_build::archive;
use fmu_build::export::{self, ExportOptions};
use fmu_build::platform::{self, PLATFORMS_ENV, Platform};
use fmu_build::shipped::{SHIPPED, ShippedPair};

use anyhow::{Context, Result, bail};
use eigenmpc::model_file::RobotFile;
use eigenmpc::modes::Family;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A library cargo builds: its package and file.
struct Library {
    /// Cargo package.
    package: &'static str,
    /// Package directory relative to the workspace root (cbindgen's input).
    dir: &'static str,
    /// The crate's `[lib] name` (the cdylib's file name follows the
    /// platform's).
    lib_name: &'static str,
}

/// The one binary of every FMU, shipped or exported.
const ROBOT: Library = Library {
    package: "eigenmpc-robot-fmu",
    dir: "robot-fmu",
    lib_name: archive::ROBOT_LIB_NAME,
};

/// The plain C library: the C API (`eigenmpc_create`, ...) and the
/// `EigenMPC` model's FMI functions, for C programs that link it.
const C_LIBRARY: Library = Library {
    package: "eigenmpc-fmu",
    dir: "controller-fmu",
    lib_name: "eigenmpc_fmu",
};

/// Items of the C API that keep their name in the header.
const C_API_UNPREFIXED: &[&str] = &["EigenMpc", "EigenMpcConfig", "EigenMpcStepInfo"];
/// Prefix of the C API's other items (its constants).
const C_API_PREFIX: &str = "EIGENMPC_";

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

fn release_build(ws: &Workspace, library: &Library) -> Result<()> {
    println!("== cargo build --release -p {}", library.package);
    let status = Command::new(cargo())
        .args(["build", "--release", "-p", library.package])
        .current_dir(&ws.root)
        .status()
        .context("running cargo build")?;
    if !status.success() {
        bail!("release build of {} failed", library.package);
    }
    Ok(())
}

/// Debian's Rust that cross-builds (`rustc-web`, `cargo-web`, with the
/// standard library's sources from `rust-web-src`): rustup cannot add
/// targets here.
const CROSS_CARGO: &str = "/usr/bin/cargo";
const CROSS_RUSTC: &str = "/usr/bin/rustc";
const CROSS_STD_SOURCES: &str = "/usr/lib/rustlib/src/rust/library";

/// Cross release build of `library` for `platform` into
/// `target/cross/<triple>/release/`; returns the built library's path.
/// The standard library is built from source (`-Zbuild-std`, hence
/// `RUSTC_BOOTSTRAP`), without debug information.
fn cross_build(ws: &Workspace, library: &Library, platform: &Platform) -> Result<PathBuf> {
    let linker_found = Command::new(platform.c_compiler)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !Path::new(CROSS_CARGO).is_file()
        || !Path::new(CROSS_RUSTC).is_file()
        || !Path::new(CROSS_STD_SOURCES).is_dir()
        || !linker_found
    {
        bail!(
            "{}: cross-building needs Debian's rustc-web, cargo-web, rust-web-src and {}: run              `bash scripts/ensure-cross-deps.sh` (as root), or build the host's only with              {PLATFORMS_ENV}=linux64",
            platform.name,
            platform.packages
        );
    }
    println!(
        "== cargo build --release -p {} --target {} (cross)",
        library.package, platform.target
    );
    let cross_target = ws.target.join("cross");
    let linker_var = format!(
        "CARGO_TARGET_{}_LINKER",
        platform.target.to_uppercase().replace('-', "_")
    );
    let status = Command::new(CROSS_CARGO)
        .args([
            "build",
            "--release",
            "-p",
            library.package,
            "-Zbuild-std=std,panic_abort",
            "--target",
            platform.target,
            "--target-dir",
        ])
        .arg(&cross_target)
        .env("RUSTC", CROSS_RUSTC)
        .env("RUSTC_BOOTSTRAP", "1")
        .env(linker_var, platform.c_compiler)
        .env("CARGO_PROFILE_RELEASE_DEBUG", "0")
        .env_remove("RUSTUP_TOOLCHAIN")
        .env_remove("CARGO_TARGET_DIR")
        .current_dir(&ws.root)
        .status()
        .with_context(|| format!("running {CROSS_CARGO}"))?;
    if !status.success() {
        bail!(
            "cross build of {} for {} failed",
            library.package,
            platform.name
        );
    }
    Ok(cross_target
        .join(platform.target)
        .join("release")
        .join(platform.library(library.lib_name)))
}

/// The FMU's binary without debug information (the release profile keeps
/// it for profiling: 20-26 MB against 2-3 MB), which goes to
/// `target/fmu/<modelIdentifier>.so.debug`, linked by `.gnu_debuglink` for
/// debuggers. Needs binutils' `objcopy` (Debian `binutils`, installed with
/// gcc by `tests/run.sh`).
fn stripped_binary(ws: &Workspace, library: &Path, platform: &Platform) -> Result<Vec<u8>> {
    let dir = ws.target.join("fmu");
    let name = format!("{}{}", archive::ROBOT_LIB_NAME, platform.library_suffix);
    let debug = dir.join(format!("{name}.debug"));
    let stripped = dir.join(&name);
    let objcopy = |args: &[&std::ffi::OsStr]| -> Result<()> {
        let status = Command::new(platform.objcopy)
            .args(args)
            .status()
            .with_context(|| {
                format!(
                    "running {} (binutils) to strip the FMU binary",
                    platform.objcopy
                )
            })?;
        if !status.success() {
            bail!("{} {args:?} failed", platform.objcopy);
        }
        Ok(())
    };
    if platform.native {
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
    } else {
        // Cross builds carry no debug information; the symbol table goes.
        objcopy(&[
            "--strip-unneeded".as_ref(),
            library.as_os_str(),
            stripped.as_os_str(),
        ])?;
    }
    let binary =
        std::fs::read(&stripped).with_context(|| format!("reading {}", stripped.display()))?;
    std::fs::remove_file(&stripped)?;
    Ok(binary)
}

/// The one FMU binary for `platform` (`eigenmpc export` and the shipped
/// FMUs carry it), stripped, at [`Platform::robot_binary_path`].
fn robot_binary(ws: &Workspace, platform: &Platform) -> Result<PathBuf> {
    let built = if platform.native {
        release_build(ws, &ROBOT)?;
        ws.target
            .join("release")
            .join(platform.library(ROBOT.lib_name))
    } else {
        cross_build(ws, &ROBOT, platform)?
    };
    let binary = stripped_binary(ws, &built, platform)?;
    let path = platform.robot_binary_path(&ws.target.join("fmu"));
    std::fs::create_dir_all(path.parent().context("robot binary folder")?)?;
    std::fs::write(&path, binary)?;
    Ok(path)
}

/// The C library for `platform`, copied to `target/fmu/c/<platform>/`.
fn c_library(ws: &Workspace, platform: &Platform) -> Result<PathBuf> {
    let built = if platform.native {
        release_build(ws, &C_LIBRARY)?;
        ws.target
            .join("release")
            .join(platform.library(C_LIBRARY.lib_name))
    } else {
        cross_build(ws, &C_LIBRARY, platform)?
    };
    let dir = ws.target.join("fmu").join("c").join(platform.name);
    std::fs::create_dir_all(&dir)?;
    let path = dir.join(platform.library(C_LIBRARY.lib_name));
    std::fs::copy(&built, &path).with_context(|| format!("copying {}", built.display()))?;
    Ok(path)
}

/// Writes the shipped `pair` into `target/fmu` (FMI 3.0: `target/fmu/fmi3`)
/// as `eigenmpc export --fmi 2,3` would, from the one binary at `binary`;
/// returns the FMUs' model descriptions as `(file under modelDescription/,
/// text)`.
fn export_pair(ws: &Workspace, pair: &ShippedPair, binary: &Path) -> Result<Vec<(String, String)>> {
    let path = ws.root.join(pair.robot);
    let file = RobotFile::load(&path).with_context(|| format!("{}", path.display()))?;
    check_joints(pair, &file, &path)?;
    let options = export_options(pair, &file, binary);
    let out = ws.target.join("fmu");
    let n = pair.joints;
    let written = eigenmpc::with_joint_count!(
        n,
        |N, S, NP| export::export::<N, S>(&file.chain::<N>()?, &options, &out)?,
        otherwise bail!(eigenmpc::joints::unsupported(n))
    );
    for path in written.archives.iter().chain([&written.ssp]) {
        println!("wrote {}", path.display());
    }
    let mut descriptions = vec![];
    for spec in &written.specs {
        descriptions.extend(descriptions_of(spec)?);
    }
    Ok(descriptions)
}

/// The shipped pair's robot file has the pair's joint count.
fn check_joints(pair: &ShippedPair, file: &RobotFile, path: &Path) -> Result<()> {
    if file.links() != pair.joints {
        bail!(
            "{}: {} links, the shipped pair {} has {}",
            path.display(),
            file.links(),
            pair.ssp,
            pair.joints
        );
    }
    Ok(())
}

/// How a shipped pair is exported: under its own names, at its energy, with
/// the file's smallest torque limit.
fn export_options<'a>(
    pair: &'a ShippedPair,
    file: &RobotFile,
    binary: &'a Path,
) -> ExportOptions<'a> {
    let tau_max = file
        .torque_limits()
        .map_or(1.0, |tl| tl.iter().copied().fold(f64::INFINITY, f64::min));
    ExportOptions {
        names: pair.names(),
        ssp: pair.ssp,
        energy: pair.energy,
        family: Family::InPhase,
        tau_max,
        chart_degree: 9,
        binary,
        fmi3: true,
    }
}

/// A spec's checked-in model descriptions: `<id>.xml` (FMI 2.0) and
/// `fmi3/<id>.xml` (FMI 3.0).
fn descriptions_of(
    spec: &eigenmpc_fmu_models::exported::ExportSpec,
) -> Result<[(String, String); 2]> {
    let description = spec.description().map_err(anyhow::Error::msg)?;
    Ok([
        (
            format!("{}.xml", spec.model_name),
            fmi2_slave::xml::model_description_xml(&description),
        ),
        (
            format!("fmi3/{}.xml", spec.model_name),
            fmi3_slave::xml::model_description_xml(&description),
        ),
    ])
}

/// What to do with the files git tracks that a build generates (the model
/// descriptions in `modelDescription/`, the book's variable tables).
#[derive(Clone, Copy, PartialEq, Eq)]
enum CheckedIn {
    /// Compare them with the generated text (a user's build).
    Check,
    /// Rewrite them (the developer's `--update-checked-in`).
    Update,
}

/// The developer's command that rewrites the checked-in files.
const UPDATE_COMMAND: &str = "cargo run --release -p fmu-build -- --update-checked-in";

impl CheckedIn {
    /// Compares (or, updating, rewrites) the checked-in `path` (relative to
    /// the workspace root) with `generated`; the path if it was out of date.
    fn reconcile(self, ws: &Workspace, path: &str, generated: &str) -> Result<Option<String>> {
        let full = ws.root.join(path);
        let old = std::fs::read_to_string(&full).unwrap_or_default();
        if old == generated {
            return Ok(None);
        }
        if self == CheckedIn::Update {
            std::fs::create_dir_all(full.parent().context("checked-in file's folder")?)?;
            std::fs::write(&full, generated).with_context(|| format!("writing {path}"))?;
        }
        Ok(Some(path.to_string()))
    }
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
    {
        let mut config = cbindgen::Config::from_file(ws.root.join("cbindgen.toml"))
            .map_err(|e| anyhow::anyhow!("cbindgen.toml: {e}"))?;
        config.export.prefix = Some(C_API_PREFIX.into());
        for name in C_API_UNPREFIXED {
            config
                .export
                .rename
                .insert(name.to_string(), name.to_string());
        }
        config.export.renaming_overrides_prefixing = true;
        let bindings = cbindgen::Builder::new()
            .with_config(config)
            .with_crate(ws.root.join(C_LIBRARY.dir))
            .generate()
            .map_err(|e| anyhow::anyhow!("cbindgen on {}: {e}", C_LIBRARY.package))?;
        bindings.write(&mut text);
    }
    let mut text = String::from_utf8(text)?;
    // The value references and enumeration items, from the variable tables,
    // inside the include guard.
    let guard_end = text
        .rfind("#endif")
        .context("no include guard in the cbindgen output")?;
    let mut defines = String::from("\n");
    for fmu in SHIPPED.iter().flat_map(|p| [&p.plant, &p.controller]) {
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

/// The book's chapter with the FMU variable tables, as generated from the
/// variable tables.
fn tables(ws: &Workspace) -> Result<(String, String)> {
    let path = eigenmpc_fmu_models::readme::TABLES_FILE;
    let old = std::fs::read_to_string(ws.root.join(path)).with_context(|| path.to_string())?;
    let new = eigenmpc_fmu_models::readme::update(&old).map_err(|e| anyhow::anyhow!(e))?;
    Ok((path.to_string(), new))
}

/// The model descriptions (FMI 2.0 `<id>.xml`, FMI 3.0 `fmi3/<id>.xml`)
/// and the controllers' mode families (`<id>.family.json`) of the shipped
/// pairs, from the robot files under `root`, without building anything.
fn shipped_descriptions(root: &Path) -> Result<Vec<(String, String)>> {
    let mut files = vec![];
    for pair in SHIPPED {
        let path = root.join(pair.robot);
        let file = RobotFile::load(&path).with_context(|| format!("{}", path.display()))?;
        check_joints(pair, &file, &path)?;
        let options = export_options(pair, &file, Path::new(""));
        let n = pair.joints;
        let specs = eigenmpc::with_joint_count!(
            n,
            |N, S, NP| export::specs::<N, S>(&file.chain::<N>()?, &options)?,
            otherwise bail!(eigenmpc::joints::unsupported(n))
        );
        for spec in &specs.specs {
            files.extend(descriptions_of(spec)?);
        }
        if let Some(family) = specs.family {
            files.push((
                format!("{}.family.json", pair.controller.model_identifier),
                family,
            ));
        }
    }
    Ok(files)
}

/// `fmu-build --descriptions DIR`: [`shipped_descriptions`] of the robot
/// files in the current folder, written into `DIR`.
fn write_descriptions(dir: &Path) -> Result<()> {
    let root = std::env::current_dir()?;
    for (file, text) in shipped_descriptions(&root)? {
        let path = dir.join(&file);
        std::fs::create_dir_all(path.parent().context("description folder")?)?;
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

const USAGE: &str = "usage: fmu-build [--update-checked-in | --descriptions DIR]
  (none)               build the FMU binary and the C library for every platform
                       (FMU_PLATFORMS narrows them), write the shipped FMUs, SSPs and
                       include/eigenmpc.h into target/, and check the checked-in model
                       descriptions and the book's variable tables: a difference fails
  --update-checked-in  the same, rewriting the checked-in files that differ (a
                       developer's command: commit what it rewrote)
  --descriptions DIR   only the shipped pairs' model descriptions and mode families,
                       from robots/ in the current folder, into DIR (no build)";

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let checked_in = match args.iter().map(String::as_str).collect::<Vec<_>>()[..] {
        [] => CheckedIn::Check,
        ["--update-checked-in"] => CheckedIn::Update,
        ["--descriptions", dir] => return write_descriptions(Path::new(dir)),
        ["--help" | "-h"] => {
            println!("{USAGE}");
            return Ok(());
        }
        _ => bail!("unexpected arguments {args:?}\n{USAGE}"),
    };
    let ws = workspace()?;
    std::fs::create_dir_all(ws.target.join("fmu"))?;
    let platforms = platform::selected().map_err(anyhow::Error::msg)?;
    for p in &platforms {
        let robot = robot_binary(&ws, p)?;
        println!(
            "wrote {} (the binary of every FMU, shipped or exported, on {})",
            robot.display(),
            p.name
        );
    }
    let host = archive::robot_binary_path(&ws.target.join("fmu"));
    let mut out_of_date = vec![];
    for pair in SHIPPED {
        for (file, xml) in export_pair(&ws, pair, &host)? {
            let path = format!("modelDescription/{file}");
            out_of_date.extend(checked_in.reconcile(&ws, &path, &xml)?);
        }
    }
    for p in &platforms {
        let path = c_library(&ws, p)?;
        println!("wrote {} (the C library, {})", path.display(), p.name);
    }
    let h = header(&ws)?;
    println!("wrote {}", h.display());
    let (path, text) = tables(&ws)?;
    out_of_date.extend(checked_in.reconcile(&ws, &path, &text)?);
    match (checked_in, out_of_date.is_empty()) {
        (_, true) => Ok(()),
        (CheckedIn::Update, false) => {
            for path in &out_of_date {
                println!("updated {path}: commit it");
            }
            Ok(())
        }
        (CheckedIn::Check, false) => bail!(
            "the checked-in {} differ from what the variable tables, the defaults and \
             robots/ generate (the FMUs in target/fmu are written): a developer's change \
             that did not update them. Run `{UPDATE_COMMAND}` and commit them.",
            out_of_date.join(", ")
        ),
    }
}
