//! The EigenMPC command line's library part: the paper-style reports of a
//! closed loop (summary text, CSV, plots), shared by `eigenmpc simulate` and
//! the FMU demo, the robustness sweep (`eigenmpc robustness`) and parameter
//! sweeps (`eigenmpc sweep`). The core crate and the FMU libraries stay free of the CLI,
//! plotting and progress-bar crates.

pub mod paper;
pub mod report;
pub mod robustness;
pub mod sweep;
