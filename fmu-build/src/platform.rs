//! The platforms every FMU carries a binary for: one table. A platform is a
//! row: where its binary goes in the archive, the Rust target that builds
//! it and the linker, the library's file name. `fmu-build` builds the one
//! FMU binary (`robot-fmu`) once per platform and every archive, shipped or
//! exported, carries all of them.

use std::path::{Path, PathBuf};

/// One platform.
#[derive(Debug, PartialEq, Eq)]
pub struct Platform {
    /// FMI 2.0 name: the folder under `binaries/` (`linux64`, `win64`).
    pub fmi2: &'static str,
    /// FMI 3.0 platform tuple: the folder under `binaries/` of an FMI 3.0
    /// archive (`x86_64-linux`, `x86_64-windows`).
    pub fmi3: &'static str,
    /// Rust target triple.
    pub target: &'static str,
    /// Built by the host's own toolchain (true) or cross-built with
    /// Debian's `rustc-web` and `-Zbuild-std` (false).
    pub native: bool,
    /// The C compiler that links for this target (cross builds), and
    /// compiles the C test hosts.
    pub c_compiler: &'static str,
    /// Shared library file name prefix and extension (`lib` + `.so`,
    /// `` + `.dll`).
    pub library_prefix: &'static str,
    /// Shared library extension, with the dot.
    pub library_suffix: &'static str,
    /// binutils' objcopy for this target (strips the binary).
    pub objcopy: &'static str,
}

/// 64-bit Linux on x86-64: the host's.
pub const LINUX64: Platform = Platform {
    fmi2: "linux64",
    fmi3: "x86_64-linux",
    target: "x86_64-unknown-linux-gnu",
    native: true,
    c_compiler: "gcc",
    library_prefix: "lib",
    library_suffix: ".so",
    objcopy: "objcopy",
};

/// 64-bit Windows: mingw-w64 (`x86_64-pc-windows-gnu`); imports only
/// Windows system libraries.
pub const WIN64: Platform = Platform {
    fmi2: "win64",
    fmi3: "x86_64-windows",
    target: "x86_64-pc-windows-gnu",
    native: false,
    c_compiler: "x86_64-w64-mingw32-gcc",
    library_prefix: "",
    library_suffix: ".dll",
    objcopy: "x86_64-w64-mingw32-objcopy",
};

/// Every platform, the host's first (the one an export loads and steps to
/// validate it).
pub const PLATFORMS: &[&Platform] = &[&LINUX64, &WIN64];

/// The FMI versions an archive can be written for (the one binary exports
/// the functions of both).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FmiVersion {
    /// FMI 2.0 Co-Simulation: `<name>.fmu`.
    Fmi2,
    /// FMI 3.0 Co-Simulation: `fmi3/<name>.fmu`.
    Fmi3,
}

impl FmiVersion {
    /// Where an archive of this version goes under the output folder `out`.
    pub fn archive(self, out: &Path, model_identifier: &str) -> PathBuf {
        match self {
            FmiVersion::Fmi2 => out.join(format!("{model_identifier}.fmu")),
            FmiVersion::Fmi3 => out.join("fmi3").join(format!("{model_identifier}.fmu")),
        }
    }
}

/// The environment variable that narrows the platforms `fmu-build` builds
/// (comma-separated FMI 2.0 names, e.g. `linux64`); unset: all.
pub const PLATFORMS_ENV: &str = "FMU_PLATFORMS";

impl Platform {
    /// The file name of crate `lib_name`'s shared library on this platform.
    pub fn library(&self, lib_name: &str) -> String {
        format!("{}{lib_name}{}", self.library_prefix, self.library_suffix)
    }

    /// The binary's path inside an FMI 2.0 archive of `model_identifier`.
    pub fn archive_path(&self, model_identifier: &str) -> String {
        self.archive_path_in(FmiVersion::Fmi2, model_identifier)
    }

    /// The binary's path inside an archive of FMI `version`.
    pub fn archive_path_in(&self, version: FmiVersion, model_identifier: &str) -> String {
        let folder = match version {
            FmiVersion::Fmi2 => self.fmi2,
            FmiVersion::Fmi3 => self.fmi3,
        };
        format!(
            "binaries/{folder}/{model_identifier}{}",
            self.library_suffix
        )
    }

    /// Where `fmu-build` puts the stripped FMU binary for this platform under
    /// the FMU folder `fmu_dir` (`target/fmu`): `robot/<fmi2>/`.
    pub fn robot_binary_path(&self, fmu_dir: &Path) -> PathBuf {
        fmu_dir
            .join("robot")
            .join(self.fmi2)
            .join(self.library(crate::archive::ROBOT_LIB_NAME))
    }

    /// The platform of FMI 2.0 name `name`.
    pub fn named(name: &str) -> Option<&'static Platform> {
        PLATFORMS.iter().copied().find(|p| p.fmi2 == name)
    }
}

/// The platforms to build: all, or those named in [`PLATFORMS_ENV`] (the
/// host's always included: exports are validated on it).
pub fn selected() -> Result<Vec<&'static Platform>, String> {
    let Ok(list) = std::env::var(PLATFORMS_ENV) else {
        return Ok(PLATFORMS.to_vec());
    };
    let mut chosen = vec![PLATFORMS[0]];
    for name in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let p = Platform::named(name).ok_or_else(|| {
            let known: Vec<&str> = PLATFORMS.iter().map(|p| p.fmi2).collect();
            format!(
                "{PLATFORMS_ENV}: unknown platform '{name}' (known: {})",
                known.join(", ")
            )
        })?;
        if !chosen.contains(&p) {
            chosen.push(p);
        }
    }
    Ok(chosen)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_names_and_archive_paths() {
        assert_eq!(LINUX64.library("eigenmpc_robot"), "libeigenmpc_robot.so");
        assert_eq!(WIN64.library("eigenmpc_robot"), "eigenmpc_robot.dll");
        assert_eq!(
            WIN64.archive_path("EigenMPC"),
            "binaries/win64/EigenMPC.dll"
        );
        assert_eq!(
            LINUX64.robot_binary_path(Path::new("t")),
            Path::new("t/robot/linux64/libeigenmpc_robot.so")
        );
        assert_eq!(Platform::named("win64"), Some(&WIN64));
        assert_eq!(Platform::named("win32"), None);
        assert!(PLATFORMS[0].native);
    }
}
