//! # EigenMPC
//!
//! A Rust implementation of EigenMPC (Coelho et al., "EigenMPC: an
//! eigenmanifold-inspired model-predictive control framework for exciting
//! efficient oscillations in mechanical systems"):
//!
//! - [`mechanics`]: simple mechanical systems `M(q) qdd + C qd + dV/dq = tau`,
//!   the paper's double pendulum as a planar serial chain, energy and exact
//!   derivatives;
//! - [`integrate`]: RK4 with sensitivities and adaptive Dormand-Prince 5(4);
//! - [`modes`]: linear modes, nonlinear eigenmodes (brake orbits) continued in
//!   energy, and the polynomial mode chart `X(s)`.

pub mod integrate;
pub mod mechanics;
pub mod modes;
pub mod mpc;
pub mod qp;
pub mod report;
