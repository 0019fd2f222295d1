//! One FMU instance: the FMI 3.0 Co-Simulation state machine, argument
//! checks and value-reference dispatch (over the array [`Layout`]) around a
//! [`Model`]. This is the safe Rust API; [`crate::abi`] wraps it for C.
//!
//! The states are fmu-core's [`State`] (so that a saved FMU state is the same
//! byte form under FMI 2.0 and 3.0), named as FMI 3.0 names them:
//! `StepComplete` is Step Mode, `StepFailed` is Step Mode after a discarded
//! step (only `fmi3Terminate`, the FMU-state functions, getters and
//! `fmi3Reset` are accepted, as in fmi2-slave). There is no Event Mode
//! (`hasEventMode = false`) and no Configuration Mode (no structural
//! parameters): those calls are errors.

use crate::layout::{self, Fmi3Type, Layout};
pub use fmu_core::instance::MAX_START_TIME;
use fmu_core::instance::{Core, Dialect};
use fmu_core::logger::{Logger, Status};
pub use fmu_core::model::{Context, Experiment, Model, ModelError, State};
use fmu_core::variables::{Causality, Initial, ModelDescription, Value, Variability};
use std::ops::{Deref, DerefMut};
use std::path::PathBuf;

/// The FMI 3.0 name of a state, for messages.
pub fn state_name(s: State) -> &'static str {
    match s {
        State::Instantiated => "Instantiated",
        State::InitializationMode => "Initialization Mode",
        State::StepComplete => "Step Mode",
        State::StepFailed => "Step Mode after a discarded step",
        State::Terminated => "Terminated",
        State::Error => "error",
    }
}

/// The outputs of `fmi3DoStep` besides its status.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepOutcome {
    /// `terminateSimulation`: the FMU cannot continue (after a discarded step).
    pub terminate_simulation: bool,
    /// `lastSuccessfulTime`.
    pub last_successful_time: f64,
}

/// FMI 3.0's words in the instance's messages.
static FMI3: Dialect = Dialect {
    state_name,
    state_word: "",
    can_save_state: "canGetAndSetFMUState",
    token_name: "instantiationToken",
    initialized: "initialization done, entered Step Mode",
};

/// One instance of model `M` with its state machine: the version-neutral
/// [`Core`] (values, state, model, clock, FMU state save and restore, which
/// it derefs to), the array layout of its variables and the FMI 3.0 calls
/// around them.
pub struct Instance<M: Model> {
    core: Core<M>,
    layout: Layout,
}

impl<M: Model> Deref for Instance<M> {
    type Target = Core<M>;
    fn deref(&self) -> &Core<M> {
        &self.core
    }
}

impl<M: Model> DerefMut for Instance<M> {
    fn deref_mut(&mut self) -> &mut Core<M> {
        &mut self.core
    }
}

const READABLE: &[State] = &[
    State::InitializationMode,
    State::StepComplete,
    State::StepFailed,
    State::Terminated,
    State::Error,
];

const WRITABLE: &[State] = &[
    State::Instantiated,
    State::InitializationMode,
    State::StepComplete,
];

/// The model's instantiation token: its FMI 2.0 GUID (a hash of its table).
pub fn instantiation_token(d: &ModelDescription) -> String {
    fmi2_slave::xml::guid(d)
}

impl<M: Model> Instance<M> {
    /// `fmi3InstantiateCoSimulation` of an FMU unpacked with its
    /// `resources/` folder at `resources`: the description is
    /// [`Model::description_for`] it, `token` must be its instantiation
    /// token. Logs and returns `None` otherwise.
    pub fn new(log: Logger, token: &str, resources: Option<PathBuf>) -> Option<Self> {
        let core = Core::new(
            "fmi3InstantiateCoSimulation",
            log,
            token,
            resources,
            instantiation_token,
            &FMI3,
        )?;
        let layout = Layout::new(&core.description);
        Some(Self { core, layout })
    }

    /// The variables as FMI 3.0 sees them (arrays).
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// `fmi3SetDebugLogging`.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[&str]) -> Status {
        self.core
            .set_debug_logging("fmi3SetDebugLogging", on, categories)
    }

    /// `fmi3EnterInitializationMode`: the experiment (FMI 2.0's
    /// `fmi2SetupExperiment`, with its checks) and the transition.
    pub fn enter_initialization_mode(
        &mut self,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> Status {
        const F: &str = "fmi3EnterInitializationMode";
        let r = self
            .core
            .set_experiment(F, tolerance, start_time, stop_time)
            .and_then(|()| self.core.enter_initialization(F))
            .map(|()| Status::Ok);
        self.conclude(r)
    }

    /// `fmi3ExitInitializationMode`: builds the model (parameter
    /// validation), computes the outputs and enters Step Mode.
    pub fn exit_initialization_mode(&mut self) -> Status {
        self.core
            .exit_initialization_mode("fmi3ExitInitializationMode")
    }

    /// `fmi3Terminate`.
    pub fn terminate(&mut self) -> Status {
        self.core.terminate("fmi3Terminate")
    }

    /// The variable of `vr` if it has type `ty` (index into the layout).
    fn lookup(&self, func: &str, ty: Fmi3Type, vr: u32) -> Result<usize, String> {
        let k = self
            .layout
            .find(vr)
            .ok_or_else(|| format!("{func}: unknown value reference {vr}"))?;
        let v = &self.layout.variables[k];
        if v.fmi3_type != ty {
            return Err(format!(
                "{func}: {} (value reference {vr}) is a {} variable (fmi3Get{} / fmi3Set{})",
                v.name,
                v.fmi3_type.xml_name(),
                v.fmi3_type.access_name(),
                v.fmi3_type.access_name()
            ));
        }
        Ok(k)
    }

    /// Generic getter: `write(k, value)` receives value number `k` of the
    /// flattened result (arrays in row-major order); `n_values` must be
    /// the total number of values of `vrs`.
    pub fn get(
        &mut self,
        func: &'static str,
        ty: Fmi3Type,
        vrs: &[u32],
        n_values: usize,
        mut write: impl FnMut(usize, Value),
    ) -> Status {
        let r = (|| {
            self.require(func, READABLE)?;
            let mut total = 0usize;
            let mut needs_model = false;
            for &vr in vrs {
                let v = &self.layout.variables[self.lookup(func, ty, vr)?];
                total += v.len();
                needs_model |= v
                    .first(&self.core.description)
                    .is_some_and(|first| first.effective_initial() == Some(Initial::Calculated));
            }
            if total != n_values {
                return Err(format!(
                    "{func}: nValues = {n_values}, the value references have {total} values"
                ));
            }
            if self.core.state == State::InitializationMode
                && needs_model
                && !self.core.model_current
            {
                self.core.compute_initial(func)?;
            }
            let mut k = 0;
            for &vr in vrs {
                let v = &self.layout.variables[self.lookup(func, ty, vr)?];
                if v.is_time() {
                    write(k, Value::Real(self.core.time));
                    k += 1;
                }
                for i in v.elements.clone() {
                    write(k, self.core.values.at(i));
                    k += 1;
                }
            }
            Ok(Status::Ok)
        })();
        self.conclude(r)
    }

    /// Generic setter: `value(k)` is value number `k` of the flattened
    /// input (arrays in row-major order; an error for a value the type
    /// cannot hold). All values are checked before any is stored, so a
    /// rejected call changes nothing.
    pub fn set(
        &mut self,
        func: &'static str,
        ty: Fmi3Type,
        vrs: &[u32],
        n_values: usize,
        value: impl Fn(usize) -> Result<Value, String>,
    ) -> Status {
        let r = (|| {
            self.require(func, WRITABLE)?;
            let mut total = 0usize;
            for &vr in vrs {
                total += self.layout.variables[self.lookup(func, ty, vr)?].len();
            }
            if total != n_values {
                return Err(format!(
                    "{func}: nValues = {n_values}, the value references have {total} values"
                ));
            }
            let mut tunables = false;
            let mut k = 0;
            for &vr in vrs {
                let v = &self.layout.variables[self.lookup(func, ty, vr)?];
                let Some(first) = v.first(&self.core.description) else {
                    return Err(format!(
                        "{func}: {} (value reference {vr}) is the independent variable: \
                         it cannot be set",
                        v.name
                    ));
                };
                if !layout::settable(first, self.core.state) {
                    return Err(format!(
                        "{func}: {} (value reference {vr}, causality {:?}, variability {:?}) \
                         cannot be set in {}",
                        v.name,
                        first.causality,
                        first.variability,
                        state_name(self.core.state)
                    ));
                }
                for i in v.elements.clone() {
                    let x = value(k).map_err(|e| {
                        format!(
                            "{func}: rejected: {}: {e}",
                            self.core.description.variables[i].name
                        )
                    })?;
                    self.core.description.variables[i]
                        .check_value(x)
                        .map_err(|e| format!("{func}: rejected: {e}"))?;
                    k += 1;
                }
                tunables |= self.core.state == State::StepComplete
                    && first.causality == Causality::Parameter
                    && first.variability == Variability::Tunable;
            }
            // Only a tunable change (rare, between steps) may allocate the backup.
            let mut backup: Vec<(usize, Value)> = Vec::new();
            if tunables {
                for &vr in vrs {
                    let v = &self.layout.variables[self.lookup(func, ty, vr)?];
                    backup.extend(v.elements.clone().map(|i| (i, self.core.values.at(i))));
                }
            }
            let mut k = 0;
            for &vr in vrs {
                let elements = self.layout.variables[self.lookup(func, ty, vr)?]
                    .elements
                    .clone();
                for i in elements {
                    self.core.values.set_at(i, value(k)?);
                    k += 1;
                }
            }
            self.core.model_current &= self.core.state == State::StepComplete;
            if tunables {
                self.core.apply_tunables(func, backup)?;
            }
            Ok(Status::Ok)
        })();
        self.conclude(r)
    }

    /// A getter or setter of a type this FMU has no variables of
    /// (`type_name`: Float32, Int8, String, Binary, Clock, ...): `fmi3OK`
    /// for no value references, else `fmi3Error` naming the first.
    pub fn other_type_access(
        &mut self,
        func: &'static str,
        type_name: &str,
        vrs: &[u32],
        setter: bool,
    ) -> Status {
        // The state check comes first, also for an empty call: the states
        // are those of the other getters and setters.
        let states = if setter { WRITABLE } else { READABLE };
        let r = self.require(func, states).and_then(|()| match vrs.first() {
            None => Ok(Status::Ok),
            Some(&vr) => Err(match self.layout.find(vr) {
                Some(k) => {
                    let v = &self.layout.variables[k];
                    format!(
                        "{func}: {} (value reference {vr}) is a {} variable, not {type_name} \
                         (use fmi3Get{} / fmi3Set{})",
                        v.name,
                        v.fmi3_type.xml_name(),
                        v.fmi3_type.access_name(),
                        v.fmi3_type.access_name()
                    )
                }
                None => format!(
                    "{func}: unknown value reference {vr} (this FMU has no {type_name} variables)"
                ),
            }),
        });
        self.conclude(r)
    }

    /// `fmi3DoStep`: advances from `t` to `t + h`.
    pub fn do_step(&mut self, t: f64, h: f64) -> (Status, StepOutcome) {
        let r = self.core.step("fmi3DoStep", t, h);
        let status = self.conclude(r);
        (
            status,
            StepOutcome {
                terminate_simulation: self.core.terminate_requested,
                last_successful_time: self.core.last_successful_time,
            },
        )
    }
}
