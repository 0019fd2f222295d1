//! The EigenMPC command line's library part: the paper-style reports of a
//! closed loop (summary text, CSV, plots), shared by `eigenmpc simulate` and
//! the FMU demo, those of its online adaptation (`simulate --adapt`), the
//! robustness sweep (`eigenmpc robustness`) and parameter sweeps
//! (`eigenmpc sweep`), and the export of a robot as an FMU pair
//! (`eigenmpc export`, the demo). The core crate and the FMU libraries stay free of the CLI,
//! plotting and progress-bar crates.

pub mod adaptation;
/// `eigenmpc export` (in fmu-build, which writes the shipped FMUs the same way).
pub use fmu_build::export;
pub mod paper;
pub mod report;
pub mod robustness;
pub mod sweep;
