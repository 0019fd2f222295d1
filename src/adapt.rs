//! Online adaptation of a controller's model, safe to leave on: the
//! energy-balance identification ([`crate::identify`]) is fed every sample
//! with the torque the robot felt over the measured interval (after the
//! controller's declared measurement delay and actuator lag,
//! [`Controller::torque_before_measurement`]); a model is made of its
//! estimate only when it
//!
//! 1. is physical and inside a trust region around the model in use (a
//!    longer step is shortened to the region's edge);
//! 2. explains the windows that arrive *after* it was formed (held out from
//!    it) significantly better than the model in use;
//!
//! and, once swapped in, a **supervisor** watches the closed loop: when the
//! energy error or the torque rose over a window, the previous model comes
//! back ([`AdaptationEvent::Reverted`]). Refusals are counted per reason
//! ([`Refusal`]) so that a caller logs each reason once.
//!
//! A new model's eigenmode family takes tens of milliseconds: it is computed
//! on a worker thread while the candidate is being validated, never inside
//! a sample. The per-sample path ([`Adaptation::sample`]) does not allocate
//! and never waits (unless `synchronous`, for offline simulation): it feeds
//! the identification, and at most once per `period` samples looks at the
//! candidate through a mutex it only `try_lock`s. Families the controller
//! drops are handed back to the worker, which frees them.

use crate::identify::{
    BaseParameters, EnergyBalanceRls, IdentifyError, RlsOptions, WindowEquation, energy_features,
};
use crate::mechanics::{PlanarChain, PlanarChainParams, Vector};
use crate::modes::{ChartFamily, FamilyOptions};
use crate::mpc::{Controller, PREDICTION_SUBSTEPS, prediction_model};
use nalgebra::SVector;
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;

/// Samples over which the recent orbit's energy features are averaged (an
/// exponential mean; 10 s at the usual 25 ms).
const ORBIT_MEMORY: usize = 400;

/// Time over which the energy error is averaged (an exponential mean of
/// its square, s) before it counts as off target: a limit cycle about the
/// wrong orbit passes through the 5 % band twice a period, which reset a
/// per-sample count (measured: a rough model of A0 under noise held such a
/// cycle at -20 % and full torque for 100 s without a model tried).
const OFF_TARGET_SMOOTHING: f64 = 2.0;

/// Standard deviations by which the estimate's energy along the orbit must
/// differ from the model in use's to rescale a candidate while it is
/// known less well than `max_orbit_uncertainty` ([`Adaptation::orbit_scale`]).
const ORBIT_SIGNIFICANCE: f64 = 3.0;

/// When and how the model follows the estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptOptions {
    /// Samples between two looks at the estimate (>= 1).
    pub period: usize,
    /// Relative change of a base parameter (against its value in use plus
    /// the identification's `prior_floor`) that makes a candidate model.
    pub min_change: f64,
    /// Largest relative change of a base parameter per model (the trust
    /// region); a longer step is shortened to its edge.
    pub trust_region: f64,
    /// Relative standard deviation of the estimate's energy scale
    /// ([`EnergyBalanceRls::scale_uncertainty`]) above which a candidate
    /// keeps the scale of the model in use.
    pub max_scale_uncertainty: f64,
    /// Relative standard deviation of the estimate's energy along the
    /// recent orbit below which such a candidate is scaled to it (see
    /// [`Adaptation`]; measured on the 24 rough lab models of issue 37
    /// under noise: within 2 %, 6 runs of 24 with the EKF and 4 without;
    /// within 3 %, 8 and 7; within 4 %, no more).
    pub max_orbit_uncertainty: f64,
    /// Held-out windows a candidate is scored on before it may be taken.
    pub min_validation_windows: usize,
    /// Held-out windows after which a candidate not shown better is refused.
    pub max_validation_windows: usize,
    /// Samples the supervisor waits after a model change before it judges.
    pub settle_samples: usize,
    /// Samples of each window the supervisor compares (before the change,
    /// and at the end of its watch).
    pub judge_samples: usize,
    /// Time the energy must stay outside the 5 % band before the
    /// estimate is tried without a steady loop, as after a stall (s).
    pub stuck_time: f64,
    /// Top of a new model's mode family (J); `<= 0`: the default of
    /// [`FamilyOptions::for_system`] for the new model.
    pub family_energy_max: f64,
    /// Identification settings.
    pub rls: RlsOptions,
    /// Offline simulation: wait for the worker's model at the next look
    /// (deterministic closed loops whatever the machine's speed). Never for
    /// a real-time loop.
    pub synchronous: bool,
    /// With a filter ([`Adaptation::set_filter`]): standard deviation of
    /// the excitation torque added to every joint's command over the first
    /// `excitation_time`, as a share of `tau_max` (0: none; see
    /// [`Controller::set_excitation`]). The lab pendulums' rough models
    /// under noise, 120 s (`cli/tests/adapt_rough_noise.rs`): 41 of 42
    /// within 2 % at 0.2 or 0.3, 33 without.
    pub excitation: f64,
    /// Time from the start over which the filter is excited (s).
    pub excitation_time: f64,
    /// Samples each excitation value is held (>= 1; 4 at 25 ms: a torque
    /// up to about 5 Hz, which the chain follows).
    pub excitation_hold: usize,
}

impl Default for AdaptOptions {
    fn default() -> Self {
        Self {
            period: 40,
            min_change: 2e-3,
            trust_region: 0.3,
            max_scale_uncertainty: 0.02,
            max_orbit_uncertainty: 0.03,
            min_validation_windows: 3,
            max_validation_windows: 12,
            settle_samples: 160,
            judge_samples: 80,
            stuck_time: 30.0,
            family_energy_max: -1.0,
            rls: RlsOptions::default(),
            synchronous: false,
            excitation: 0.3,
            excitation_time: 40.0,
            excitation_hold: 4,
        }
    }
}

impl AdaptOptions {
    /// Checks the options; the message names the offending one.
    pub fn validate(&self) -> Result<(), IdentifyError> {
        let bad = |what: String| Err(IdentifyError::NotPhysical(what));
        for (name, v) in [
            ("min_change", self.min_change),
            ("trust_region", self.trust_region),
            ("max_scale_uncertainty", self.max_scale_uncertainty),
            ("max_orbit_uncertainty", self.max_orbit_uncertainty),
            ("stuck_time", self.stuck_time),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(format!("{name} = {v} must be finite and > 0"));
            }
        }
        if self.min_validation_windows == 0
            || self.max_validation_windows < self.min_validation_windows
        {
            return bad(format!(
                "validation windows {}..{} must satisfy 1 <= min <= max",
                self.min_validation_windows, self.max_validation_windows
            ));
        }
        for (name, v) in [
            ("excitation", self.excitation),
            ("excitation_time", self.excitation_time),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(format!("{name} = {v} must be finite and >= 0"));
            }
        }
        if self.excitation_hold == 0 {
            return bad("excitation_hold must be >= 1".into());
        }
        if self.judge_samples == 0 {
            return bad("judge_samples must be >= 1".into());
        }
        self.rls.validate()
    }
}

/// Why a candidate model was not taken (one count each).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Refusal {
    /// The estimate (shortened to the trust region) is not a physical chain.
    NotPhysical,
    /// It did not explain the held-out windows significantly better than
    /// the model in use.
    NotBetter,
    /// Its model or mode family could not be computed, or the controller
    /// refused it.
    ModelFailed,
}

impl Refusal {
    /// Every reason, in the order of [`Adaptation::refusals`].
    pub const ALL: [Refusal; 3] = [
        Refusal::NotPhysical,
        Refusal::NotBetter,
        Refusal::ModelFailed,
    ];

    /// What the reason means, for a log.
    pub fn describe(self) -> &'static str {
        match self {
            Refusal::NotPhysical => {
                "the estimate is not a physical chain (negative mass, inertia, friction)"
            }
            Refusal::NotBetter => {
                "it did not explain the windows measured after it significantly better than the \
                 model in use"
            }
            Refusal::ModelFailed => "its model or mode family could not be computed",
        }
    }
}

/// What the adaptation is doing (the FMU's `adaptation_status`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum AdaptationStatus {
    /// No window has informed the estimate yet.
    Idle,
    /// Gathering information the estimate lacks (its scale).
    Excitation,
    /// A candidate is being validated or a new model supervised.
    Learning,
    /// The estimate agrees with the model in use.
    Converged,
    /// The last model was taken back by the supervisor.
    Reverted,
    /// The controller's stall supervisor released the torque
    /// ([`Controller::supervisor_events`]): the last model was taken back,
    /// or the estimate is being tried.
    Supervisor,
}

/// Something a caller may want to log, with its figures.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum AdaptationEvent {
    /// A model was swapped in; `improvement` is its score on the held-out
    /// windows (sum of squared errors in units of their variance, the
    /// model in use minus the new one) over `windows` windows.
    Accepted {
        /// Score gained on the held-out windows.
        improvement: f64,
        /// Held-out windows scored.
        windows: usize,
    },
    /// A candidate was refused.
    Refused(Refusal),
    /// The supervisor took the last model back: over its window, the RMS
    /// torque (N m, all joints) and the RMS energy error (J) before the
    /// change and after.
    Reverted {
        /// RMS torque before the change.
        torque_before: f64,
        /// RMS torque at the end of the watch.
        torque_after: f64,
        /// RMS energy error before the change.
        energy_before: f64,
        /// RMS energy error at the end of the watch.
        energy_after: f64,
    },
}

/// A request to the worker: the model's parameters and, for a controller
/// on a mode family, the family's options and mode.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
struct Request<const N: usize> {
    params: PlanarChainParams<N>,
    /// The family's options, mode and the energy the controller runs at
    /// (the charts about it are refitted to a higher degree when they miss
    /// the new model's orbits: [`ChartFamily::compute_accurate`]).
    family: Option<(FamilyOptions, usize, f64)>,
    /// The controller's shooting interval (for the prediction substeps).
    dt: f64,
}

/// The worker's answer: the model, its family (None: the controller has
/// none) and the prediction substeps its friction needs.
type Computed<const N: usize> = (PlanarChain<N>, Option<ChartFamily<N>>, usize);

/// What the worker and the sample path share.
struct Slot<const N: usize> {
    /// A request and its generation.
    request: Option<(u64, Request<N>)>,
    /// The worker's answer to the request of a generation (Err: the model
    /// or its family failed).
    result: Option<(u64, Result<Computed<N>, ()>)>,
    /// A family the controller no longer uses, for the worker to free.
    garbage: Option<ChartFamily<N>>,
    quit: bool,
}

/// Mean squares of the closed loop over a block of samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
struct Block {
    torque: f64,
    energy: f64,
    samples: usize,
}

impl Block {
    fn add(&mut self, torque2: f64, energy2: f64) {
        self.torque += torque2;
        self.energy += energy2;
        self.samples += 1;
    }

    /// `(RMS torque, RMS energy error)`.
    fn rms(&self) -> (f64, f64) {
        let n = self.samples.max(1) as f64;
        ((self.torque / n).sqrt(), (self.energy / n).sqrt())
    }
}

/// The candidate being scored on held-out windows, and its model being
/// computed.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
struct Candidate<const N: usize, const NP: usize> {
    theta: SVector<f64, NP>,
    request: Request<N>,
    /// Sum over the windows of `(e_in_use^2 - e_candidate^2) / R`.
    score: f64,
    /// Sum of `(h' (theta_c - theta_u))^2 / R`: how far apart the two
    /// models' predictions are (the score's expectation if the candidate is
    /// right).
    distinct: f64,
    windows: usize,
    /// Proposed after a stall: taken as soon as its model is ready (the
    /// loop it replaces is known to be bad; the watch judges it).
    forced: bool,
}

/// A model swapped in and the one it replaced, under watch.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
struct Watch<const N: usize, const NP: usize> {
    previous_theta: SVector<f64, NP>,
    previous_model: PlanarChain<N>,
    previous_family: Option<ChartFamily<N>>,
    previous_substeps: usize,
    before: Block,
    /// The first block after the change (the energy error the new model
    /// starts from).
    early: Block,
    /// The last `judge_samples` of the watch.
    after: Block,
    /// The current `period` of the watch, and whether one showed the
    /// torque far above the one before while the energy error grew.
    current: Block,
    last_energy: f64,
    strikes: usize,
    alarm: bool,
    samples: usize,
}

/// What the adaptation is doing between two looks.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
enum Phase<const N: usize, const NP: usize> {
    Watching,
    Validating(Candidate<N, NP>),
    Supervising(Watch<N, NP>),
}

/// Identification plus model updates of one controller on an `N`-joint
/// chain (`NX = 2 N`, `NP` = [`crate::identify::base_parameter_count`]`(N)`).
pub struct Adaptation<const N: usize, const NX: usize, const NP: usize> {
    prior: PlanarChainParams<N>,
    options: AdaptOptions,
    rls: EnergyBalanceRls<N, NP>,
    /// Base parameters of the model the controller has.
    in_use: SVector<f64, NP>,
    phase: Phase<N, NP>,
    /// A candidate this close to the last reverted model is not tried again.
    reverted_theta: Option<SVector<f64, NP>>,
    /// The closed loop's last `judge_samples` (before a change).
    recent: Block,
    recent_done: Block,
    recent_prev: Block,
    /// Energy features of the measured states, averaged over about the
    /// last `ORBIT_MEMORY` samples: where the loop has been.
    orbit: SVector<f64, NP>,
    /// Answers to requests of another generation are dropped: a restored
    /// state ([`Adaptation::restore_state`]) starts a new one.
    generation: u64,
    samples: usize,
    /// No candidate before this sample (after a revert).
    hold_until: usize,
    /// The controller's stall events already answered.
    stalls_seen: usize,
    /// Samples in a row with the energy outside the 5 % band (its RMS
    /// over the last [`OFF_TARGET_SMOOTHING`] s).
    off_target: usize,
    /// Exponential mean of the squared energy error (J^2).
    energy_error_square: f64,
    updates: usize,
    reverts: usize,
    refusals: [usize; 3],
    last_event: Option<(usize, AdaptationEvent)>,
    events: usize,
    status: AdaptationStatus,
    shared: Arc<(Mutex<Slot<N>>, Condvar)>,
    worker: Option<JoinHandle<()>>,
    /// The state and parameters estimated together: when set, candidates
    /// come from its estimate instead of the energy balance's.
    filter: Option<Box<dyn crate::state_parameter_ekf::ParameterFilter<N, NX, NP>>>,
    /// The excitation's generator.
    excitation: crate::noise::GaussianNoise,
}

impl<const N: usize, const NX: usize, const NP: usize> Adaptation<N, NX, NP> {
    /// Starts from the controller's model `prior` (gear ratios, gravity and
    /// the Coulomb sharpness are taken as known) and its worker thread.
    pub fn new(prior: &PlanarChainParams<N>, options: AdaptOptions) -> Result<Self, IdentifyError> {
        options.validate()?;
        let rls = EnergyBalanceRls::new(prior, options.rls)?;
        let in_use = BaseParameters::<N, NP>::of(prior)?.theta;
        let shared = Arc::new((
            Mutex::new(Slot {
                request: None,
                result: None,
                garbage: None,
                quit: false,
            }),
            Condvar::new(),
        ));
        let for_worker = Arc::clone(&shared);
        let worker = std::thread::Builder::new()
            .name("eigenmpc-adapt".into())
            .spawn(move || work::<N, NX>(&for_worker))
            .map_err(|e| IdentifyError::NotPhysical(format!("no worker thread: {e}")))?;
        Ok(Self {
            prior: *prior,
            options: AdaptOptions {
                period: options.period.max(1),
                judge_samples: options.judge_samples.max(1),
                ..options
            },
            rls,
            in_use,
            phase: Phase::Watching,
            reverted_theta: None,
            recent: Block::default(),
            recent_done: Block::default(),
            recent_prev: Block::default(),
            orbit: SVector::zeros(),
            generation: 0,
            samples: 0,
            hold_until: 0,
            stalls_seen: 0,
            off_target: 0,
            energy_error_square: 0.0,
            updates: 0,
            reverts: 0,
            refusals: [0; 3],
            last_event: None,
            events: 0,
            status: AdaptationStatus::Idle,
            shared,
            worker: Some(worker),
            filter: None,
            excitation: crate::noise::GaussianNoise::new(0x0e1c_17a7_1000),
        })
    }

    /// Candidates from now on come from `filter`, the state and parameters
    /// estimated together (fed every sample with the measured state and the
    /// torque felt; library only, the FMU does not use it yet). Its
    /// estimate and covariance replace the energy balance's in the
    /// significance test; its energy scale is taken as known (the
    /// dynamics give it); and a candidate is taken once the held-out
    /// windows do not show it worse (the energy balance's windows under
    /// noise seldom tell a right candidate from the model in use: the
    /// paper's pendulum refused them all). The supervisor still watches
    /// each new model. Over its first `excitation_time` the commands carry
    /// an excitation torque ([`AdaptOptions::excitation`]).
    /// [`Adaptation::save_state`] covers the filter (restored into one set
    /// the same way).
    pub fn set_filter(
        &mut self,
        filter: Box<dyn crate::state_parameter_ekf::ParameterFilter<N, NX, NP>>,
    ) {
        self.filter = Some(filter);
    }

    /// The filter set by [`Adaptation::set_filter`], if any.
    pub fn filter(&self) -> Option<&dyn crate::state_parameter_ekf::ParameterFilter<N, NX, NP>> {
        self.filter.as_deref()
    }

    /// The identification.
    pub fn identification(&self) -> &EnergyBalanceRls<N, NP> {
        &self.rls
    }

    /// Base parameters of the model the controller uses now.
    pub fn in_use(&self) -> BaseParameters<N, NP> {
        BaseParameters { theta: self.in_use }
    }

    /// Drops the identification's open window (see
    /// [`EnergyBalanceRls::restart_window`]).
    pub fn restart_window(&mut self) {
        self.rls.restart_window();
    }

    /// Models swapped into the controller so far (reverts not subtracted).
    pub fn model_updates(&self) -> usize {
        self.updates
    }

    /// Models the supervisor took back.
    pub fn reverts(&self) -> usize {
        self.reverts
    }

    /// Candidates refused so far, per reason (in [`Refusal::ALL`]'s order).
    pub fn refusals(&self) -> [usize; 3] {
        self.refusals
    }

    /// Candidates refused so far, all reasons.
    pub fn refused(&self) -> usize {
        self.refusals.iter().sum()
    }

    /// Estimates whose model or mode family could not be computed (the
    /// controller kept its model).
    pub fn failed_models(&self) -> usize {
        self.refusals[2]
    }

    /// What the adaptation is doing.
    pub fn status(&self) -> AdaptationStatus {
        self.status
    }

    /// The latest event and its number (events are numbered from 1; a
    /// caller logs those it has not seen).
    pub fn last_event(&self) -> Option<(usize, AdaptationEvent)> {
        self.last_event
    }

    fn event(&mut self, event: AdaptationEvent) {
        self.events += 1;
        self.last_event = Some((self.events, event));
    }

    fn refuse(&mut self, reason: Refusal) {
        self.refusals[reason as usize] += 1;
        self.event(AdaptationEvent::Refused(reason));
    }

    /// One sample, after the controller's step (with the state the step
    /// used, see the `AdaptiveController` of the FMU): `(q, qd)` measured
    /// now, `felt` the torque that acted over the `dt` before the
    /// measurement ([`Controller::torque_before_measurement`]: the previous
    /// command, or the one the declared measurement delay and actuator lag
    /// say acted then).
    /// Feeds the identification; scores, takes or refuses a candidate;
    /// supervises a new model.
    pub fn sample(
        &mut self,
        controller: &mut Controller<PlanarChain<N>, N, NX>,
        q: &Vector<N>,
        qd: &Vector<N>,
        felt: &Vector<N>,
        dt: f64,
    ) {
        let window = self.rls.add_sample(q, qd, felt, dt);
        if let Some(filter) = self.filter.as_mut() {
            let z = SVector::<f64, NX>::from_fn(|i, _| if i < N { q[i] } else { qd[i - N] });
            filter.step(&z, felt);
        }
        self.samples += 1;
        self.excite(controller, dt);
        let stalls = controller.supervisor_events();
        if stalls > self.stalls_seen {
            self.stalls_seen = stalls;
            self.stall(controller);
        }
        self.observe(controller, q, qd, felt);
        if let Some(window) = window {
            self.score(&window);
        }
        if !self.samples.is_multiple_of(self.options.period) {
            return;
        }
        self.look(controller);
    }

    /// With a filter, over the first `excitation_time` seconds: a new
    /// excitation torque every `excitation_hold` samples (Gaussian,
    /// `excitation` times `tau_max` per joint), then none. Under feedback
    /// alone the torque is a function of the state (on the orbit it
    /// balances the friction the model knows), so the data cannot tell the
    /// model's scale from its friction: the filter's energy parameters
    /// drifted 3-10 % low with its friction high (the lab pendulums' rough
    /// models under noise ended up to 19 % high; see
    /// `cli/tests/adapt_rough_noise.rs`).
    fn excite(&mut self, controller: &mut Controller<PlanarChain<N>, N, NX>, dt: f64) {
        if self.filter.is_none() || self.options.excitation <= 0.0 {
            return;
        }
        let exciting = self.samples as f64 * dt < self.options.excitation_time;
        if !exciting {
            // Once, whatever the status went through meanwhile.
            if controller.excitation().iter().any(|v| *v != 0.0) {
                controller.set_excitation(&Vector::<N>::zeros());
            }
            if self.status == AdaptationStatus::Excitation {
                self.status = AdaptationStatus::Learning;
            }
            return;
        }
        if matches!(
            self.status,
            AdaptationStatus::Idle | AdaptationStatus::Learning | AdaptationStatus::Converged
        ) {
            self.status = AdaptationStatus::Excitation;
        }
        if (self.samples - 1).is_multiple_of(self.options.excitation_hold) {
            let amplitude = self.options.excitation * controller.config().tau_max;
            let torque = Vector::<N>::from_fn(|_, _| amplitude * self.excitation.sample());
            controller.set_excitation(&torque);
        }
    }

    /// While the scale of the energy parameters is uncertain, the factor
    /// on those of the model in use that gives them the estimate's energy
    /// along the recent orbit, when that energy is known within
    /// `max_orbit_uncertainty` or off the model in use's by more than
    /// [`ORBIT_SIGNIFICANCE`] standard deviations (1 otherwise), its change shortened by
    /// `step` and to the trust region. Under sensor noise the windows
    /// give the energy along the orbit the loop runs on (within 1-6 % on
    /// the lab pendulum A0 at 0.005 rad / 0.05 rad/s) far better than the
    /// scale of every parameter (6-7 %), and that energy is what the loop
    /// settles at: a rough model's scale stayed (10-30 % off) before.
    fn orbit_scale(&self, estimate: &SVector<f64, NP>, step: f64) -> f64 {
        // The energy parameters come first; sums by index (a product of
        // views sized at run time would allocate).
        let e = NP - 2 * N;
        let phi = &self.orbit;
        let covariance = self.rls.covariance();
        let (mut estimated, mut in_use, mut variance) = (0.0, 0.0, 0.0);
        for i in 0..e {
            estimated += phi[i] * estimate[i];
            in_use += phi[i] * self.in_use[i];
            for k in 0..e {
                variance += phi[i] * covariance[(i, k)] * phi[k];
            }
        }
        let sd = variance.max(0.0).sqrt();
        // Known within `max_orbit_uncertainty`, or off the model in use by
        // more than three of its standard deviations (a scale 16 % off
        // stayed: its orbit energy was known only within 4-5 %).
        let known = sd <= self.options.max_orbit_uncertainty * estimated
            || (estimated - in_use).abs() > ORBIT_SIGNIFICANCE * sd;
        if !(estimated > 0.0 && in_use > 0.0 && variance.is_finite() && known) {
            return 1.0;
        }
        let limit = self.options.trust_region;
        (1.0 + (estimated / in_use - 1.0) * step).clamp(1.0 - limit, 1.0 + limit)
    }

    /// The closed loop's torque and energy error (under the model in use)
    /// into the supervisor's blocks.
    fn observe(
        &mut self,
        controller: &Controller<PlanarChain<N>, N, NX>,
        q: &Vector<N>,
        qd: &Vector<N>,
        command: &Vector<N>,
    ) {
        if !(q.iter().chain(qd).chain(command).all(|v| v.is_finite())) {
            return;
        }
        let features = energy_features::<N, NP>(&self.prior, q, qd);
        let memory = ORBIT_MEMORY.min(self.samples.max(1)) as f64;
        self.orbit += (features - self.orbit) / memory;
        let energy = self.in_use.dot(&features);
        let e_ref = controller.config().cost.e_ref;
        let e2 = (energy - e_ref).powi(2);
        let share = (controller.config().dt / OFF_TARGET_SMOOTHING).min(1.0);
        self.energy_error_square += (e2 - self.energy_error_square) * share;
        if self.energy_error_square > (0.05 * e_ref).powi(2) {
            self.off_target += 1;
        } else {
            self.off_target = 0;
        }
        let t2 = command.norm_squared();
        let judge = self.options.judge_samples;
        self.recent.add(t2, e2);
        if self.recent.samples >= judge {
            self.recent_prev = std::mem::replace(&mut self.recent_done, self.recent);
            self.recent = Block::default();
        }
        if let Phase::Supervising(watch) = &mut self.phase {
            watch.samples += 1;
            if watch.samples <= self.options.period {
                watch.early.add(t2, e2);
            }
            let end = self.options.settle_samples + judge;
            if watch.samples > end.saturating_sub(judge) {
                watch.after.add(t2, e2);
            }
            watch.current.add(t2, e2);
            if watch.current.samples >= self.options.period {
                let (torque_before, _) = watch.before.rms();
                let (torque, energy) = std::mem::take(&mut watch.current).rms();
                let config = controller.config();
                // A catastrophe is not waited out: a torque far above the
                // steady loop's before the change while the energy error
                // does not come down (a right model that finds the
                // energy low brings it down by climbing), two periods in a
                // row, is judged at the next look.
                let bad = torque > 2.0 * torque_before + 0.1 * config.tau_max
                    && energy >= 0.95 * watch.last_energy;
                watch.strikes = if bad { watch.strikes + 1 } else { 0 };
                watch.alarm |= watch.strikes >= 2;
                watch.last_energy = energy;
            }
        }
    }

    /// A held-out window: the candidate formed before it is scored against
    /// the model in use.
    fn score(&mut self, window: &WindowEquation<NP>) {
        if let Phase::Validating(candidate) = &mut self.phase {
            if !(window.variance > 0.0 && window.y.is_finite()) {
                return;
            }
            let delta = window.h.dot(&(candidate.theta - self.in_use));
            candidate.score +=
                window.normalised_error(&self.in_use) - window.normalised_error(&candidate.theta);
            candidate.distinct += delta * delta / window.variance;
            candidate.windows += 1;
        }
        if self.status == AdaptationStatus::Idle && window.used {
            self.status = AdaptationStatus::Learning;
        }
    }

    /// The controller called a stall: a model just taken goes back (the
    /// loop was better before it); otherwise the estimate is tried at once,
    /// without waiting for a steady loop (a stalled loop never is one).
    fn stall(&mut self, controller: &mut Controller<PlanarChain<N>, N, NX>) {
        // Its own events (Reverted, Accepted) say what it did.
        match std::mem::replace(&mut self.phase, Phase::Watching) {
            Phase::Supervising(mut watch) => {
                watch.alarm = true;
                self.judge(controller, watch);
            }
            Phase::Validating(mut candidate) => {
                candidate.forced = true;
                self.decide(controller, candidate);
            }
            Phase::Watching => {
                self.propose(controller, true);
                if let Phase::Validating(candidate) =
                    std::mem::replace(&mut self.phase, Phase::Watching)
                {
                    self.decide(controller, candidate);
                }
            }
        }
        self.status = AdaptationStatus::Supervisor;
    }

    /// A loop that has stayed off its target for `stuck_time` (a wrong
    /// model's limit cycle, say another mode's or a joint held bent) is
    /// never steady: it is known bad, and the estimate is tried as after a
    /// stall.
    fn stuck(&self, dt: f64) -> bool {
        self.off_target as f64 * dt >= self.options.stuck_time && self.samples >= self.hold_until
    }

    fn look(&mut self, controller: &mut Controller<PlanarChain<N>, N, NX>) {
        let stuck = self.stuck(controller.config().dt);
        match std::mem::replace(&mut self.phase, Phase::Watching) {
            Phase::Watching => self.propose(controller, false),
            Phase::Validating(mut candidate) => {
                candidate.forced |= stuck;
                self.decide(controller, candidate)
            }
            Phase::Supervising(watch) => self.judge(controller, watch),
        }
    }

    /// Makes a candidate of the estimate when it has moved: shortened to
    /// the trust region, physical, not the model just reverted; posts its
    /// model to the worker. `forced` (after a stall): whatever the loop.
    fn propose(&mut self, controller: &Controller<PlanarChain<N>, N, NX>, forced: bool) {
        // The change is measured on the estimate as a model would take it
        // (rotor inertias and friction not negative): a frictionless joint's
        // estimate scattering below zero is no change.
        let estimate = match &self.filter {
            Some(filter) => filter.parameters().projected(&self.prior).theta,
            None => self.rls.estimate().projected(&self.prior).theta,
        };
        let floor = self.options.rls.prior_floor;
        let relative = |a: &SVector<f64, NP>, b: &SVector<f64, NP>| {
            (0..NP)
                .map(|i| (a[i] - b[i]).abs() / (b[i].abs() + floor))
                .fold(0.0, f64::max)
        };
        let change = relative(&estimate, &self.in_use);
        if change < self.options.min_change {
            if self.rls.updates() > 0 && self.status != AdaptationStatus::Reverted {
                self.status = AdaptationStatus::Converged;
            }
            return;
        }
        // Only a steady loop proposes: its energy error (under the model in
        // use) in the 5 % band, or no longer falling. The supervisor then
        // has a loop to compare with, and the climb's information is kept
        // by the identification (a climb's windows cannot show a biased
        // estimate, say by an undeclared delay, to be wrong).
        let (torque, energy_error) = self.recent_done.rms();
        let (_, energy_before) = self.recent_prev.rms();
        let config = controller.config();
        // The torque is the RMS of its norm over the joints: a loop that
        // sits on the bound has about sqrt(N) tau_max.
        let saturating = 0.7 * (N as f64).sqrt() * config.tau_max;
        let steady = energy_error < 0.05 * config.cost.e_ref
            || (energy_error > 0.9 * energy_before && torque < saturating);
        let forced = forced || self.stuck(config.dt);
        if !forced && (self.recent_prev.samples == 0 || !steady || self.samples < self.hold_until) {
            return;
        }
        // The estimate must have moved significantly from the model in use
        // (its Mahalanobis distance under the estimate's covariance beyond
        // the 99 % quantile of chi^2 with NP degrees of freedom), not only
        // by the noise of its windows.
        let moved = estimate - self.in_use;
        let covariance = match &self.filter {
            Some(filter) => filter.parameter_covariance(),
            None => *self.rls.covariance(),
        };
        let significant = covariance
            .cholesky()
            .map(|c| moved.dot(&c.solve(&moved)))
            .is_some_and(|d2| d2 > chi2_99(NP));
        if !significant {
            return;
        }
        // After a stall the loop is known to be bad: the estimate is taken
        // whole (the watch judges it; the model before comes back if the
        // loop does worse).
        let step = if forced {
            1.0
        } else {
            (self.options.trust_region / change).min(1.0)
        };
        let mut theta = BaseParameters::<N, NP> {
            theta: self.in_use + (estimate - self.in_use) * step,
        }
        .projected(&self.prior)
        .theta;
        // Free motion and friction give the ratios of the energy parameters;
        // only work that changes the energy gives their scale. While the
        // estimate's scale is uncertain, the candidate keeps the ratios of
        // the model in use, scaled to the estimate's energy along the
        // recent orbit when that is certain ([`Self::orbit_scale`]), and
        // corrects the friction (which the work along the orbit gives on
        // its own): a wrong scale, or ratios fitted with it, moves the
        // energy the loop settles at, which no measurement shows (measured:
        // a rough model of the lab pendulum A0 ended 7 % high with them,
        // 4 % low without).
        if self.filter.is_none()
            && self.rls.scale_uncertainty() > self.options.max_scale_uncertainty
        {
            let scale = self.orbit_scale(&estimate, step);
            for i in 0..NP - 2 * N {
                theta[i] = self.in_use[i] * scale;
            }
        }
        if let Some(reverted) = &self.reverted_theta
            && relative(&theta, reverted) < 3.0 * self.options.min_change
        {
            return;
        }
        let Ok(params) = (BaseParameters::<N, NP> { theta }).physical(&self.prior) else {
            self.refuse(Refusal::NotPhysical);
            return;
        };
        let family = match controller.family() {
            Some(family) => {
                let Ok(chain) = PlanarChain::new(params) else {
                    self.refuse(Refusal::NotPhysical);
                    return;
                };
                let mut options = if self.options.family_energy_max > 0.0 {
                    FamilyOptions::up_to(self.options.family_energy_max)
                } else {
                    FamilyOptions::for_system(&chain, &[controller.config().cost.e_ref])
                };
                options.degree = family.degree();
                Some((options, family.mode_index(), controller.config().cost.e_ref))
            }
            None => None,
        };
        let request = Request {
            params,
            family,
            dt: controller.config().dt,
        };
        let (lock, wake) = &*self.shared;
        let Ok(mut slot) = lock.lock() else { return };
        // Copies of plain data: no allocation.
        slot.request = Some((self.generation, request.clone()));
        wake.notify_one();
        drop(slot);
        if self.status != AdaptationStatus::Reverted {
            self.status = AdaptationStatus::Learning;
        }
        self.phase = Phase::Validating(Candidate {
            theta,
            request,
            score: 0.0,
            distinct: 0.0,
            windows: 0,
            forced,
        });
    }

    /// Takes the candidate once the held-out windows show it better and its
    /// model is ready; refuses it when they do not.
    fn decide(
        &mut self,
        controller: &mut Controller<PlanarChain<N>, N, NX>,
        candidate: Candidate<N, NP>,
    ) {
        let o = &self.options;
        // Better: the gain is at least a quarter of what a right candidate
        // gains and three of its standard deviations (2 sqrt(distinct)).
        let margin = (6.0 * candidate.distinct.sqrt()).max(0.25 * candidate.distinct);
        // The two must also differ by three standard deviations on those
        // windows: a candidate the windows cannot tell apart is not taken.
        let worse = candidate.windows >= o.min_validation_windows && candidate.score < -margin;
        let better = candidate.forced
            || (candidate.windows >= o.min_validation_windows
                && candidate.distinct >= 9.0
                && candidate.score > margin)
            || (self.filter.is_some() && candidate.windows >= o.min_validation_windows && !worse);
        if !better && !worse && candidate.windows < o.max_validation_windows {
            self.phase = Phase::Validating(candidate);
            return;
        }
        if !better {
            self.cancel();
            self.refuse(Refusal::NotBetter);
            return;
        }
        let Some(computed) = self.take_result() else {
            // Still being computed: look again next period.
            self.phase = Phase::Validating(candidate);
            return;
        };
        let Ok((model, family, substeps)) = computed else {
            self.refuse(Refusal::ModelFailed);
            return;
        };
        let previous_model = *controller.system();
        let previous_substeps = controller.config().substeps;
        let previous_family = match controller.replace_model(model, family) {
            Ok(old) => old,
            Err(_) => {
                self.refuse(Refusal::ModelFailed);
                return;
            }
        };
        if controller.set_substeps(substeps).is_err() {
            // Put the model back (same family degree: cannot fail).
            let _ = controller.replace_model(previous_model, previous_family);
            self.refuse(Refusal::ModelFailed);
            return;
        }
        self.updates += 1;
        self.event(AdaptationEvent::Accepted {
            improvement: candidate.score,
            windows: candidate.windows,
        });
        self.reverted_theta = None;
        self.phase = Phase::Supervising(Watch {
            previous_theta: self.in_use,
            previous_model,
            previous_family,
            previous_substeps,
            before: self.recent_done,
            early: Block::default(),
            after: Block::default(),
            current: Block::default(),
            last_energy: 0.0,
            strikes: 0,
            alarm: false,
            samples: 0,
        });
        self.in_use = candidate.theta;
        self.status = AdaptationStatus::Learning;
    }

    /// At the end of a watch: keeps the new model, or brings the previous
    /// one back when the closed loop does worse. Worse: once the energy is
    /// in the 5 % band, a torque that rose; before, an energy error that
    /// rose above both the one before the change and the one the new model
    /// started from.
    fn judge(&mut self, controller: &mut Controller<PlanarChain<N>, N, NX>, watch: Watch<N, NP>) {
        if !watch.alarm && watch.samples < self.options.settle_samples + self.options.judge_samples
        {
            self.phase = Phase::Supervising(watch);
            return;
        }
        let e_ref = controller.config().cost.e_ref;
        let tau_max = controller.config().tau_max;
        let (torque_before, energy_before) = watch.before.rms();
        let (_, energy_early) = watch.early.rms();
        let (torque_after, energy_after) = watch.after.rms();
        let settled = |e: f64| e < 0.05 * e_ref;
        let worse = watch.alarm
            || if settled(energy_after) {
                settled(energy_before) && torque_after > 1.2 * torque_before + 0.02 * tau_max
            } else {
                energy_after > 1.2 * energy_before.max(energy_early) + 0.01 * e_ref
            };
        let Watch {
            previous_theta,
            previous_model,
            previous_family,
            previous_substeps,
            ..
        } = watch;
        if !worse {
            self.discard_family(previous_family);
            return;
        }
        match controller.replace_model(previous_model, previous_family) {
            Ok(dropped) => {
                let _ = controller.set_substeps(previous_substeps);
                self.discard_family(dropped);
                self.reverted_theta = Some(self.in_use);
                self.in_use = previous_theta;
                self.reverts += 1;
                // Each revert doubles the wait before the next candidate.
                let wait = (self.options.settle_samples + self.options.judge_samples)
                    .saturating_mul(1 << self.reverts.min(16));
                self.hold_until = self.samples.saturating_add(wait);
                self.status = AdaptationStatus::Reverted;
                self.event(AdaptationEvent::Reverted {
                    torque_before,
                    torque_after,
                    energy_before,
                    energy_after,
                });
            }
            Err(_) => self.refuse(Refusal::ModelFailed),
        }
    }

    /// The worker's answer for the current generation: waits for it when
    /// `synchronous`, else takes it only if it is there.
    fn take_result(&mut self) -> Option<Result<Computed<N>, ()>> {
        let (lock, wake) = &*self.shared;
        let mut slot = if self.options.synchronous {
            // A candidate's request is always in flight (a restored state
            // posts it again): its answer comes.
            let Ok(mut slot) = lock.lock() else {
                return None;
            };
            while !matches!(&slot.result, Some((g, _)) if *g == self.generation) {
                if slot.result.is_some() {
                    self.drop_stale(&mut slot);
                }
                slot = match wake.wait(slot) {
                    Ok(s) => s,
                    Err(_) => return None,
                };
            }
            slot
        } else {
            // Never wait in a real-time sample: a busy worker is looked at
            // next period.
            let Ok(slot) = lock.try_lock() else {
                return None;
            };
            slot
        };
        if matches!(&slot.result, Some((g, _)) if *g != self.generation) {
            self.drop_stale(&mut slot);
        }
        slot.result.take().map(|(_, result)| result)
    }

    /// Forgets the candidate's request: its answer, when it comes, is of an
    /// old generation and freed as stale.
    fn cancel(&mut self) {
        self.generation += 1;
        let (lock, _) = &*self.shared;
        if let Ok(mut slot) = lock.try_lock() {
            slot.request = None;
            if slot.result.is_some() {
                self.drop_stale(&mut slot);
            }
        }
    }

    /// Hands a family to the worker to free (dropped here only when the
    /// worker still has one to free: rare, and never in a real-time loop's
    /// steady state).
    fn discard_family(&self, family: Option<ChartFamily<N>>) {
        if family.is_none() {
            return;
        }
        let (lock, wake) = &*self.shared;
        let slot = if self.options.synchronous {
            lock.lock().ok()
        } else {
            lock.try_lock().ok()
        };
        if let Some(mut slot) = slot
            && slot.garbage.is_none()
        {
            slot.garbage = family;
            wake.notify_one();
        }
    }
}

/// The state of an [`Adaptation`] between two samples
/// ([`Adaptation::save_state`]).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct AdaptationState<const N: usize, const NP: usize> {
    rls: EnergyBalanceRls<N, NP>,
    in_use: SVector<f64, NP>,
    phase: Phase<N, NP>,
    reverted_theta: Option<SVector<f64, NP>>,
    recent: Block,
    recent_done: Block,
    recent_prev: Block,
    orbit: SVector<f64, NP>,
    samples: usize,
    hold_until: usize,
    stalls_seen: usize,
    off_target: usize,
    energy_error_square: f64,
    updates: usize,
    reverts: usize,
    refusals: [usize; 3],
    last_event: Option<(usize, AdaptationEvent)>,
    events: usize,
    status: AdaptationStatus,
    /// The filter's, when one is set.
    filter: Option<crate::state_parameter_ekf::FilterState>,
    /// The excitation generator's state.
    excitation: u64,
}

impl<const N: usize, const NX: usize, const NP: usize> Adaptation<N, NX, NP> {
    /// A stale answer (of a generation before a restore or a refusal) goes
    /// to the worker's garbage, or is dropped when that is taken.
    fn drop_stale(&self, slot: &mut Slot<N>) {
        if let Some((_, Ok((_, family @ Some(_), _)))) = slot.result.take()
            && slot.garbage.is_none()
        {
            slot.garbage = family;
        }
    }

    /// Everything the next samples depend on: the identification, the
    /// model in use, a candidate (its request is posted again on restore)
    /// and a model under watch. With `synchronous` (offline simulation), a
    /// restored adaptation continues bit for bit.
    pub fn save_state(&self) -> AdaptationState<N, NP> {
        AdaptationState {
            rls: self.rls.clone(),
            in_use: self.in_use,
            phase: self.phase.clone(),
            reverted_theta: self.reverted_theta,
            recent: self.recent,
            recent_done: self.recent_done,
            recent_prev: self.recent_prev,
            orbit: self.orbit,
            samples: self.samples,
            hold_until: self.hold_until,
            stalls_seen: self.stalls_seen,
            off_target: self.off_target,
            energy_error_square: self.energy_error_square,
            updates: self.updates,
            reverts: self.reverts,
            refusals: self.refusals,
            last_event: self.last_event,
            events: self.events,
            status: self.status,
            filter: self.filter.as_ref().map(|f| f.save_state()),
            excitation: self.excitation.state(),
        }
    }

    /// Continues from `state` (saved by an adaptation with the same
    /// prior and options): a candidate's request is posted again, answers
    /// the worker is still computing for the state before are dropped.
    pub fn restore_state(&mut self, state: AdaptationState<N, NP>) -> Result<(), IdentifyError> {
        self.rls.check_compatible(&state.rls)?;
        match (&mut self.filter, &state.filter) {
            (Some(filter), Some(saved)) => {
                // Checked before anything changes; nothing after it fails.
                filter
                    .restore_state(saved)
                    .map_err(IdentifyError::NotPhysical)?;
            }
            (None, None) => {}
            _ => {
                return Err(IdentifyError::NotPhysical(
                    "the saved adaptation has another filter set-up".into(),
                ));
            }
        }
        let (lock, wake) = &*self.shared;
        let mut slot = lock.lock().unwrap_or_else(|e| e.into_inner());
        self.generation += 1;
        slot.request = match &state.phase {
            Phase::Validating(candidate) => Some((self.generation, candidate.request.clone())),
            _ => None,
        };
        slot.result = None;
        self.rls = state.rls;
        self.in_use = state.in_use;
        self.phase = state.phase;
        self.reverted_theta = state.reverted_theta;
        self.recent = state.recent;
        self.recent_done = state.recent_done;
        self.recent_prev = state.recent_prev;
        self.orbit = state.orbit;
        self.samples = state.samples;
        self.hold_until = state.hold_until;
        self.stalls_seen = state.stalls_seen;
        self.off_target = state.off_target;
        self.energy_error_square = state.energy_error_square;
        self.updates = state.updates;
        self.reverts = state.reverts;
        self.refusals = state.refusals;
        self.last_event = state.last_event;
        self.events = state.events;
        self.status = state.status;
        self.excitation = crate::noise::GaussianNoise::new(state.excitation);
        wake.notify_all();
        Ok(())
    }
}

impl<const N: usize, const NX: usize, const NP: usize> Drop for Adaptation<N, NX, NP> {
    fn drop(&mut self) {
        let (lock, wake) = &*self.shared;
        if let Ok(mut slot) = lock.lock() {
            slot.quit = true;
        }
        wake.notify_one();
        if let Some(worker) = self.worker.take() {
            let _ = worker.join();
        }
    }
}

/// The 99 % quantile of chi^2 with `k` degrees of freedom
/// (Wilson-Hilferty, within 1 % for `k >= 3`).
fn chi2_99(k: usize) -> f64 {
    let k = k as f64;
    let a = 2.0 / (9.0 * k);
    k * (1.0 - a + 2.326_347_874 * a.sqrt()).powi(3)
}

/// The worker: computes requested models and families, frees garbage.
fn work<const N: usize, const NX: usize>(shared: &(Mutex<Slot<N>>, Condvar)) {
    let (lock, wake) = shared;
    let Ok(mut slot) = lock.lock() else { return };
    loop {
        drop(slot.garbage.take());
        if slot.quit {
            return;
        }
        if let Some((generation, request)) = slot.request.take() {
            drop(slot);
            let computed = PlanarChain::new(request.params)
                .ok()
                .and_then(|model| {
                    // Other friction may need another prediction model
                    // (an eigenvalue problem: here, not in the sample).
                    let (model, substeps, _) =
                        prediction_model(&model, request.dt, PREDICTION_SUBSTEPS);
                    match &request.family {
                        None => Some((model, None, substeps)),
                        Some((options, mode, energy)) => {
                            ChartFamily::compute_accurate::<_, NX>(&model, *mode, options, *energy)
                                .ok()
                                .map(|family| (model, Some(family), substeps))
                        }
                    }
                })
                .ok_or(());
            slot = match lock.lock() {
                Ok(s) => s,
                Err(_) => return,
            };
            slot.result = Some((generation, computed));
            wake.notify_all();
            continue;
        }
        slot = match wake.wait(slot) {
            Ok(s) => s,
            Err(_) => return,
        };
    }
}
