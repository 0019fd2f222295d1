//! Packaging shared by `fmu-build` (the shipped FMUs) and `eigenmpc export`
//! (a user's robot): FMU archives ([`archive`]) and the closed loops as SSP
//! archives ([`ssp`]).

pub mod archive;
pub mod ssp;
