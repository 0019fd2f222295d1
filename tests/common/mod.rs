//! Shared test helpers.
pub mod qp_reference;
