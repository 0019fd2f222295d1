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
//! - [`math`]: elementary functions with the same bits on every machine (the
//!   shipped FMUs' defaults and GUIDs do not depend on where they are built);
//! - [`integrate`]: RK4 with sensitivities and adaptive Dormand-Prince 5(4);
//! - [`modes`]: linear modes, nonlinear eigenmodes (brake orbits) continued in
//!   energy, the polynomial mode chart `X(s)` and its family over energy;
//! - [`mpc`]: the EigenMPC controller (real-time iterations);
//! - [`identify`], [`adapt`]: online identification of the robot from its
//!   energy balance, and the controller's model following it;
//! - [`robustness`]: closed loops with noise, delay, a sluggish motor and a
//!   plant that is not the model.
//!
//! # The controller in a Rust loop
//!
//! The paper's scenario: the curved EigenMPC controller drives the double
//! pendulum from `q = (0.05, 0.05)` at rest onto its in-phase eigenmode at
//! `E_ref = 14 J` with `|tau| <= 1 N m`. Each sample the controller gets the
//! measured state and returns the torque to hold until the next one; the plant
//! here is the same model stepped with RK4 (put your robot's measurement in its
//! place).
//!
//! ```
//! use eigenmpc::integrate::rk4_step;
//! use eigenmpc::mechanics::{DoublePendulum, MechanicalSystem};
//! use eigenmpc::modes::{Chart, ContinuationOptions, eigenmode_family, linear_modes};
//! use eigenmpc::mpc::{Controller, MpcConfig, Reference, Variant};
//! use nalgebra::SVector;
//!
//! let robot = DoublePendulum::default(); // 1 kg point masses on 1 m links
//! let config = MpcConfig::paper(Variant::Curved); // E_ref 14 J, tau_max 1 N m, dt 25 ms
//! let (e_ref, tau_max, dt) = (config.cost.e_ref, config.tau_max, config.dt);
//!
//! // The in-phase eigenmode at E_ref and its chart X(s), the curved cost's guide.
//! let eigenvector = linear_modes(&robot)?[0].eigenvector;
//! let options = ContinuationOptions::default();
//! let mode = eigenmode_family::<_, 2, 4>(&robot, 0, &[e_ref], &options)?.remove(0);
//! let chart = Chart::fit(&mode.path, &eigenvector, &robot.equilibrium(), 9)?;
//! let reference = Reference::with_chart(Variant::Curved, chart);
//! let mut controller = Controller::<_, 2, 4>::new(robot, config, reference)?;
//!
//! let mut z = SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0); // (q, qd)
//! let e_start = controller.energy(&z);
//! // 10 s: 400 samples of 25 ms.
//! for _ in 0..400 {
//!     let out = controller.step(&z); // the measured state in, the torque out
//!     assert!(out.status.is_ok());
//!     assert!(out.tau.amax() <= tau_max);
//!     // The plant: four RK4 steps per sample with the torque held.
//!     for _ in 0..4 {
//!         z = rk4_step::<_, 2, 4>(&robot, &z, &out.tau, dt / 4.0);
//!     }
//! }
//! let e_end = controller.energy(&z);
//! // With 1 N m the pump-up takes about 20 s: after 10 s the pendulum has
//! // gained about 4 J, on its way up to E_ref.
//! println!("energy {e_start:.3} J -> {e_end:.3} J (E_ref {e_ref} J)");
//! assert!(e_end > e_start + 3.0 && e_end < e_ref);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod adapt;
pub mod identify;
pub mod integrate;
pub mod joints;
pub mod math;
pub mod mechanics;
#[cfg(feature = "files")]
pub mod model_file;
pub mod modes;
pub mod mpc;
pub mod noise;
pub mod qp;
#[cfg(feature = "tooling")]
pub mod robustness;
pub mod state_parameter_ekf;
