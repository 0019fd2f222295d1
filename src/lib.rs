//! # EigenMPC
//!
//! A Rust implementation of EigenMPC (Coelho et al., "EigenMPC: an
//! eigenmanifold-inspired model-predictive control framework for exciting
//! efficient oscillations in mechanical systems"):
//!
//! - [`mechanics`]: simple mechanical systems `M(q) qdd + C qd + dV/dq +
//!   tau_f(qd) = tau`, planar chains of rigid links with geared motors and
//!   friction (the paper's double pendulum is the point-mass 2-link chain),
//!   energy and exact derivatives;
//! - [`joints`]: the joint counts compiled to fixed sizes (one table) and
//!   [`with_joint_count!`], the dispatch from a count known at run time;
//! - [`model_file`]: robots from JSON/YAML parameter files;
//! - [`integrate`]: RK4 with sensitivities and adaptive Dormand-Prince 5(4);
//! - [`modes`]: linear modes, nonlinear eigenmodes (brake orbits) continued in
//!   energy, the polynomial mode chart `X(s)` and its family over energy;
//! - [`mpc`]: the EigenMPC controller (real-time iterations);
//! - [`identify`], [`adapt`]: online identification of the robot from its
//!   energy balance, and the controller's model following it;
//! - [`robustness`]: closed loops with noise, delay, a sluggish motor and a
//!   plant that is not the model.

pub mod adapt;
pub mod identify;
pub mod integrate;
pub mod joints;
pub mod mechanics;
#[cfg(feature = "files")]
pub mod model_file;
pub mod modes;
pub mod mpc;
pub mod qp;
#[cfg(feature = "tooling")]
pub mod robustness;
