//! One FMU instance: the FMI 2.0 Co-Simulation state machine, argument
//! checks and value-reference dispatch around a [`Model`]. This is the safe
//! Rust API; [`crate::abi`] wraps it for C.

use crate::logger::{Logger, Status};
pub use crate::model::{Context, Experiment, Model, ModelError, State};
use crate::variables::{BaseType, Causality, Initial, Value, Variability};
pub use fmu_core::instance::MAX_START_TIME;
use fmu_core::instance::{Core, Dialect};
use std::ops::{Deref, DerefMut};
use std::path::PathBuf;

/// FMI 2.0's words in the instance's messages.
static FMI2: Dialect = Dialect {
    state_name: State::name,
    state_word: "state ",
    can_save_state: "canGetAndSetFMUstate",
    token_name: "GUID",
    initialized: "initialization done, ready to step",
};

/// One instance of model `M` with its state machine: the version-neutral
/// [`Core`] (values, state, model, clock, FMU state save and restore, which
/// it derefs to) and the FMI 2.0 calls around it.
pub struct Instance<M: Model> {
    core: Core<M>,
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

/// States in which `fmi2Get*Status` may be called.
const STATUS_READABLE: &[State] = &[State::StepComplete, State::StepFailed, State::Terminated];

impl<M: Model> Instance<M> {
    /// `fmi2Instantiate`: checks the GUID against the model's; logs and
    /// returns `None` on mismatch or an invalid variable table.
    pub fn new(log: Logger, guid: &str) -> Option<Self> {
        Self::with_resources(log, guid, None)
    }

    /// `fmi2Instantiate` of an FMU unpacked with its `resources/` folder at
    /// `resources`: the description is [`Model::description_for`] it.
    pub fn with_resources(log: Logger, guid: &str, resources: Option<PathBuf>) -> Option<Self> {
        let core = Core::new(
            "fmi2Instantiate",
            log,
            guid,
            resources,
            crate::xml::guid,
            &FMI2,
        )?;
        Some(Self { core })
    }

    /// `fmi2SetDebugLogging`.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[&str]) -> Status {
        self.core
            .set_debug_logging("fmi2SetDebugLogging", on, categories)
    }

    /// `fmi2SetupExperiment`.
    pub fn setup_experiment(
        &mut self,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> Status {
        let r = self
            .core
            .set_experiment("fmi2SetupExperiment", tolerance, start_time, stop_time)
            .map(|()| Status::Ok);
        self.conclude(r)
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization_mode(&mut self) -> Status {
        let r = self
            .core
            .enter_initialization("fmi2EnterInitializationMode")
            .map(|()| Status::Ok);
        self.conclude(r)
    }

    /// `fmi2ExitInitializationMode`: builds the model (parameter validation)
    /// and computes the outputs.
    pub fn exit_initialization_mode(&mut self) -> Status {
        self.core
            .exit_initialization_mode("fmi2ExitInitializationMode")
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> Status {
        self.core.terminate("fmi2Terminate")
    }

    /// Generic getter: `write(k, value)` receives the value of `vrs[k]`.
    pub fn get(
        &mut self,
        func: &'static str,
        base: BaseType,
        vrs: &[u32],
        mut write: impl FnMut(usize, Value),
    ) -> Status {
        let r = (|| {
            self.require(func, READABLE)?;
            let mut indices_ok = true;
            let mut needs_model = false;
            for &vr in vrs {
                match self.core.values.index(base, vr) {
                    Some(i) => {
                        let v = &self.core.description.variables[i];
                        needs_model |= v.effective_initial() == Some(Initial::Calculated);
                    }
                    None => indices_ok = false,
                }
            }
            if !indices_ok {
                let vr = vrs
                    .iter()
                    .find(|&&vr| self.core.values.index(base, vr).is_none())
                    .copied()
                    .unwrap_or_default();
                return Err(format!("{func}: unknown {base:?} value reference {vr}"));
            }
            if self.core.state == State::InitializationMode
                && needs_model
                && !self.core.model_current
            {
                self.core.compute_initial(func)?;
            }
            for (k, &vr) in vrs.iter().enumerate() {
                let i = self.core.values.index(base, vr).expect("checked above");
                write(k, self.core.values.at(i));
            }
            Ok(Status::Ok)
        })();
        self.conclude(r)
    }

    /// Generic setter: `value(k)` is the value for `vrs[k]`. All values are
    /// checked before any is stored, so a rejected call changes nothing.
    pub fn set(
        &mut self,
        func: &'static str,
        base: BaseType,
        vrs: &[u32],
        value: impl Fn(usize) -> Value,
    ) -> Status {
        let r = (|| {
            self.require(
                func,
                &[
                    State::Instantiated,
                    State::InitializationMode,
                    State::StepComplete,
                ],
            )?;
            let mut tunables = false;
            for (k, &vr) in vrs.iter().enumerate() {
                let i = self
                    .values
                    .index(base, vr)
                    .ok_or_else(|| format!("{func}: unknown {base:?} value reference {vr}"))?;
                let var = &self.core.description.variables[i];
                let settable = var.variability != Variability::Constant
                    && match self.core.state {
                        State::Instantiated => {
                            var.causality == Causality::Input
                                || matches!(
                                    var.effective_initial(),
                                    Some(Initial::Exact | Initial::Approx)
                                )
                        }
                        State::InitializationMode => {
                            var.causality == Causality::Input
                                || var.effective_initial() == Some(Initial::Exact)
                        }
                        _ => {
                            var.causality == Causality::Input
                                || (var.causality == Causality::Parameter
                                    && var.variability == Variability::Tunable)
                        }
                    };
                if !settable {
                    return Err(format!(
                        "{func}: {} (value reference {vr}, causality {:?}, variability {:?}) cannot be set in state {}",
                        var.name, var.causality, var.variability, self.core.state
                    ));
                }
                var.check_value(value(k))
                    .map_err(|e| format!("{func}: rejected: {e}"))?;
                tunables |=
                    self.core.state == State::StepComplete && var.causality == Causality::Parameter;
            }
            // Only a tunable change (rare, between steps) may allocate the backup.
            let backup: Vec<(usize, Value)> = if tunables {
                vrs.iter()
                    .map(|&vr| {
                        let i = self.core.values.index(base, vr).expect("checked above");
                        (i, self.core.values.at(i))
                    })
                    .collect()
            } else {
                Vec::new()
            };
            for (k, &vr) in vrs.iter().enumerate() {
                let i = self.core.values.index(base, vr).expect("checked above");
                self.core.values.set_at(i, value(k));
            }
            self.core.model_current &= self.core.state == State::StepComplete;
            if tunables {
                self.core.apply_tunables(func, backup)?;
            }
            Ok(Status::Ok)
        })();
        self.conclude(r)
    }

    /// `fmi2GetReal`.
    pub fn get_real(&mut self, vrs: &[u32], out: &mut [f64]) -> Status {
        if vrs.len() != out.len() {
            return self.fail("fmi2GetReal: value array length differs from vr array length");
        }
        self.get("fmi2GetReal", BaseType::Real, vrs, |k, v| {
            if let Value::Real(x) = v {
                out[k] = x;
            }
        })
    }

    /// `fmi2SetReal`.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Status {
        if vrs.len() != values.len() {
            return self.fail("fmi2SetReal: value array length differs from vr array length");
        }
        self.set("fmi2SetReal", BaseType::Real, vrs, |k| {
            Value::Real(values[k])
        })
    }

    /// `fmi2GetInteger`.
    pub fn get_integer(&mut self, vrs: &[u32], out: &mut [i32]) -> Status {
        if vrs.len() != out.len() {
            return self.fail("fmi2GetInteger: value array length differs from vr array length");
        }
        self.get("fmi2GetInteger", BaseType::Integer, vrs, |k, v| {
            if let Value::Integer(x) = v {
                out[k] = x;
            }
        })
    }

    /// `fmi2SetInteger`.
    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Status {
        if vrs.len() != values.len() {
            return self.fail("fmi2SetInteger: value array length differs from vr array length");
        }
        self.set("fmi2SetInteger", BaseType::Integer, vrs, |k| {
            Value::Integer(values[k])
        })
    }

    /// `fmi2GetBoolean`.
    pub fn get_boolean(&mut self, vrs: &[u32], out: &mut [bool]) -> Status {
        if vrs.len() != out.len() {
            return self.fail("fmi2GetBoolean: value array length differs from vr array length");
        }
        self.get("fmi2GetBoolean", BaseType::Boolean, vrs, |k, v| {
            if let Value::Boolean(x) = v {
                out[k] = x;
            }
        })
    }

    /// `fmi2SetBoolean`.
    pub fn set_boolean(&mut self, vrs: &[u32], values: &[bool]) -> Status {
        if vrs.len() != values.len() {
            return self.fail("fmi2SetBoolean: value array length differs from vr array length");
        }
        self.set("fmi2SetBoolean", BaseType::Boolean, vrs, |k| {
            Value::Boolean(values[k])
        })
    }

    /// `fmi2GetString` / `fmi2SetString`: the models have no String
    /// variables, so any value reference is unknown.
    pub fn string_access(&mut self, func: &'static str, vrs: &[u32], setter: bool) -> Status {
        // The state check comes first, also for an empty call (nvr = 0):
        // the states are those of the other getters and setters.
        let states: &[State] = if setter {
            &[
                State::Instantiated,
                State::InitializationMode,
                State::StepComplete,
            ]
        } else {
            READABLE
        };
        let r = self.require(func, states).and_then(|()| match vrs.first() {
            None => Ok(Status::Ok),
            Some(vr) => Err(format!(
                "{func}: unknown String value reference {vr} (this FMU has no String variables)"
            )),
        });
        self.conclude(r)
    }

    /// `fmi2DoStep`: advances from `t` to `t + h`.
    pub fn do_step(&mut self, t: f64, h: f64) -> Status {
        let r = self.core.step("fmi2DoStep", t, h);
        self.conclude(r)
    }

    /// `fmi2GetRealStatus(fmi2LastSuccessfulTime)`.
    pub fn last_successful_time(&mut self) -> Result<f64, Status> {
        let r = self.require("fmi2GetRealStatus", STATUS_READABLE);
        match r {
            Ok(()) => Ok(self.core.last_successful_time),
            Err(e) => Err(self.conclude(Err(e))),
        }
    }

    /// `fmi2GetBooleanStatus(fmi2Terminated)`: whether the slave asks to stop
    /// (after a discarded step it cannot continue).
    pub fn terminate_requested(&mut self) -> Result<bool, Status> {
        let r = self.require("fmi2GetBooleanStatus", STATUS_READABLE);
        match r {
            Ok(()) => Ok(self.core.terminate_requested),
            Err(e) => Err(self.conclude(Err(e))),
        }
    }

    /// A status (`fmi2Get*Status`) this FMU cannot provide: `fmi2Discard`
    /// with a warning line and no state change, as FMI 2.0 section 4.2.3
    /// prescribes ("If a status is required which cannot be retrieved by the
    /// slave it returns fmi2Discard"). Calls in a state where no status may
    /// be queried stay errors.
    pub fn status_unavailable(&mut self, func: &str, why: &str) -> Status {
        let r = self.require(func, STATUS_READABLE).map(|()| {
            self.core.log.log(
                crate::logger::Category::StatusWarning,
                Status::Discard,
                &format!("{func}: status not available: {why}"),
            );
            Status::Discard
        });
        self.conclude(r)
    }
}
