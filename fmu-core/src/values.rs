//! The value store: current values of all variables, addressed by value
//! reference. The plumbing writes inputs and parameters into it (after
//! checking them against the variable table); the model reads them and writes
//! its outputs. Sized once at instantiation; access does not allocate.

use crate::variables::{BaseType, Causality, ModelDescription, Value};

const NONE: u32 = u32::MAX;

/// Current values of a model's variables.
#[derive(Clone, Debug)]
pub struct Values {
    values: Vec<Value>,
    /// Per base type: value reference -> variable index (`NONE` if unused).
    lookup: [Vec<u32>; 3],
}

fn slot(base: BaseType) -> usize {
    match base {
        BaseType::Real => 0,
        BaseType::Integer => 1,
        BaseType::Boolean => 2,
    }
}

impl Values {
    /// Start values of a (validated) description; calculated values start at zero.
    pub fn new(description: &ModelDescription) -> Self {
        let mut lookup: [Vec<u32>; 3] = Default::default();
        let mut values = Vec::with_capacity(description.variables.len());
        for (i, v) in description.variables.iter().enumerate() {
            let table = &mut lookup[slot(v.var_type.base())];
            let vr = v.value_reference as usize;
            if table.len() <= vr {
                table.resize(vr + 1, NONE);
            }
            table[vr] = i as u32;
            values.push(v.start.unwrap_or(match v.var_type.base() {
                BaseType::Real => Value::Real(0.0),
                BaseType::Integer => Value::Integer(0),
                BaseType::Boolean => Value::Boolean(false),
            }));
        }
        Self { values, lookup }
    }

    /// All values, in the order of the variable table (FMU state).
    pub fn all(&self) -> &[Value] {
        &self.values
    }

    /// The store of `description` holding `values` (a saved state): each
    /// value must have its variable's type, and parameters and inputs must
    /// pass the variable's checks.
    pub fn from_saved(description: &ModelDescription, values: &[Value]) -> Result<Self, String> {
        if values.len() != description.variables.len() {
            return Err(format!(
                "{} values for {} variables",
                values.len(),
                description.variables.len()
            ));
        }
        let mut store = Self::new(description);
        for (i, (var, &value)) in description.variables.iter().zip(values).enumerate() {
            let same_type = matches!(
                (var.var_type.base(), value),
                (BaseType::Real, Value::Real(_))
                    | (BaseType::Integer, Value::Integer(_))
                    | (BaseType::Boolean, Value::Boolean(_))
            );
            if !same_type {
                return Err(format!("{} has type {:?}", var.name, var.var_type));
            }
            if matches!(var.causality, Causality::Parameter | Causality::Input) {
                var.check_value(value)?;
            }
            store.values[i] = value;
        }
        Ok(store)
    }

    /// Index into the variable table of `(base, vr)`, if the reference exists.
    pub fn index(&self, base: BaseType, vr: u32) -> Option<usize> {
        match self.lookup[slot(base)].get(vr as usize) {
            Some(&i) if i != NONE => Some(i as usize),
            _ => None,
        }
    }

    /// The value of variable number `index`.
    pub fn at(&self, index: usize) -> Value {
        self.values[index]
    }

    /// Overwrites variable number `index` (no checks: the plumbing checks
    /// against the table before calling this).
    pub fn set_at(&mut self, index: usize, value: Value) {
        self.values[index] = value;
    }

    fn must(&self, base: BaseType, vr: u32) -> usize {
        // A wrong constant in model code is a programming error, caught by the
        // table test; at run time the panic is turned into fmi2Error.
        self.index(base, vr)
            .unwrap_or_else(|| panic!("model code used unknown {base:?} value reference {vr}"))
    }

    /// Real value of `vr`.
    pub fn real(&self, vr: u32) -> f64 {
        match self.values[self.must(BaseType::Real, vr)] {
            Value::Real(x) => x,
            _ => unreachable!("the Real table holds Real values"),
        }
    }

    /// Writes the Real value of `vr` (outputs, calculated values).
    pub fn set_real(&mut self, vr: u32, x: f64) {
        let i = self.must(BaseType::Real, vr);
        self.values[i] = Value::Real(x);
    }

    /// Integer (or enumeration) value of `vr`.
    pub fn integer(&self, vr: u32) -> i32 {
        match self.values[self.must(BaseType::Integer, vr)] {
            Value::Integer(x) => x,
            _ => unreachable!("the Integer table holds Integer values"),
        }
    }

    /// Writes the Integer value of `vr`.
    pub fn set_integer(&mut self, vr: u32, x: i32) {
        let i = self.must(BaseType::Integer, vr);
        self.values[i] = Value::Integer(x);
    }

    /// Boolean value of `vr`.
    pub fn boolean(&self, vr: u32) -> bool {
        match self.values[self.must(BaseType::Boolean, vr)] {
            Value::Boolean(x) => x,
            _ => unreachable!("the Boolean table holds Boolean values"),
        }
    }

    /// Writes the Boolean value of `vr`.
    pub fn set_boolean(&mut self, vr: u32, x: bool) {
        let i = self.must(BaseType::Boolean, vr);
        self.values[i] = Value::Boolean(x);
    }
}
