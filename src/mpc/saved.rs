//! A controller's saved state ([`Controller::save_state`]): everything a
//! later sample depends on, so that a restored controller continues bit for
//! bit (the FMU's `fmi2GetFMUstate`). The solver's workspace and the QP are
//! not saved: the next preparation rebuilds them from the plan.

use super::delay::CommandHistory;
use super::estimator::Ekf;
use super::supervisor::Supervisor;
use super::{Controller, CostParams, MpcError, Reference};
use crate::mechanics::{MechanicalSystem, Vector};
use crate::modes::ChartFamily;
use nalgebra::SVector;
use serde::{Deserialize, Serialize};

/// The state of a [`Controller`] between two samples.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ControllerState<S, const N: usize, const NX: usize> {
    /// The model in use (an adapted one differs from the one built with).
    system: S,
    /// The latest tuning.
    cost: CostParams,
    /// RK4 substeps per shooting interval (follow the model).
    substeps: usize,
    reference: Reference<N>,
    family: Option<ChartFamily<N>>,
    xs: Vec<SVector<f64, NX>>,
    us: Vec<Vector<N>>,
    initialised: bool,
    shift_pending: bool,
    merit_penalty: f64,
    warm_start_usable: bool,
    consecutive_qp_failures: usize,
    estimator: Option<Ekf<N, NX>>,
    /// The past commands (delay, lag and estimator need them).
    history: CommandHistory<N>,
    embedded: Option<SVector<f64, NX>>,
    supervisor: Supervisor<N>,
    /// The torque added to the commands ([`Controller::set_excitation`]).
    excitation: Vector<N>,
    /// The QP solver's warm start ([`crate::qp::QpSolver::save_warm_start`]).
    solver: Vec<f64>,
}

impl<S, const N: usize, const NX: usize> Controller<S, N, NX>
where
    S: MechanicalSystem<N> + Clone,
{
    /// Everything the next samples depend on. Allocates (not for the
    /// sample path).
    pub fn save_state(&self) -> ControllerState<S, N, NX> {
        ControllerState {
            system: self.system.clone(),
            cost: self.config.cost,
            substeps: self.config.substeps,
            reference: self.reference.clone(),
            family: self.family.clone(),
            xs: self.xs.clone(),
            us: self.us.clone(),
            initialised: self.initialised,
            shift_pending: self.shift_pending,
            merit_penalty: self.merit_penalty,
            warm_start_usable: self.warm_start_usable,
            consecutive_qp_failures: self.consecutive_qp_failures,
            estimator: self.estimator.clone(),
            history: self.history.clone(),
            embedded: self.embedded,
            supervisor: self.supervisor.clone(),
            excitation: self.excitation,
            solver: self.solver.save_warm_start(),
        }
    }

    /// Continues from `state`, saved by a controller with the same
    /// configuration (horizon, QP backend, estimator, variant): from here
    /// on this controller computes what that one did. Nothing is changed if
    /// `state` does not fit.
    pub fn restore_state(&mut self, state: ControllerState<S, N, NX>) -> Result<(), MpcError> {
        let nh = self.config.horizon;
        let bad = |what: String| Err(MpcError::InvalidState(what));
        if state.xs.len() != nh + 1 || state.us.len() != nh {
            return bad(format!(
                "a plan of {} intervals for a horizon of {nh}",
                state.us.len()
            ));
        }
        if state.reference.variant() != self.reference.variant() {
            return bad(format!(
                "a {} reference for a {} controller",
                state.reference.variant(),
                self.reference.variant()
            ));
        }
        state.reference.validate().map_err(MpcError::InvalidState)?;
        if state.family.is_some() != self.family.is_some()
            || state.estimator.is_some() != self.estimator.is_some()
        {
            return bad("a state with another mode family or estimator set-up".into());
        }
        if state.history.len() != self.history.len() {
            return bad(format!(
                "a history of {} commands for {} (another delay or lag)",
                state.history.len(),
                self.history.len()
            ));
        }
        let finite = state.merit_penalty.is_finite()
            && state.history.is_finite()
            && state.excitation.iter().all(|v| v.is_finite())
            && state
                .embedded
                .is_none_or(|x| x.iter().all(|v| v.is_finite()))
            && state.xs.iter().all(|x| x.iter().all(|v| v.is_finite()))
            && state.us.iter().all(|u| u.iter().all(|v| v.is_finite()));
        if !finite {
            return bad("non-finite plan, torque or merit penalty".into());
        }
        let mut config = self.config;
        config.cost = state.cost;
        config.substeps = state.substeps;
        config.validate()?;
        self.solver
            .restore_warm_start(&state.solver)
            .map_err(MpcError::InvalidState)?;
        self.config = config;
        self.set_system(state.system);
        self.reference = state.reference;
        if let Some(chart) = self.reference.chart_mut() {
            // Room for a family of any degree, as `ChartFamily::chart`
            // makes it (a restored chart has only its own): a model
            // swapped in later writes into it without allocating.
            for c in chart.coefficients.iter_mut() {
                c.reserve(crate::modes::MAX_FAMILY_DEGREE.saturating_sub(c.len()) + 1);
            }
        }
        self.family = state.family;
        self.xs = state.xs;
        self.us = state.us;
        self.initialised = state.initialised;
        self.shift_pending = state.shift_pending;
        self.merit_penalty = state.merit_penalty;
        self.warm_start_usable = state.warm_start_usable;
        self.consecutive_qp_failures = state.consecutive_qp_failures;
        self.estimator = state.estimator;
        self.history = state.history;
        self.embedded = state.embedded;
        self.supervisor = state.supervisor;
        self.excitation = state.excitation;
        // The QP is rebuilt from the plan (deterministic: the same numbers).
        self.prepared = false;
        self.pending_preparation_time = 0.0;
        Ok(())
    }
}
