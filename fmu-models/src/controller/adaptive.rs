//! The controller with its optional online adaptation ([`Settings::adapt`]):
//! what the FMU and the plain C API run every sample, so that both adapt
//! the same way.

use super::precomputed::PrecomputedFamily;
use super::settings::{ChainController, Settings};
use eigenmpc::adapt::{Adaptation, AdaptationEvent, AdaptationState, AdaptationStatus};
use eigenmpc::identify::BaseParameters;
use eigenmpc::mechanics::PlanarChain;
use eigenmpc::mechanics::Vector;
use eigenmpc::mpc::{ControlOutput, ControllerState};
use nalgebra::SVector;

/// An `N`-joint controller (`NX = 2 N`, `NP` =
/// [`eigenmpc::identify::base_parameter_count`]`(N)`, `NA = NX + NP`) and,
/// with `adapt`, the identification its model follows.
pub struct AdaptiveController<const N: usize, const NX: usize, const NP: usize, const NA: usize> {
    controller: ChainController<N, NX>,
    adaptation: Option<Adaptation<N, NX, NP>>,
    /// Base parameters of the model the controller was built with (None:
    /// a model with joint springs has none).
    prior: Option<BaseParameters<N, NP>>,
}

impl<const N: usize, const NX: usize, const NP: usize, const NA: usize>
    AdaptiveController<N, NX, NP, NA>
{
    /// Builds the controller of `settings` and, with `adapt`, its
    /// adaptation (refused for a model with joint springs: its energy is
    /// not linear in the base parameters). Set-up: allocates, may take tens
    /// of milliseconds (the mode family).
    pub fn new(settings: &Settings<N>) -> Result<Self, String> {
        Self::with_family(settings, None).map(|(c, _)| c)
    }

    /// [`AdaptiveController::new`] taking `precomputed` as the mode family
    /// when it fits ([`Settings::build_with`]; the second value says why
    /// it did not).
    pub fn with_family(
        settings: &Settings<N>,
        precomputed: Option<&PrecomputedFamily<N>>,
    ) -> Result<(Self, Option<String>), String> {
        let (controller, refused) = settings.build_with::<NX>(precomputed)?;
        let params = *controller.system().params();
        let prior = BaseParameters::<N, NP>::of(&params).ok();
        let adaptation = if settings.adapt {
            Some(settings.adaptation::<NX, NP, NA>(&params)?)
        } else {
            None
        };
        Ok((
            Self {
                controller,
                adaptation,
                prior,
            },
            refused,
        ))
    }

    /// One sample at state `z`, `dt` seconds after the previous one:
    /// solves, then feeds the identification with the measured `z` (also
    /// with `state_estimator = ekf`: the filter's estimate leans towards
    /// the model the identification corrects) and the torque that acted
    /// over the sample before the measurement, and takes a ready model
    /// for the next sample. Allocation-free; waits for the worker only
    /// without `adapt_realtime` (offline simulation).
    pub fn step(&mut self, z: &SVector<f64, NX>, dt: f64) -> ControlOutput<N> {
        let out = self.controller.step(z);
        if let Some(adaptation) = &mut self.adaptation {
            let q = Vector::<N>::from_fn(|j, _| z[j]);
            let qd = Vector::<N>::from_fn(|j, _| z[N + j]);
            // The torque that acted before the measurement (the previous
            // command without a declared delay or lag).
            let felt = self.controller.torque_before_measurement();
            adaptation.sample(&mut self.controller, &q, &qd, &felt, dt);
        }
        out
    }

    /// Forgets the plan (as [`eigenmpc::mpc::Controller::reset`]) and the
    /// open identification window: the next sample starts afresh. The
    /// estimate and the adapted model are kept.
    pub fn reset(&mut self) {
        self.controller.reset();
        if let Some(adaptation) = &mut self.adaptation {
            adaptation.restart_window();
        }
    }

    /// The controller.
    pub fn controller(&self) -> &ChainController<N, NX> {
        &self.controller
    }

    /// The controller, for tuning.
    pub fn controller_mut(&mut self) -> &mut ChainController<N, NX> {
        &mut self.controller
    }

    /// The base parameters: the identification's estimate with `adapt`,
    /// else those of the model (None: a model with joint springs).
    pub fn estimate(&self) -> Option<BaseParameters<N, NP>> {
        match &self.adaptation {
            Some(a) => Some(a.identification().estimate()),
            None => self.prior,
        }
    }

    /// Everything the next samples depend on (an FMU's saved state).
    pub fn save_state(&self) -> AdaptiveState<N, NX, NP> {
        AdaptiveState {
            controller: self.controller.save_state(),
            adaptation: self.adaptation.as_ref().map(|a| a.save_state()),
        }
    }

    /// Continues from `state`, saved by a controller built from the same
    /// settings.
    /// A refused state changes nothing: the controller part is restored
    /// first (it checks everything before it changes anything), and put
    /// back when the adaptation part is refused.
    pub fn restore_state(&mut self, state: AdaptiveState<N, NX, NP>) -> Result<(), String> {
        if self.adaptation.is_some() != state.adaptation.is_some() {
            return Err("the saved state has another adapt setting".into());
        }
        let before = self
            .adaptation
            .as_ref()
            .map(|_| self.controller.save_state());
        self.controller
            .restore_state(state.controller)
            .map_err(|e| e.to_string())?;
        if let (Some(a), Some(saved)) = (&mut self.adaptation, state.adaptation)
            && let Err(e) = a.restore_state(saved)
        {
            if let Some(before) = before {
                // The state was this controller's a moment ago.
                let _ = self.controller.restore_state(before);
            }
            return Err(e.to_string());
        }
        Ok(())
    }

    /// Candidates the adaptation refused so far (0 without `adapt`).
    pub fn refused_models(&self) -> usize {
        self.adaptation.as_ref().map_or(0, |a| a.refused())
    }

    /// Models the adaptation's supervisor took back (0 without `adapt`).
    pub fn reverted_models(&self) -> usize {
        self.adaptation.as_ref().map_or(0, |a| a.reverts())
    }

    /// What the adaptation is doing (idle without `adapt`).
    pub fn adaptation_status(&self) -> AdaptationStatus {
        self.adaptation
            .as_ref()
            .map_or(AdaptationStatus::Idle, |a| a.status())
    }

    /// The adaptation's latest event and its number (None: none yet, or no
    /// `adapt`).
    pub fn adaptation_event(&self) -> Option<(usize, AdaptationEvent)> {
        self.adaptation.as_ref().and_then(|a| a.last_event())
    }

    /// Models taken from the identification so far (0 without `adapt`).
    pub fn model_updates(&self) -> usize {
        self.adaptation.as_ref().map_or(0, |a| a.model_updates())
    }
}

/// The state of an [`AdaptiveController`] between two samples.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct AdaptiveState<const N: usize, const NX: usize, const NP: usize> {
    controller: ControllerState<PlanarChain<N>, N, NX>,
    adaptation: Option<AdaptationState<N, NP>>,
}
