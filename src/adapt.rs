//! Online adaptation of a controller's model: the energy-balance
//! identification ([`crate::identify`]) is fed every sample; when its
//! estimate has moved, the new model and its eigenmode family are computed
//! on a worker thread (tens of milliseconds: never inside a sample) and
//! swapped into the controller at the first sample after they are ready.
//!
//! The per-sample path ([`Adaptation::sample`]) does not allocate and never
//! waits: it feeds the identification, and at most once per `period`
//! samples posts a request or takes a finished result through a mutex it
//! only `try_lock`s. The family the controller drops is handed back to the
//! worker, which frees it.

use crate::identify::{BaseParameters, EnergyBalanceRls, IdentifyError, RlsOptions};
use crate::mechanics::{PlanarChain, PlanarChainParams, Vector};
use crate::modes::{ChartFamily, FamilyOptions};
use crate::mpc::{Controller, prediction_substeps};
use nalgebra::SVector;
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;

/// When the model follows the estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptOptions {
    /// Samples between two looks at the estimate (>= 1).
    pub period: usize,
    /// Relative change of a base parameter (against its value in use plus
    /// the identification's `prior_floor`) that triggers a new model.
    pub min_change: f64,
    /// Top of a new model's mode family (J); `<= 0`: the default of
    /// [`FamilyOptions::for_system`] for the new model.
    pub family_energy_max: f64,
    /// Identification settings.
    pub rls: RlsOptions,
    /// Offline simulation: wait for the worker's model at the next look
    /// (deterministic closed loops whatever the machine's speed). Never for
    /// a real-time loop.
    pub synchronous: bool,
}

impl Default for AdaptOptions {
    fn default() -> Self {
        Self {
            period: 40,
            min_change: 1e-2,
            family_energy_max: -1.0,
            rls: RlsOptions::default(),
            synchronous: false,
        }
    }
}

/// A request to the worker: the model's parameters and, for a controller
/// on a mode family, the family's options and mode.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
struct Request<const N: usize> {
    params: PlanarChainParams<N>,
    family: Option<(FamilyOptions, usize)>,
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

/// Identification plus model updates of one controller on an `N`-joint
/// chain (`NX = 2 N`, `NP` = [`crate::identify::base_parameter_count`]`(N)`).
pub struct Adaptation<const N: usize, const NX: usize, const NP: usize> {
    prior: PlanarChainParams<N>,
    options: AdaptOptions,
    rls: EnergyBalanceRls<N, NP>,
    /// Base parameters of the model the controller has.
    in_use: SVector<f64, NP>,
    /// Base parameters of the model the worker is computing.
    posted: SVector<f64, NP>,
    pending: bool,
    /// The request the worker is computing (kept for a saved state).
    request: Option<Request<N>>,
    /// Answers to requests of another generation are dropped: a restored
    /// state ([`Adaptation::restore_state`]) starts a new one.
    generation: u64,
    /// Requests whose model or family could not be computed.
    failures: usize,
    samples: usize,
    updates: usize,
    shared: Arc<(Mutex<Slot<N>>, Condvar)>,
    worker: Option<JoinHandle<()>>,
}

impl<const N: usize, const NX: usize, const NP: usize> Adaptation<N, NX, NP> {
    /// Starts from the controller's model `prior` (gear ratios, gravity and
    /// the Coulomb sharpness are taken as known) and its worker thread.
    pub fn new(prior: &PlanarChainParams<N>, options: AdaptOptions) -> Result<Self, IdentifyError> {
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
                ..options
            },
            rls,
            in_use,
            posted: in_use,
            pending: false,
            request: None,
            generation: 0,
            failures: 0,
            samples: 0,
            updates: 0,
            shared,
            worker: Some(worker),
        })
    }

    /// The identification.
    pub fn identification(&self) -> &EnergyBalanceRls<N, NP> {
        &self.rls
    }

    /// Drops the identification's open window (see
    /// [`EnergyBalanceRls::restart_window`]).
    pub fn restart_window(&mut self) {
        self.rls.restart_window();
    }

    /// Models swapped into the controller so far.
    pub fn model_updates(&self) -> usize {
        self.updates
    }

    /// Estimates whose model or mode family could not be computed (the
    /// controller kept its model).
    pub fn failed_models(&self) -> usize {
        self.failures
    }

    /// One sample, before or after the controller's step (the
    /// `AdaptiveController` of the FMU calls it after, with the state the
    /// step used): `(q, qd)` measured now, `tau` the torque applied since
    /// the previous sample, `dt` ago. Feeds the identification; swaps a
    /// ready model and family into `controller`; posts a new one when the
    /// estimate has moved.
    pub fn sample(
        &mut self,
        controller: &mut Controller<PlanarChain<N>, N, NX>,
        q: &Vector<N>,
        qd: &Vector<N>,
        tau: &Vector<N>,
        dt: f64,
    ) {
        self.rls.add_sample(q, qd, tau, dt);
        self.samples += 1;
        if !self.samples.is_multiple_of(self.options.period) {
            return;
        }
        let (lock, wake) = &*self.shared;
        let mut slot = if self.options.synchronous {
            let Ok(mut slot) = lock.lock() else { return };
            while self.pending && !matches!(&slot.result, Some((g, _)) if *g == self.generation) {
                if slot.result.is_some() {
                    self.drop_stale(&mut slot);
                }
                slot = match wake.wait(slot) {
                    Ok(s) => s,
                    Err(_) => return,
                };
            }
            slot
        } else {
            // Never wait in a real-time sample: a busy worker is looked at
            // next period.
            let Ok(slot) = lock.try_lock() else { return };
            slot
        };
        if matches!(&slot.result, Some((g, _)) if *g != self.generation) {
            self.drop_stale(&mut slot);
        }
        if let Some((_, result)) = slot.result.take() {
            self.pending = false;
            self.request = None;
            // A failed model or family (or one this controller cannot
            // take) leaves the model in use; a later estimate may succeed.
            let replaced = result.map(|(model, family, substeps)| {
                let old = controller.replace_model(model, family)?;
                controller.set_substeps(substeps).map(|()| old)
            });
            match replaced {
                Ok(Ok(old)) => {
                    // Empty here: the worker frees the garbage before it
                    // computes the next result, so this never drops a family.
                    slot.garbage = old;
                    self.in_use = self.posted;
                    self.updates += 1;
                    wake.notify_one();
                }
                _ => self.failures += 1,
            }
        }
        if self.pending {
            return;
        }
        let estimate = self.rls.estimate();
        // Relative change per parameter (a friction coefficient near zero
        // against the prior's floor).
        let floor = self.options.rls.prior_floor;
        let change = (0..NP)
            .map(|i| (estimate.theta[i] - self.in_use[i]).abs() / (self.in_use[i].abs() + floor))
            .fold(0.0, f64::max);
        if change < self.options.min_change {
            return;
        }
        let Ok(params) = estimate.physical(&self.prior) else {
            return;
        };
        let family = match controller.family() {
            Some(family) => {
                let Ok(chain) = PlanarChain::new(params) else {
                    return;
                };
                let mut options = if self.options.family_energy_max > 0.0 {
                    FamilyOptions::up_to(self.options.family_energy_max)
                } else {
                    FamilyOptions::for_system(&chain, &[controller.config().cost.e_ref])
                };
                options.degree = family.degree();
                Some((options, family.mode_index()))
            }
            None => None,
        };
        let request = Request {
            params,
            family,
            dt: controller.config().dt,
        };
        // Copies of plain data: no allocation.
        slot.request = Some((self.generation, request.clone()));
        self.request = Some(request);
        self.posted = estimate.theta;
        self.pending = true;
        wake.notify_one();
    }
}

/// The state of an [`Adaptation`] between two samples
/// ([`Adaptation::save_state`]).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct AdaptationState<const N: usize, const NP: usize> {
    rls: EnergyBalanceRls<N, NP>,
    in_use: SVector<f64, NP>,
    posted: SVector<f64, NP>,
    /// The request the worker was computing (posted again on restore).
    request: Option<Request<N>>,
    failures: usize,
    samples: usize,
    updates: usize,
}

impl<const N: usize, const NX: usize, const NP: usize> Adaptation<N, NX, NP> {
    /// A stale answer (of a generation before a restore) goes to the
    /// worker's garbage, or is dropped when that is taken.
    fn drop_stale(&self, slot: &mut Slot<N>) {
        if let Some((_, Ok((_, family @ Some(_), _)))) = slot.result.take()
            && slot.garbage.is_none()
        {
            slot.garbage = family;
        }
    }

    /// Everything the next samples depend on: the identification, the
    /// model in use and a request in flight. With `synchronous` (offline
    /// simulation), a restored adaptation continues bit for bit.
    pub fn save_state(&self) -> AdaptationState<N, NP> {
        AdaptationState {
            rls: self.rls.clone(),
            in_use: self.in_use,
            posted: self.posted,
            request: if self.pending {
                self.request.clone()
            } else {
                None
            },
            failures: self.failures,
            samples: self.samples,
            updates: self.updates,
        }
    }

    /// Continues from `state` (saved by an adaptation with the same
    /// prior and options): a request in flight is posted again, answers
    /// the worker is still computing for the state before are dropped.
    pub fn restore_state(&mut self, state: AdaptationState<N, NP>) -> Result<(), IdentifyError> {
        self.rls.check_compatible(&state.rls)?;
        let (lock, wake) = &*self.shared;
        let mut slot = lock.lock().unwrap_or_else(|e| e.into_inner());
        self.generation += 1;
        slot.request = state
            .request
            .clone()
            .map(|request| (self.generation, request));
        slot.result = None;
        self.pending = state.request.is_some();
        self.request = state.request;
        self.rls = state.rls;
        self.in_use = state.in_use;
        self.posted = state.posted;
        self.failures = state.failures;
        self.samples = state.samples;
        self.updates = state.updates;
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
                    // Other friction may need other prediction substeps
                    // (an eigenvalue problem: here, not in the sample).
                    let substeps = prediction_substeps(&model, request.dt);
                    match &request.family {
                        None => Some((model, None, substeps)),
                        Some((options, mode)) => {
                            ChartFamily::compute::<_, NX>(&model, *mode, options)
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
