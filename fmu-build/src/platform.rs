//! The platforms every FMU carries a binary for: one table. A platform is a
//! row: where its binary goes in the archive, the Rust target that builds
//! it and the linker, the library's file name. `fmu-build` builds the one
//! FMU binary (`robot-fmu`) once per platform and every archive, shipped or
//! exported, carries all of them that its FMI version names: FMI 2.0
//! defines no name for 64-bit ARM Linux, so `aarch64-linux` is in the FMI
//! 3.0 archives only.

use std::path::{Path, PathBuf};

/// One platform.
#[derive(Debug, PartialEq, Eq)]
pub struct Platform {
    /// The platform's name here: `FMU_PLATFORMS`, messages and the folders
    /// under `target/fmu/robot/` and `target/fmu/c/` (the FMI 2.0 name where
    /// there is one).
    pub name: &'static str,
    /// FMI 2.0 name: the folder under `binaries/` (`linux64`, `win64`);
    /// `None` where FMI 2.0 names none (its binary is left out of FMI 2.0
    /// archives).
    pub fmi2: Option<&'static str>,
    /// FMI 3.0 platform tuple: the folder under `binaries/` of an FMI 3.0
    /// archive (`x86_64-linux`, `x86_64-windows`, `aarch64-linux`).
    pub fmi3: &'static str,
    /// Rust target triple.
    pub target: &'static str,
    /// Built by the host's own toolchain (true) or cross-built with
    /// Debian's `rustc-web` and `-Zbuild-std` (false).
    pub native: bool,
    /// The C compiler that links for this target (cross builds), and
    /// compiles the C test hosts.
    pub c_compiler: &'static str,
    /// The Debian packages a cross build needs besides Debian's Rust
    /// (`scripts/ensure-cross-deps.sh` installs them; named in the error
    /// when they are missing).
    pub packages: &'static str,
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
    name: "linux64",
    fmi2: Some("linux64"),
    fmi3: "x86_64-linux",
    target: "x86_64-unknown-linux-gnu",
    native: true,
    c_compiler: "gcc",
    packages: "gcc binutils",
    library_prefix: "lib",
    library_suffix: ".so",
    objcopy: "objcopy",
};

/// 64-bit Windows: mingw-w64 (`x86_64-pc-windows-gnu`); imports only
/// Windows system libraries.
pub const WIN64: Platform = Platform {
    name: "win64",
    fmi2: Some("win64"),
    fmi3: "x86_64-windows",
    target: "x86_64-pc-windows-gnu",
    native: false,
    c_compiler: "x86_64-w64-mingw32-gcc",
    packages: "gcc-mingw-w64-x86-64",
    library_prefix: "",
    library_suffix: ".dll",
    objcopy: "x86_64-w64-mingw32-objcopy",
};

/// 64-bit ARM Linux (boards on robots): FMI 3.0 archives only, FMI 2.0
/// having no name for it.
pub const AARCH64_LINUX: Platform = Platform {
    name: "aarch64-linux",
    fmi2: None,
    fmi3: "aarch64-linux",
    target: "aarch64-unknown-linux-gnu",
    native: false,
    c_compiler: "aarch64-linux-gnu-gcc",
    packages: "gcc-aarch64-linux-gnu",
    library_prefix: "lib",
    library_suffix: ".so",
    objcopy: "aarch64-linux-gnu-objcopy",
};

/// Every platform, the host's first (the one an export loads and steps to
/// validate it).
pub const PLATFORMS: &[&Platform] = &[&LINUX64, &WIN64, &AARCH64_LINUX];

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
/// (comma-separated names, e.g. `linux64,win64`); unset: all.
pub const PLATFORMS_ENV: &str = "FMU_PLATFORMS";

impl Platform {
    /// The file name of crate `lib_name`'s shared library on this platform.
    pub fn library(&self, lib_name: &str) -> String {
        format!("{}{lib_name}{}", self.library_prefix, self.library_suffix)
    }

    /// The binary's path inside an archive of FMI `version`, or `None` if
    /// that version has no name for this platform.
    pub fn archive_path(&self, version: FmiVersion, model_identifier: &str) -> Option<String> {
        let folder = match version {
            FmiVersion::Fmi2 => self.fmi2?,
            FmiVersion::Fmi3 => self.fmi3,
        };
        Some(format!(
            "binaries/{folder}/{model_identifier}{}",
            self.library_suffix
        ))
    }

    /// Where `fmu-build` puts the stripped FMU binary for this platform under
    /// the FMU folder `fmu_dir` (`target/fmu`): `robot/<name>/`.
    pub fn robot_binary_path(&self, fmu_dir: &Path) -> PathBuf {
        fmu_dir
            .join("robot")
            .join(self.name)
            .join(self.library(crate::archive::ROBOT_LIB_NAME))
    }

    /// The platform named `name`.
    pub fn named(name: &str) -> Option<&'static Platform> {
        PLATFORMS.iter().copied().find(|p| p.name == name)
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
            let known: Vec<&str> = PLATFORMS.iter().map(|p| p.name).collect();
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
            WIN64.archive_path(FmiVersion::Fmi2, "EigenMPC").as_deref(),
            Some("binaries/win64/EigenMPC.dll")
        );
        assert_eq!(
            AARCH64_LINUX.archive_path(FmiVersion::Fmi2, "EigenMPC"),
            None
        );
        assert_eq!(
            AARCH64_LINUX
                .archive_path(FmiVersion::Fmi3, "EigenMPC")
                .as_deref(),
            Some("binaries/aarch64-linux/EigenMPC.so")
        );
        assert_eq!(
            LINUX64.robot_binary_path(Path::new("t")),
            Path::new("t/robot/linux64/libeigenmpc_robot.so")
        );
        assert_eq!(Platform::named("win64"), Some(&WIN64));
        assert_eq!(Platform::named("win32"), None);
        assert_eq!(Platform::named("aarch64-linux"), Some(&AARCH64_LINUX));
        assert!(PLATFORMS[0].native);
        // Every name is unique, and so is every folder of each version.
        for (i, a) in PLATFORMS.iter().enumerate() {
            for b in &PLATFORMS[i + 1..] {
                assert_ne!(a.name, b.name);
                assert_ne!(a.fmi3, b.fmi3);
                assert!(a.fmi2.is_none() || a.fmi2 != b.fmi2);
            }
        }
    }
}
