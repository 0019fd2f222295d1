//! Packaging shared by `fmu-build` and `eigenmpc export`: FMU archives
//! ([`archive`]), the closed loops as SSP archives ([`ssp`]), the export of a
//! robot file as a validated FMU pair ([`export`]) and the pairs this
//! workspace ships, each an export of a robot file in `robots/`
//! ([`shipped`]), for every platform of [`platform`].

pub mod archive;
pub mod export;
pub mod platform;
pub mod shipped;
pub mod ssp;
pub mod validate;
