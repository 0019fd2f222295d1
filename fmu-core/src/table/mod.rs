//! Declarative variable tables parameterised by the number of joints `n`
//! (Reference-FMUs style: the table is the single source of truth).
//!
//! A [`Table`] is a list of [`Row`]s. A row is one quantity (`q`, `E_ref`,
//! `chart.coef`) with a [`Shape`] that expands it to one scalar variable
//! (`E_ref`), one per joint (`q[1]`..`q[n]`) or one per joint and power
//! (`chart.coef[j,k]`). From the table follow:
//!
//! - the value references, laid out by [`Table::new`]: per base type (Real,
//!   Integer) the rows take consecutive references in table order, a row
//!   marked [`Row::at`] starts its block at a fixed reference (so that a
//!   table extended at the end keeps every earlier reference);
//! - the [`Variable`]s of `modelDescription.xml` ([`Table::variables`]),
//!   their start values taken from a default settings value `S` through the
//!   rows' [`Field`] accessors;
//! - the model's settings from the FMU's current values ([`Table::read`]);
//! - a start-value list for a given settings value ([`Table::start_values`]);
//! - the C header's value-reference constants ([`Table::c_defines`]) and a
//!   Markdown variable table ([`markdown`]).
//!
//! Adding a parameter is one row: its name, shape, type, unit, range,
//! description and the two accessors into the settings.
//!
//! This file is the run-time half (layout, lookups, values into settings);
//! `generate.rs` the generated half (XML variables, C constants, docs).

mod generate;

pub use generate::{RowDoc, markdown};

use crate::values::Values;
use crate::variables::{BaseType, EnumerationType, Value, Variability, Variable};

/// How many scalar variables a row expands to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// One variable, `name`.
    Scalar,
    /// One per joint, `name[j]`, `j = 1..=n`.
    Joints,
    /// One per joint and power, `name[j,k]`, `j = 1..=n`, `k = 0..K`; value
    /// reference `first + K (j - 1) + k`.
    JointPowers(usize),
    /// One per pair of joints `j <= l` (upper triangle), `name[j,l]`, both
    /// 1-based; element `(j, k = l)`, value reference `first` + row-major
    /// position in the triangle.
    JointPairs,
}

impl Shape {
    /// Number of scalar variables for `n` joints.
    pub fn len(self, n: usize) -> usize {
        match self {
            Shape::Scalar => 1,
            Shape::Joints => n,
            Shape::JointPowers(k) => n * k,
            Shape::JointPairs => n * (n + 1) / 2,
        }
    }

    /// The elements in value-reference order.
    pub fn elements(self, n: usize) -> Vec<Element> {
        match self {
            Shape::Scalar => vec![Element::default()],
            Shape::Joints => (0..n).map(|j| Element { j, k: 0 }).collect(),
            Shape::JointPowers(powers) => (0..n)
                .flat_map(|j| (0..powers).map(move |k| Element { j, k }))
                .collect(),
            Shape::JointPairs => (0..n)
                .flat_map(|j| (j..n).map(move |k| Element { j, k }))
                .collect(),
        }
    }

    /// Offset of `e` from the row's first value reference (`n` joints).
    pub fn offset(self, n: usize, e: Element) -> usize {
        match self {
            Shape::Scalar => 0,
            Shape::Joints => e.j,
            Shape::JointPowers(powers) => powers * e.j + e.k,
            // Rows 0..j of the triangle hold n, n - 1, ..., n - j + 1 entries.
            Shape::JointPairs => e.j * n - e.j * e.j.saturating_sub(1) / 2 + (e.k - e.j),
        }
    }
}

/// One element of a row: joint `j` (0-based) and power `k`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Element {
    /// Joint index, 0-based (`name[j + 1]`).
    pub j: usize,
    /// Power ([`Shape::JointPowers`]) or second joint, 0-based
    /// ([`Shape::JointPairs`]).
    pub k: usize,
}

/// The value type of a row.
#[derive(Clone, Debug, PartialEq)]
pub enum Kind {
    /// `fmi2Real`.
    Real,
    /// `fmi2Integer`.
    Integer,
    /// An enumeration (travels as `fmi2Integer`); its items bound the value.
    Enumeration(EnumerationType),
    /// `fmi2Boolean`.
    Boolean,
}

impl Kind {
    fn base(&self) -> BaseType {
        match self {
            Kind::Real => BaseType::Real,
            Kind::Integer | Kind::Enumeration(_) => BaseType::Integer,
            Kind::Boolean => BaseType::Boolean,
        }
    }
}

/// Accessors of a parameter row into the settings `S` (start values come
/// from `get` on the defaults; the FMU's values go in through `set`).
pub enum Field<S> {
    /// A Real parameter.
    Real {
        /// Reads element `e` from the settings.
        get: fn(&S, Element) -> f64,
        /// Writes element `e` into the settings.
        set: fn(&mut S, Element, f64),
    },
    /// An Integer or enumeration parameter.
    Integer {
        /// Reads element `e` from the settings.
        get: fn(&S, Element) -> i32,
        /// Writes element `e` into the settings.
        set: fn(&mut S, Element, i32),
    },
    /// A Boolean parameter.
    Boolean {
        /// Reads element `e` from the settings.
        get: fn(&S, Element) -> bool,
        /// Writes element `e` into the settings.
        set: fn(&mut S, Element, bool),
    },
}

impl<S> Field<S> {
    /// A Real field.
    pub fn real(get: fn(&S, Element) -> f64, set: fn(&mut S, Element, f64)) -> Self {
        Field::Real { get, set }
    }

    /// An Integer (or enumeration) field.
    pub fn integer(get: fn(&S, Element) -> i32, set: fn(&mut S, Element, i32)) -> Self {
        Field::Integer { get, set }
    }

    /// A Boolean field.
    pub fn boolean(get: fn(&S, Element) -> bool, set: fn(&mut S, Element, bool)) -> Self {
        Field::Boolean { get, set }
    }

    fn get(&self, s: &S, e: Element) -> Value {
        match self {
            Field::Real { get, .. } => Value::Real(get(s, e)),
            Field::Integer { get, .. } => Value::Integer(get(s, e)),
            Field::Boolean { get, .. } => Value::Boolean(get(s, e)),
        }
    }

    fn set(&self, s: &mut S, e: Element, v: Value) {
        match (self, v) {
            (Field::Real { set, .. }, Value::Real(x)) => set(s, e, x),
            (Field::Integer { set, .. }, Value::Integer(i)) => set(s, e, i),
            (Field::Boolean { set, .. }, Value::Boolean(b)) => set(s, e, b),
            // The plumbing stores values of the row's own type only.
            _ => {}
        }
    }
}

/// What the host does with a row.
pub enum Role<S> {
    /// Set by the master every communication step; the model reads it.
    Input {
        /// Start value.
        start: f64,
    },
    /// Computed by the model. No direct feedthrough within a step.
    Output {
        /// `Continuous` or `Discrete` (changes only at communication points).
        variability: Variability,
    },
    /// A parameter held in the settings.
    Parameter {
        /// May change between communication steps.
        tunable: bool,
        /// Accessors into the settings.
        field: Field<S>,
    },
}

/// Initial dependencies of an output (ModelStructure `InitialUnknowns`).
#[derive(Clone, Debug, PartialEq)]
pub enum Deps {
    /// Every input and exact parameter (attribute omitted).
    All,
    /// Every element of the named rows.
    Rows(Vec<&'static str>),
    /// Element `j` of the named row (e.g. `q[j]` on `q0[j]`).
    SameJoint(&'static str),
}

/// One quantity of the table (see the module documentation).
pub struct Row<S> {
    /// Base name: `q`, `E_ref`, `chart.coef`.
    pub name: &'static str,
    /// Expansion per joint.
    pub shape: Shape,
    /// Value type.
    pub kind: Kind,
    /// Causality and, for parameters, the settings accessors.
    pub role: Role<S>,
    /// Unit (Real rows).
    pub unit: Option<&'static str>,
    /// Smallest allowed value.
    pub min: Option<f64>,
    /// Largest allowed value.
    pub max: Option<f64>,
    /// XML description; `{j}` and `{k}` are replaced by the joint (1-based)
    /// and the power of each element.
    pub description: String,
    /// One-line meaning for the Markdown table (default: the description).
    pub summary: Option<String>,
    /// Start column of the Markdown table (default: the start values).
    pub start_text: Option<String>,
    /// Range column of the Markdown table (default: from min and max), for
    /// a range that depends on the number of joints.
    pub range_text: Option<String>,
    /// Fixed first value reference of the row's block.
    pub at: Option<u32>,
    /// Free tag for selecting rows (e.g. `"model"` for the start-value files).
    pub group: Option<&'static str>,
    /// Initial dependencies (outputs).
    pub initial_dependencies: Deps,
}

impl<S> Row<S> {
    fn new(name: &'static str, shape: Shape, kind: Kind) -> Self {
        Self {
            name,
            shape,
            kind,
            role: Role::Output {
                variability: Variability::Continuous,
            },
            unit: None,
            min: None,
            max: None,
            description: String::new(),
            summary: None,
            start_text: None,
            range_text: None,
            at: None,
            group: None,
            initial_dependencies: Deps::All,
        }
    }

    /// A Real row (an output until a role is chosen).
    pub fn real(name: &'static str, shape: Shape) -> Self {
        Self::new(name, shape, Kind::Real)
    }

    /// An Integer row.
    pub fn integer(name: &'static str, shape: Shape) -> Self {
        Self::new(name, shape, Kind::Integer)
    }

    /// A Boolean row.
    pub fn boolean(name: &'static str, shape: Shape) -> Self {
        Self::new(name, shape, Kind::Boolean)
    }

    /// An enumeration row; its range is the items' range.
    pub fn enumeration(name: &'static str, shape: Shape, t: EnumerationType) -> Self {
        let min = t.items.iter().map(|i| i.1).min().map(f64::from);
        let max = t.items.iter().map(|i| i.1).max().map(f64::from);
        let mut row = Self::new(name, shape, Kind::Enumeration(t));
        row.min = min;
        row.max = max;
        row
    }

    /// An input with the given start value.
    pub fn input(mut self, start: f64) -> Self {
        self.role = Role::Input { start };
        self
    }

    /// An output (continuous for Real rows, discrete otherwise).
    pub fn output(mut self) -> Self {
        let variability = if self.kind == Kind::Real {
            Variability::Continuous
        } else {
            Variability::Discrete
        };
        self.role = Role::Output { variability };
        self
    }

    /// A discrete output (changes only at communication points).
    pub fn discrete_output(mut self) -> Self {
        self.role = Role::Output {
            variability: Variability::Discrete,
        };
        self
    }

    /// A fixed parameter.
    pub fn parameter(mut self, field: Field<S>) -> Self {
        self.role = Role::Parameter {
            tunable: false,
            field,
        };
        self
    }

    /// A tunable parameter.
    pub fn tunable(mut self, field: Field<S>) -> Self {
        self.role = Role::Parameter {
            tunable: true,
            field,
        };
        self
    }

    /// Sets the unit.
    pub fn unit(mut self, unit: &'static str) -> Self {
        self.unit = Some(unit);
        self
    }

    /// Sets the allowed range.
    pub fn range(mut self, min: f64, max: f64) -> Self {
        self.min = Some(min);
        self.max = Some(max);
        self
    }

    /// Sets the XML description (template with `{j}`, `{k}`).
    pub fn describe(mut self, text: impl Into<String>) -> Self {
        self.description = text.into();
        self
    }

    /// Sets the Markdown meaning.
    pub fn summary(mut self, text: impl Into<String>) -> Self {
        self.summary = Some(text.into());
        self
    }

    /// Sets the Markdown start column.
    pub fn start_text(mut self, text: impl Into<String>) -> Self {
        self.start_text = Some(text.into());
        self
    }

    /// Sets the Markdown range column.
    pub fn range_text(mut self, text: impl Into<String>) -> Self {
        self.range_text = Some(text.into());
        self
    }

    /// Starts the row's value-reference block at `vr`.
    pub fn at(mut self, vr: u32) -> Self {
        self.at = Some(vr);
        self
    }

    /// Tags the row.
    pub fn group(mut self, group: &'static str) -> Self {
        self.group = Some(group);
        self
    }

    /// Sets the initial dependencies (outputs).
    pub fn initially_depends_on(mut self, deps: Deps) -> Self {
        self.initial_dependencies = deps;
        self
    }

    /// The name of element `e`: `q[2]`, `chart.coef[1,3]`, `E_ref`.
    pub fn element_name(&self, e: Element) -> String {
        match self.shape {
            Shape::Scalar => self.name.to_string(),
            Shape::Joints => format!("{}[{}]", self.name, e.j + 1),
            Shape::JointPowers(_) => format!("{}[{},{}]", self.name, e.j + 1, e.k),
            Shape::JointPairs => format!("{}[{},{}]", self.name, e.j + 1, e.k + 1),
        }
    }

    /// The name pattern: `q[j]`, `chart.coef[j,k]`, `E_ref`.
    pub fn pattern(&self) -> String {
        match self.shape {
            Shape::Scalar => self.name.to_string(),
            Shape::Joints => format!("{}[j]", self.name),
            Shape::JointPowers(_) => format!("{}[j,k]", self.name),
            Shape::JointPairs => format!("{}[j,l]", self.name),
        }
    }

    /// True for parameters.
    pub fn is_parameter(&self) -> bool {
        matches!(self.role, Role::Parameter { .. })
    }

    /// True for tunable parameters.
    pub fn is_tunable(&self) -> bool {
        matches!(self.role, Role::Parameter { tunable: true, .. })
    }

    fn start(&self, defaults: &S, e: Element) -> Option<Value> {
        match &self.role {
            Role::Input { start } => Some(Value::Real(*start)),
            Role::Output { .. } => None,
            Role::Parameter { field, .. } => Some(field.get(defaults, e)),
        }
    }
}

fn fill(template: &str, e: Element) -> String {
    template
        .replace("{j}", &(e.j + 1).to_string())
        .replace("{k}", &e.k.to_string())
}

/// A table for `n` joints with its value-reference layout.
pub struct Table<S> {
    /// Number of joints.
    pub n: usize,
    /// The rows, in XML order.
    pub rows: Vec<Row<S>>,
    /// First value reference of each row.
    first: Vec<u32>,
}

impl<S> Table<S> {
    /// Lays out the value references: per base type, consecutive in row
    /// order; a row with [`Row::at`] starts at that reference.
    pub fn new(n: usize, rows: Vec<Row<S>>) -> Self {
        let mut next = [0u32; 3];
        let first = rows
            .iter()
            .map(|row| {
                let slot = match row.kind.base() {
                    BaseType::Real => 0,
                    BaseType::Integer => 1,
                    BaseType::Boolean => 2,
                };
                let start = row.at.unwrap_or(next[slot]);
                next[slot] = start + row.shape.len(n) as u32;
                start
            })
            .collect();
        Self { n, rows, first }
    }

    /// Index of the row named `name`.
    pub fn row_index(&self, name: &str) -> Option<usize> {
        self.rows.iter().position(|r| r.name == name)
    }

    /// The row named `name`.
    pub fn row(&self, name: &str) -> Option<&Row<S>> {
        self.row_index(name).map(|i| &self.rows[i])
    }

    /// Value reference of element `e` of row number `i`.
    pub fn vr_at(&self, i: usize, e: Element) -> u32 {
        self.first[i] + self.rows[i].shape.offset(self.n, e) as u32
    }

    /// Value reference of element `e` of the row named `name`.
    pub fn vr(&self, name: &str, e: Element) -> Option<u32> {
        self.row_index(name).map(|i| self.vr_at(i, e))
    }

    /// Value references of the `n` elements of a [`Shape::Joints`] row
    /// (`None` if there is no such row).
    pub fn joint_vrs<const N: usize>(&self, name: &str) -> Option<[u32; N]> {
        let i = self.row_index(name)?;
        Some(std::array::from_fn(|j| self.vr_at(i, Element { j, k: 0 })))
    }

    /// Writes the parameters of the rows selected by `select` from the
    /// FMU's current `values` into `settings`.
    pub fn read(&self, values: &Values, settings: &mut S, select: impl Fn(&Row<S>) -> bool) {
        for (i, row) in self.rows.iter().enumerate() {
            let Role::Parameter { field, .. } = &row.role else {
                continue;
            };
            if !select(row) {
                continue;
            }
            for e in row.shape.elements(self.n) {
                let vr = self.vr_at(i, e);
                let v = match row.kind.base() {
                    BaseType::Real => Value::Real(values.real(vr)),
                    BaseType::Integer => Value::Integer(values.integer(vr)),
                    BaseType::Boolean => Value::Boolean(values.boolean(vr)),
                };
                field.set(settings, e, v);
            }
        }
    }

    /// `settings` with the parameters `(name, value)` of the FMU described
    /// by `d` (this table's description) set, each checked as `fmi2SetReal`
    /// / `fmi2SetInteger` / `fmi2SetBoolean` would check it: Integer and
    /// enumeration parameters take integral values, Boolean ones 0 or 1.
    /// Refused, naming the variable: an unknown name, a variable that is
    /// not a parameter, a value out of range or not integral where it must be.
    /// `settings` must hold the table's start values (the defaults).
    pub fn settings_from_named(
        &self,
        d: &crate::ModelDescription,
        mut settings: S,
        values: &[(&str, f64)],
    ) -> Result<S, String> {
        let mut current = Values::new(d);
        for &(name, x) in values {
            let (v, value) = named_value(d, name, x)?;
            let index = current
                .index(v.var_type.base(), v.value_reference)
                .ok_or_else(|| format!("{name}: no value slot"))?;
            current.set_at(index, value);
        }
        self.read(&current, &mut settings, |_| true);
        Ok(settings)
    }

    /// `(name, value)` of every element of the parameter rows selected by
    /// `select`, read from `settings`, in table order.
    pub fn start_values(
        &self,
        settings: &S,
        select: impl Fn(&Row<S>) -> bool,
    ) -> Vec<(String, Value)> {
        let mut out = vec![];
        for row in &self.rows {
            let Role::Parameter { field, .. } = &row.role else {
                continue;
            };
            if select(row) {
                for e in row.shape.elements(self.n) {
                    out.push((row.element_name(e), field.get(settings, e)));
                }
            }
        }
        out
    }
}

pub use crate::variables::compact;

/// The parameter `name` of the FMU described by `d` and `x` as its value,
/// checked as `fmi2Set*` would check it.
pub fn named_value<'d>(
    d: &'d crate::ModelDescription,
    name: &str,
    x: f64,
) -> Result<(&'d Variable, Value), String> {
    let v = d
        .variable(name)
        .ok_or_else(|| format!("{name} is not a variable of {}", d.model_name))?;
    if v.causality != crate::Causality::Parameter {
        return Err(format!(
            "{name} is not a parameter of {} (it is set or read while running)",
            d.model_name
        ));
    }
    let value = match v.var_type.base() {
        BaseType::Real => Value::Real(x),
        BaseType::Boolean if x == 0.0 || x == 1.0 => Value::Boolean(x == 1.0),
        BaseType::Boolean => return Err(format!("{name} = {x} must be 0 or 1 (Boolean)")),
        _ if x.fract() == 0.0 && x.abs() <= i32::MAX as f64 => Value::Integer(x as i32),
        _ => return Err(format!("{name} = {x} must be an integer")),
    };
    v.check_value(value)?;
    Ok((v, value))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Default)]
    struct S {
        a: [f64; 3],
        c: [[f64; 2]; 3],
        mode: i32,
    }

    fn table(n: usize) -> Table<S> {
        Table::new(
            n,
            vec![
                Row::<S>::real("q", Shape::Joints).input(0.0).unit("rad"),
                Row::<S>::real("energy", Shape::Scalar).output(),
                Row::<S>::real("a", Shape::Joints)
                    .parameter(Field::real(|s, e| s.a[e.j], |s, e, v| s.a[e.j] = v))
                    .range(0.0, 1e6)
                    .describe("a of joint {j}"),
                Row::<S>::real("c.x", Shape::JointPowers(2))
                    .parameter(Field::real(
                        |s, e| s.c[e.j][e.k],
                        |s, e, v| s.c[e.j][e.k] = v,
                    ))
                    .at(100),
                Row::<S>::real("q0", Shape::Joints)
                    .parameter(Field::real(|_, _| 0.5, |_, _, _| {})),
                Row::<S>::integer("mode", Shape::Scalar)
                    .parameter(Field::integer(|s, _| s.mode, |s, _, v| s.mode = v)),
            ],
        )
    }

    #[test]
    fn layout_is_consecutive_per_base_type_with_fixed_blocks() {
        let t = table(3);
        assert_eq!(t.joint_vrs::<3>("q"), Some([0, 1, 2]));
        assert_eq!(t.vr("energy", Element::default()), Some(3));
        assert_eq!(t.joint_vrs::<3>("a"), Some([4, 5, 6]));
        assert_eq!(t.vr("c.x", Element { j: 2, k: 1 }), Some(105));
        assert_eq!(t.joint_vrs::<3>("q0"), Some([106, 107, 108]));
        assert_eq!(t.vr("mode", Element::default()), Some(0));
        let t2 = table(2);
        assert_eq!(t2.joint_vrs::<2>("a"), Some([3, 4]));
        assert_eq!(t2.vr("c.x", Element { j: 1, k: 1 }), Some(103));
    }

    #[test]
    fn variables_names_and_start_values_follow_the_rows() {
        let t = table(2);
        let s = S {
            a: [1.5, 2.5, 0.0],
            ..Default::default()
        };
        let v = t.variables(&s);
        let names: Vec<&str> = v.iter().map(|v| v.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "q[1]", "q[2]", "energy", "a[1]", "a[2]", "c.x[1,0]", "c.x[1,1]", "c.x[2,0]",
                "c.x[2,1]", "q0[1]", "q0[2]", "mode"
            ]
        );
        assert_eq!(v[4].start, Some(Value::Real(2.5)));
        assert_eq!(v[4].description, "a of joint 2");
        assert_eq!(v[4].max, Some(1e6));
        let sv = t.start_values(&s, |r| r.name == "a");
        assert_eq!(
            sv,
            [
                ("a[1]".to_string(), Value::Real(1.5)),
                ("a[2]".to_string(), Value::Real(2.5))
            ]
        );
    }

    /// Boolean rows get their own value references; a pair row is the
    /// upper triangle, row by row.
    #[test]
    fn boolean_and_joint_pair_rows() {
        #[derive(Default)]
        struct B {
            on: bool,
        }
        let t = Table::new(
            3,
            vec![
                Row::<B>::real("x", Shape::Scalar).output(),
                Row::<B>::real("A", Shape::JointPairs).output(),
                Row::<B>::boolean("on", Shape::Scalar)
                    .parameter(Field::boolean(|s, _| s.on, |s, _, v| s.on = v)),
            ],
        );
        let pairs: Vec<(String, u32)> = Shape::JointPairs
            .elements(3)
            .into_iter()
            .map(|e| (t.rows[1].element_name(e), t.vr_at(1, e)))
            .collect();
        let expected = [
            ("A[1,1]", 1),
            ("A[1,2]", 2),
            ("A[1,3]", 3),
            ("A[2,2]", 4),
            ("A[2,3]", 5),
            ("A[3,3]", 6),
        ];
        assert_eq!(pairs.len(), expected.len());
        for ((name, vr), (n, v)) in pairs.iter().zip(expected) {
            assert_eq!((name.as_str(), *vr), (n, v));
        }
        assert_eq!(t.vr("on", Element::default()), Some(0));
        let v = t.variables(&B { on: true });
        assert_eq!(v.last().unwrap().start, Some(Value::Boolean(true)));
        let h = t.c_defines("X_", "X").unwrap();
        assert!(h.contains("#define X_VR_A_2_3 5\n"), "{h}");
        assert!(h.contains("Boolean value reference of on"), "{h}");
        let md = markdown(&[("X", t.docs(&B::default()))]).unwrap();
        assert!(md.contains("| `on` | bool 0 | parameter (fixed) |"), "{md}");
        assert!(md.contains("| `A[j,l]` | 1, 2, 3, 4, 5, 6 |"), "{md}");
    }

    #[test]
    fn c_defines_and_markdown() {
        let t = table(2);
        let h = t.c_defines("X_", "X").unwrap();
        assert!(h.contains("#define X_VR_Q1 0\n"), "{h}");
        assert!(h.contains("#define X_VR_Q0_2 105\n"), "{h}");
        assert!(h.contains("#define X_VR_C_X_JK(j, k) (100 + 2 * ((j) - 1) + (k))"));
        assert!(h.contains("#define X_VR_MODE 0\n"));
        let md = markdown(&[("X", t.docs(&S::default()))]).unwrap();
        assert!(
            md.contains("| `a[j]` | 3, 4 | parameter (fixed) |  | 0 | [0, 1e6] | a of joint j |"),
            "{md}"
        );
        assert!(md.contains("| `c.x[j,k]` | 100 + 2 (j-1) + k |"), "{md}");
        assert_eq!(compact(1e-6), "1e-6");
        assert_eq!(compact(9.81), "9.81");
        assert_eq!(compact(2500.0), "2500");
    }
}
