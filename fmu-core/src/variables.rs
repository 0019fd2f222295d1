//! The variable table: one description per model that drives both the
//! value-reference dispatch of the binary and the generated
//! `modelDescription.xml`, so the two cannot drift apart.

use std::collections::HashSet;

/// Base type of a scalar variable (FMI 2.0 `Real`, `Integer`, `Boolean`,
/// `Enumeration`; enumerations travel through `fmi2GetInteger`/`fmi2SetInteger`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum VarType {
    /// `fmi2Real`.
    Real,
    /// `fmi2Integer`.
    Integer,
    /// `fmi2Boolean`.
    Boolean,
    /// An enumeration declared in [`ModelDescription::enumerations`], by name.
    Enumeration(String),
}

impl VarType {
    /// The C API family the variable is accessed through.
    pub fn base(&self) -> BaseType {
        match self {
            VarType::Real => BaseType::Real,
            VarType::Integer | VarType::Enumeration(_) => BaseType::Integer,
            VarType::Boolean => BaseType::Boolean,
        }
    }
}

/// The accessor family (`fmi2GetReal`, `fmi2GetInteger`, `fmi2GetBoolean`);
/// value references are unique within one family.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BaseType {
    /// Real variables.
    Real,
    /// Integer and enumeration variables.
    Integer,
    /// Boolean variables.
    Boolean,
}

/// FMI 2.0 causality.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    /// Set by the user before (fixed) or during (tunable) the simulation.
    Parameter,
    /// Computed from parameters at initialization.
    CalculatedParameter,
    /// Set by the master every communication step.
    Input,
    /// Computed by the model, readable by the master.
    Output,
    /// Internal value, readable for diagnostics.
    Local,
}

/// FMI 2.0 variability.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variability {
    /// Never changes.
    Constant,
    /// Fixed after initialization.
    Fixed,
    /// May change between communication steps (parameters only).
    Tunable,
    /// Changes only at discrete instants (communication points).
    Discrete,
    /// Changes continuously (Real only).
    Continuous,
}

/// FMI 2.0 `initial` attribute.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Initial {
    /// The start value is the value.
    Exact,
    /// The start value is a guess the model may change.
    Approx,
    /// Computed by the model from other variables.
    Calculated,
}

/// A start or current value.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Value {
    /// Real value.
    Real(f64),
    /// Integer or enumeration value.
    Integer(i32),
    /// Boolean value.
    Boolean(bool),
}

/// One scalar variable of the model.
#[derive(Clone, Debug, PartialEq)]
pub struct Variable {
    /// Name as the host shows it (e.g. `q[1]`).
    pub name: String,
    /// Value reference, unique within its [`BaseType`].
    pub value_reference: u32,
    /// Base type.
    pub var_type: VarType,
    /// Causality.
    pub causality: Causality,
    /// Variability.
    pub variability: Variability,
    /// `initial` attribute as written to the XML (`None`: not written).
    pub initial: Option<Initial>,
    /// Start value (required for inputs and parameters, absent for calculated values).
    pub start: Option<Value>,
    /// Unit name, defined in [`ModelDescription::units`].
    pub unit: Option<String>,
    /// One-line description.
    pub description: String,
    /// Smallest allowed value (Real, Integer).
    pub min: Option<f64>,
    /// Largest allowed value (Real, Integer).
    pub max: Option<f64>,
    /// Outputs: names of the inputs this output depends on directly within a
    /// communication step (`Some(vec![])`: none; `None`: all, attribute omitted).
    pub dependencies: Option<Vec<String>>,
    /// Initial unknowns: names of the inputs and exact parameters the value
    /// depends on after initialization (`None`: all, attribute omitted).
    pub initial_dependencies: Option<Vec<String>>,
}

impl Variable {
    fn new(name: impl Into<String>, value_reference: u32, var_type: VarType) -> Self {
        let variability = if var_type == VarType::Real {
            Variability::Continuous
        } else {
            Variability::Discrete
        };
        Self {
            name: name.into(),
            value_reference,
            var_type,
            causality: Causality::Local,
            variability,
            initial: None,
            start: None,
            unit: None,
            description: String::new(),
            min: None,
            max: None,
            dependencies: None,
            initial_dependencies: None,
        }
    }

    /// A Real variable (local, continuous until a causality is chosen).
    pub fn real(name: impl Into<String>, value_reference: u32) -> Self {
        Self::new(name, value_reference, VarType::Real)
    }

    /// An Integer variable.
    pub fn integer(name: impl Into<String>, value_reference: u32) -> Self {
        Self::new(name, value_reference, VarType::Integer)
    }

    /// A Boolean variable.
    pub fn boolean(name: impl Into<String>, value_reference: u32) -> Self {
        Self::new(name, value_reference, VarType::Boolean)
    }

    /// An enumeration variable of the declared type `type_name`.
    pub fn enumeration(
        name: impl Into<String>,
        value_reference: u32,
        type_name: impl Into<String>,
    ) -> Self {
        Self::new(
            name,
            value_reference,
            VarType::Enumeration(type_name.into()),
        )
    }

    /// Causality input with the given start value.
    pub fn input(mut self, start: Value) -> Self {
        self.causality = Causality::Input;
        self.initial = None;
        self.start = Some(start);
        self
    }

    /// Causality output, computed by the model (`initial = calculated`).
    pub fn output(mut self) -> Self {
        self.causality = Causality::Output;
        self.initial = Some(Initial::Calculated);
        self.start = None;
        self
    }

    /// A fixed parameter with the given start value.
    pub fn parameter(mut self, start: Value) -> Self {
        self.causality = Causality::Parameter;
        self.variability = Variability::Fixed;
        self.initial = Some(Initial::Exact);
        self.start = Some(start);
        self
    }

    /// A tunable parameter (may be changed between communication steps).
    pub fn tunable(mut self, start: Value) -> Self {
        self = self.parameter(start);
        self.variability = Variability::Tunable;
        self
    }

    /// Sets the variability (e.g. `Discrete` for a Real output that only
    /// changes at communication points).
    pub fn variability(mut self, variability: Variability) -> Self {
        self.variability = variability;
        self
    }

    /// Sets the unit.
    pub fn unit(mut self, unit: impl Into<String>) -> Self {
        self.unit = Some(unit.into());
        self
    }

    /// Sets the description.
    pub fn describe(mut self, description: impl Into<String>) -> Self {
        self.description = description.into();
        self
    }

    /// Sets the smallest allowed value.
    pub fn min(mut self, min: f64) -> Self {
        self.min = Some(min);
        self
    }

    /// Sets the largest allowed value.
    pub fn max(mut self, max: f64) -> Self {
        self.max = Some(max);
        self
    }

    /// Outputs: the inputs this output depends on directly (empty: none).
    pub fn depends_on(mut self, names: &[&str]) -> Self {
        self.dependencies = Some(names.iter().map(|s| s.to_string()).collect());
        self
    }

    /// Initial unknowns: the knowns this value depends on at initialization.
    pub fn initially_depends_on(mut self, names: &[&str]) -> Self {
        self.initial_dependencies = Some(names.iter().map(|s| s.to_string()).collect());
        self
    }

    /// The `initial` the standard implies when the attribute is absent.
    pub fn effective_initial(&self) -> Option<Initial> {
        self.initial.or(match self.causality {
            Causality::Input => None,
            Causality::Parameter => Some(Initial::Exact),
            Causality::CalculatedParameter | Causality::Output | Causality::Local => {
                Some(Initial::Calculated)
            }
        })
    }

    /// True when the value is one of the "initial unknowns" of the
    /// co-simulation ModelStructure (outputs not given exactly, calculated
    /// parameters).
    pub fn is_initial_unknown(&self) -> bool {
        match self.causality {
            Causality::Output => matches!(
                self.effective_initial(),
                Some(Initial::Approx | Initial::Calculated)
            ),
            Causality::CalculatedParameter => true,
            _ => false,
        }
    }

    /// Checks `value` against the type and the min/max of the variable.
    pub fn check_value(&self, value: Value) -> Result<(), String> {
        let x = match (self.var_type.base(), value) {
            (BaseType::Real, Value::Real(x)) => {
                if !x.is_finite() {
                    return Err(format!("{} = {x} is not a finite number", self.name));
                }
                x
            }
            (BaseType::Integer, Value::Integer(i)) => i as f64,
            (BaseType::Boolean, Value::Boolean(_)) => return Ok(()),
            _ => return Err(format!("{} has type {:?}", self.name, self.var_type)),
        };
        if let Some(min) = self.min
            && x < min
        {
            return Err(format!(
                "{} = {} is below its minimum {}",
                self.name,
                compact(x),
                compact(min)
            ));
        }
        if let Some(max) = self.max
            && x > max
        {
            return Err(format!(
                "{} = {} is above its maximum {}",
                self.name,
                compact(x),
                compact(max)
            ));
        }
        Ok(())
    }
}

/// An enumeration type (`<TypeDefinitions><SimpleType><Enumeration>`).
#[derive(Clone, Debug, PartialEq)]
pub struct EnumerationType {
    /// Type name referenced by [`VarType::Enumeration`].
    pub name: String,
    /// Items `(name, value, description)`.
    pub items: Vec<(String, i32, String)>,
}

/// A unit with its exponents of SI base units (`<UnitDefinitions>`).
#[derive(Clone, Debug, PartialEq)]
pub struct Unit {
    /// Unit name, e.g. `N.m`.
    pub name: String,
    /// Exponent of kg.
    pub kg: i32,
    /// Exponent of m.
    pub m: i32,
    /// Exponent of s.
    pub s: i32,
    /// Exponent of rad.
    pub rad: i32,
}

impl Unit {
    /// A unit `kg^kg m^m s^s rad^rad`.
    pub fn new(name: &str, kg: i32, m: i32, s: i32, rad: i32) -> Self {
        Self {
            name: name.into(),
            kg,
            m,
            s,
            rad,
        }
    }
}

/// `<DefaultExperiment>`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DefaultExperiment {
    /// Start time (s).
    pub start_time: f64,
    /// Stop time (s).
    pub stop_time: f64,
    /// Suggested communication step (s).
    pub step_size: f64,
    /// Suggested relative tolerance of the FMU's integrator, if it has one.
    pub tolerance: Option<f64>,
}

/// Everything the host learns from `modelDescription.xml`, as data.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelDescription {
    /// `modelName`.
    pub model_name: String,
    /// `modelIdentifier`: also the shared library's file name.
    pub model_identifier: String,
    /// One-line description.
    pub description: String,
    /// Model version.
    pub version: String,
    /// Author.
    pub author: String,
    /// Generating tool.
    pub generation_tool: String,
    /// Whether doStep accepts any communication step size.
    pub can_handle_variable_communication_step_size: bool,
    /// Whether the model saves and restores its state ([`crate::Model::save_state`]):
    /// `canGetAndSetFMUstate` and `canSerializeFMUstate`.
    pub can_save_state: bool,
    /// Default experiment, if any.
    pub default_experiment: Option<DefaultExperiment>,
    /// Units used by the variables.
    pub units: Vec<Unit>,
    /// Enumeration types used by the variables.
    pub enumerations: Vec<EnumerationType>,
    /// The variables, in the order of the XML (their 1-based position is the
    /// ModelStructure index).
    pub variables: Vec<Variable>,
}

/// Largest value reference accepted (the dispatch uses a dense lookup table).
pub const MAX_VALUE_REFERENCE: u32 = 1 << 20;

impl ModelDescription {
    /// The variable named `name`.
    pub fn variable(&self, name: &str) -> Option<&Variable> {
        self.variables.iter().find(|v| v.name == name)
    }

    /// Checks the table against the FMI 2.0 rules the dispatch and the XML rely on.
    pub fn validate(&self) -> Result<(), String> {
        let mut names = HashSet::new();
        let mut refs = HashSet::new();
        for v in &self.variables {
            let ctx = |msg: &str| format!("variable {}: {msg}", v.name);
            if !names.insert(v.name.as_str()) {
                return Err(ctx("duplicate name"));
            }
            if v.value_reference >= MAX_VALUE_REFERENCE {
                return Err(ctx("value reference too large"));
            }
            if !refs.insert((v.var_type.base(), v.value_reference)) {
                return Err(ctx("duplicate value reference within its base type"));
            }
            if v.variability == Variability::Continuous && v.var_type != VarType::Real {
                return Err(ctx("only Real variables can be continuous"));
            }
            if matches!(v.variability, Variability::Fixed | Variability::Tunable)
                && !matches!(
                    v.causality,
                    Causality::Parameter | Causality::CalculatedParameter | Causality::Local
                )
            {
                return Err(ctx("fixed/tunable variability needs a parameter"));
            }
            let needs_start = matches!(v.causality, Causality::Input)
                || matches!(
                    v.effective_initial(),
                    Some(Initial::Exact | Initial::Approx)
                );
            match (needs_start, v.start) {
                (true, None) => return Err(ctx("needs a start value")),
                (false, Some(_)) => return Err(ctx("a calculated value has no start value")),
                (true, Some(s)) => v.check_value(s).map_err(|e| ctx(&e))?,
                _ => {}
            }
            if let Some(u) = &v.unit {
                if v.var_type != VarType::Real {
                    return Err(ctx("only Real variables have units"));
                }
                if !self.units.iter().any(|d| &d.name == u) {
                    return Err(ctx("unit not in the unit definitions"));
                }
            }
            if let VarType::Enumeration(t) = &v.var_type
                && !self.enumerations.iter().any(|e| &e.name == t)
            {
                return Err(ctx("enumeration type not declared"));
            }
            if v.dependencies.is_some() && v.causality != Causality::Output {
                return Err(ctx("only outputs list direct dependencies"));
            }
            for d in v.dependencies.iter().flatten() {
                match self.variable(d) {
                    Some(k) if k.causality == Causality::Input => {}
                    _ => return Err(ctx(&format!("dependency {d} is not an input"))),
                }
            }
            if v.initial_dependencies.is_some() && !v.is_initial_unknown() {
                return Err(ctx("only initial unknowns list initial dependencies"));
            }
            for d in v.initial_dependencies.iter().flatten() {
                match self.variable(d) {
                    Some(k)
                        if k.causality == Causality::Input
                            || k.effective_initial() == Some(Initial::Exact) => {}
                    _ => {
                        return Err(ctx(&format!(
                            "initial dependency {d} is neither an input nor an exact value"
                        )));
                    }
                }
            }
        }
        Ok(())
    }
}

/// The shorter of Rust's shortest round-trip decimal and exponent forms, for
/// messages: `1e300`, not three hundred digits.
pub fn compact(x: f64) -> String {
    let plain = format!("{x}");
    let exp = format!("{x:e}");
    if exp.len() < plain.len() { exp } else { plain }
}
