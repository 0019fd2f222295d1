//! The FMI 3.0 view of a model's FMI 2.0-style variable table.
//!
//! [`Layout::new`] reads a [`ModelDescription`] (the one the model gives
//! both FMI versions) and derives, without changing it:
//!
//! - **arrays**: a run of consecutive scalars `base[i]` (or `base[i,k]`, any
//!   number of indices) with the same type, causality, variability, initial,
//!   unit, min, max and description pattern, whose indices enumerate a full
//!   rectangle in row-major order with the first index starting at 1, is one
//!   array variable `base` with one `<Dimension>` per index (the other
//!   indices start where the names say: `chart.coef[1,0]` .. `[N,K-1]` is an
//!   `N x K` array). Its values travel in row-major order, which is the
//!   order of the scalars in the table. A run that fails any check (the
//!   upper triangle `estimate.A[j,l]`, `j <= l`, a first index not starting
//!   at 1, a name clash) stays scalars with their FMI 2.0 names, which are
//!   legal structured names in FMI 3.0 too;
//! - **value references**: FMI 3.0 wants them unique over all variables,
//!   FMI 2.0 tables number each base type from 0. A Float64 keeps its FMI 2.0
//!   reference, an Int32 / enumeration adds [`INTEGER_VR_OFFSET`], a Boolean
//!   [`BOOLEAN_VR_OFFSET`] (see [`fmi3_value_reference`]); an array has the
//!   reference of its first element, the references of its other elements
//!   are not used;
//! - **the independent variable** `time` (FMI 3.0 requires exactly one), at
//!   [`TIME_VALUE_REFERENCE`], readable with `fmi3GetFloat64`;
//! - **descriptions**: an array's description is its elements' with the
//!   digits that follow the element's indices replaced by the index letter
//!   (`j` for the first index, `k` for the second, `l`, then `i3`, `i4`, ...):
//!   "Measured angle of joint 1" / "... joint 2" becomes "Measured angle of
//!   joint j".
//!
//! Everything is computed once at instantiation; the lookups
//! ([`Layout::find`]) do not allocate.

use fmu_core::variables::MAX_VALUE_REFERENCE;
use fmu_core::{BaseType, Causality, Initial, ModelDescription, VarType, Variability, Variable};
use std::collections::HashMap;
use std::ops::Range;

/// Added to an Integer or enumeration's FMI 2.0 value reference.
pub const INTEGER_VR_OFFSET: u32 = MAX_VALUE_REFERENCE;
/// Added to a Boolean's FMI 2.0 value reference.
pub const BOOLEAN_VR_OFFSET: u32 = 2 * MAX_VALUE_REFERENCE;
/// The value reference of the independent variable `time`.
pub const TIME_VALUE_REFERENCE: u32 = 3 * MAX_VALUE_REFERENCE;

/// The FMI 3.0 value reference of the FMI 2.0 variable `(base, vr)` (for an
/// array element: the array's is that of its first element).
pub fn fmi3_value_reference(base: BaseType, fmi2_vr: u32) -> u32 {
    match base {
        BaseType::Real => fmi2_vr,
        BaseType::Integer => INTEGER_VR_OFFSET + fmi2_vr,
        BaseType::Boolean => BOOLEAN_VR_OFFSET + fmi2_vr,
    }
}

/// The FMI 3.0 type of a variable, and the `fmi3Get*` / `fmi3Set*` family
/// that accesses it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fmi3Type {
    /// FMI 2.0 Real: `fmi3GetFloat64`.
    Float64,
    /// FMI 2.0 Integer: `fmi3GetInt32`.
    Int32,
    /// FMI 2.0 enumeration: `<Enumeration>`, accessed with `fmi3GetInt64`
    /// (FMI 3.0 section 2.4.7.4.3).
    Enumeration,
    /// FMI 2.0 Boolean: `fmi3GetBoolean`.
    Boolean,
}

impl Fmi3Type {
    fn of(t: &VarType) -> Self {
        match t {
            VarType::Real => Fmi3Type::Float64,
            VarType::Integer => Fmi3Type::Int32,
            VarType::Enumeration(_) => Fmi3Type::Enumeration,
            VarType::Boolean => Fmi3Type::Boolean,
        }
    }

    /// The element name of the modelDescription (and of messages).
    pub fn xml_name(self) -> &'static str {
        match self {
            Fmi3Type::Float64 => "Float64",
            Fmi3Type::Int32 => "Int32",
            Fmi3Type::Enumeration => "Enumeration",
            Fmi3Type::Boolean => "Boolean",
        }
    }

    /// The C type the variable travels as (`fmi3GetInt64` for enumerations).
    pub fn access_name(self) -> &'static str {
        match self {
            Fmi3Type::Enumeration => "Int64",
            t => t.xml_name(),
        }
    }
}

/// One FMI 3.0 variable: a scalar, an array, or the independent `time`.
#[derive(Clone, Debug, PartialEq)]
pub struct Fmi3Variable {
    /// The FMI 3.0 name (`q`, `chart.coef`, `energy`, `estimate.A[1,2]`).
    pub name: String,
    /// Unique over all variables of the FMU.
    pub value_reference: u32,
    /// The FMI 3.0 type.
    pub fmi3_type: Fmi3Type,
    /// Array sizes, outermost first (empty: a scalar).
    pub dimensions: Vec<usize>,
    /// Its FMI 2.0 variables (positions in `ModelDescription::variables`),
    /// in row-major order; empty for `time`.
    pub elements: Range<usize>,
    /// The description (an array's with index letters, see the module).
    pub description: String,
}

impl Fmi3Variable {
    /// Whether this is the independent variable `time`.
    pub fn is_time(&self) -> bool {
        self.elements.is_empty()
    }

    /// Number of values (`1` for a scalar and `time`).
    pub fn len(&self) -> usize {
        if self.is_time() {
            1
        } else {
            self.elements.len()
        }
    }

    /// Never true (every variable has at least one value); for clippy.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The FMI 2.0 variable whose attributes the whole variable shares
    /// (`None` for `time`).
    pub fn first<'a>(&self, d: &'a ModelDescription) -> Option<&'a Variable> {
        (!self.is_time()).then(|| &d.variables[self.elements.start])
    }
}

/// The FMI 3.0 variables of a description and the value-reference lookup.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// In modelDescription order: `time` first, then the table's order.
    pub variables: Vec<Fmi3Variable>,
    /// `(value reference, index into variables)`, sorted by reference.
    lookup: Vec<(u32, u32)>,
    /// For each FMI 2.0 variable, the FMI 3.0 variable holding it.
    owner: Vec<u32>,
}

/// `base[i,k,..]` split into its base and indices (`None` for a name that
/// is not one array element).
fn parse_element(name: &str) -> Option<(&str, Vec<u64>)> {
    let inner = name.strip_suffix(']')?;
    let open = inner.rfind('[')?;
    let (base, list) = (&inner[..open], &inner[open + 1..]);
    if base.is_empty() || base.contains(['[', ']']) || list.is_empty() {
        return None;
    }
    let indices = list
        .split(',')
        .map(|s| {
            if !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()) {
                s.parse().ok()
            } else {
                None
            }
        })
        .collect::<Option<Vec<u64>>>()?;
    Some((base, indices))
}

/// The array sizes of a run whose indices enumerate a full rectangle in
/// row-major order, the first index from 1, the others from their first
/// value; `None` otherwise.
fn rectangle(indices: &[Vec<u64>]) -> Option<Vec<usize>> {
    let first = indices.first()?;
    if first[0] != 1 {
        return None;
    }
    let mut sizes = Vec::with_capacity(first.len());
    for (d, &start) in first.iter().enumerate() {
        let max = indices.iter().map(|ix| ix[d]).max()?;
        if indices.iter().any(|ix| ix[d] < start) {
            return None;
        }
        sizes.push(usize::try_from(max - start + 1).ok()?);
    }
    let count = sizes
        .iter()
        .try_fold(1usize, |acc, &s| acc.checked_mul(s))?;
    if count != indices.len() {
        return None;
    }
    // Row-major: the last index runs fastest.
    for (p, ix) in indices.iter().enumerate() {
        let mut rest = p;
        for d in (0..sizes.len()).rev() {
            let expected = first[d] + (rest % sizes[d]) as u64;
            rest /= sizes[d];
            if ix[d] != expected {
                return None;
            }
        }
    }
    Some(sizes)
}

/// A description cut into runs of digits and runs of anything else.
fn tokens(s: &str) -> Vec<(bool, &str)> {
    let mut out = Vec::new();
    let mut start = 0;
    let mut digits = None;
    for (i, ch) in s.char_indices() {
        let d = ch.is_ascii_digit();
        if digits != Some(d) {
            if let Some(prev) = digits {
                out.push((prev, &s[start..i]));
            }
            start = i;
            digits = Some(d);
        }
    }
    if let Some(prev) = digits {
        out.push((prev, &s[start..]));
    }
    out
}

fn index_letter(d: usize) -> String {
    match d {
        0 => "j".into(),
        1 => "k".into(),
        2 => "l".into(),
        _ => format!("i{d}"),
    }
}

/// The common description of a run's elements: text equal in all, digit
/// runs either equal in all or equal to the element's index `d` in all
/// (replaced by the index letter). `None` if the descriptions differ
/// otherwise.
fn description_template(descriptions: &[&str], indices: &[Vec<u64>]) -> Option<String> {
    let toks: Vec<Vec<(bool, &str)>> = descriptions.iter().map(|s| tokens(s)).collect();
    let first = &toks[0];
    if toks
        .iter()
        .any(|t| t.len() != first.len() || t.iter().zip(first).any(|(a, b)| a.0 != b.0))
    {
        return None;
    }
    let mut out = String::new();
    for (p, &(is_digit, text)) in first.iter().enumerate() {
        let same = toks.iter().all(|t| t[p].1 == text);
        if same {
            out.push_str(text);
            continue;
        }
        if !is_digit {
            return None;
        }
        let dims = indices[0].len();
        let d = (0..dims).find(|&d| {
            toks.iter()
                .zip(indices)
                .all(|(t, ix)| t[p].1.parse::<u64>().ok() == Some(ix[d]))
        })?;
        out.push_str(&index_letter(d));
    }
    Some(out)
}

/// Whether `b` may join the array that `a` starts: same base, index count
/// and every attribute an FMI 3.0 array has once.
fn same_array(a: &Variable, pa: &(&str, Vec<u64>), b: &Variable, pb: &(&str, Vec<u64>)) -> bool {
    pa.0 == pb.0
        && pa.1.len() == pb.1.len()
        && a.var_type == b.var_type
        && a.causality == b.causality
        && a.variability == b.variability
        && a.initial == b.initial
        && a.unit == b.unit
        && a.min == b.min
        && a.max == b.max
        && a.start.is_some() == b.start.is_some()
}

impl Layout {
    /// The FMI 3.0 variables of `d` (see the module documentation). `d` is
    /// a validated description (unique names, value references below
    /// [`MAX_VALUE_REFERENCE`] within each base type).
    pub fn new(d: &ModelDescription) -> Self {
        let vars = &d.variables;
        let parsed: Vec<Option<(&str, Vec<u64>)>> =
            vars.iter().map(|v| parse_element(&v.name)).collect();
        // Candidate arrays: (range, sizes, description).
        let mut arrays: Vec<(Range<usize>, Vec<usize>, String)> = Vec::new();
        let mut i = 0;
        while i < vars.len() {
            let Some(pi) = &parsed[i] else {
                i += 1;
                continue;
            };
            let mut j = i + 1;
            while j < vars.len()
                && parsed[j]
                    .as_ref()
                    .is_some_and(|pj| same_array(&vars[i], pi, &vars[j], pj))
            {
                j += 1;
            }
            let indices: Vec<Vec<u64>> = parsed[i..j]
                .iter()
                .map(|p| p.as_ref().expect("parsed").1.clone())
                .collect();
            let descriptions: Vec<&str> =
                vars[i..j].iter().map(|v| v.description.as_str()).collect();
            if let (Some(sizes), Some(description)) = (
                rectangle(&indices),
                description_template(&descriptions, &indices),
            ) {
                arrays.push((i..j, sizes, description));
            }
            i = j;
        }
        // An array whose base name is also a scalar's name, or whose base
        // has elements outside the array, stays scalars: names stay unique
        // and `m[2]` never reads as an element of some other array `m`.
        let scalar_names: std::collections::HashSet<&str> = vars
            .iter()
            .filter(|v| !v.name.contains('['))
            .map(|v| v.name.as_str())
            .collect();
        let mut base_count: HashMap<&str, usize> = HashMap::new();
        for (base, _) in parsed.iter().flatten() {
            *base_count.entry(base).or_default() += 1;
        }
        arrays.retain(|(r, ..)| {
            let base = parsed[r.start].as_ref().expect("parsed").0;
            base_count[base] == r.len() && !scalar_names.contains(base)
        });

        let mut time_name = String::from("time");
        while vars.iter().any(|v| v.name == time_name)
            || arrays
                .iter()
                .any(|(r, ..)| parsed[r.start].as_ref().expect("parsed").0 == time_name)
        {
            time_name.push('_');
        }
        let mut variables = vec![Fmi3Variable {
            name: time_name,
            value_reference: TIME_VALUE_REFERENCE,
            fmi3_type: Fmi3Type::Float64,
            dimensions: Vec::new(),
            elements: 0..0,
            description: "Simulation time (the independent variable)".into(),
        }];
        let mut next_array = arrays.into_iter().peekable();
        let mut i = 0;
        while i < vars.len() {
            let v = &vars[i];
            let vr = fmi3_value_reference(v.var_type.base(), v.value_reference);
            match next_array.next_if(|(r, ..)| r.start == i) {
                Some((range, sizes, description)) => {
                    let base = parsed[i].as_ref().expect("parsed").0;
                    i = range.end;
                    variables.push(Fmi3Variable {
                        name: base.to_string(),
                        value_reference: vr,
                        fmi3_type: Fmi3Type::of(&v.var_type),
                        dimensions: sizes,
                        elements: range,
                        description,
                    });
                }
                None => {
                    variables.push(Fmi3Variable {
                        name: v.name.clone(),
                        value_reference: vr,
                        fmi3_type: Fmi3Type::of(&v.var_type),
                        dimensions: Vec::new(),
                        elements: i..i + 1,
                        description: v.description.clone(),
                    });
                    i += 1;
                }
            }
        }
        let mut lookup: Vec<(u32, u32)> = variables
            .iter()
            .enumerate()
            .map(|(k, v)| (v.value_reference, k as u32))
            .collect();
        lookup.sort_unstable();
        let mut owner = vec![0u32; vars.len()];
        for (k, v) in variables.iter().enumerate() {
            for e in v.elements.clone() {
                owner[e] = k as u32;
            }
        }
        Self {
            variables,
            lookup,
            owner,
        }
    }

    /// The index into [`Layout::variables`] of value reference `vr`.
    pub fn find(&self, vr: u32) -> Option<usize> {
        self.lookup
            .binary_search_by_key(&vr, |&(r, _)| r)
            .ok()
            .map(|p| self.lookup[p].1 as usize)
    }

    /// The FMI 3.0 variable holding FMI 2.0 variable number `element`.
    pub fn owner(&self, element: usize) -> &Fmi3Variable {
        &self.variables[self.owner[element] as usize]
    }

    /// The FMI 3.0 variable named `name` (an array by its base name).
    pub fn variable(&self, name: &str) -> Option<&Fmi3Variable> {
        self.variables.iter().find(|v| v.name == name)
    }
}

/// Whether the value of `v` may be set in state `state` (FMI 3.0 section
/// 2.2.x, as fmi2-slave: inputs, and exact/approx values before
/// initialization, exact ones in initialization mode, tunable parameters
/// in step mode).
pub(crate) fn settable(v: &Variable, state: fmu_core::State) -> bool {
    use fmu_core::State;
    v.variability != Variability::Constant
        && match state {
            State::Instantiated => {
                v.causality == Causality::Input
                    || matches!(
                        v.effective_initial(),
                        Some(Initial::Exact | Initial::Approx)
                    )
            }
            State::InitializationMode => {
                v.causality == Causality::Input || v.effective_initial() == Some(Initial::Exact)
            }
            State::StepComplete => {
                v.causality == Causality::Input
                    || (v.causality == Causality::Parameter
                        && v.variability == Variability::Tunable)
            }
            _ => false,
        }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fmu_core::{EnumerationType, Value};

    fn description(variables: Vec<Variable>) -> ModelDescription {
        ModelDescription {
            model_name: "T".into(),
            model_identifier: "T".into(),
            description: String::new(),
            version: "1".into(),
            author: String::new(),
            generation_tool: String::new(),
            can_handle_variable_communication_step_size: true,
            can_save_state: false,
            default_experiment: None,
            units: vec![],
            enumerations: vec![EnumerationType {
                name: "E".into(),
                items: vec![("a".into(), 1, String::new())],
            }],
            variables,
        }
    }

    #[test]
    fn element_names() {
        assert_eq!(parse_element("q[1]"), Some(("q", vec![1])));
        assert_eq!(
            parse_element("chart.coef[2,0]"),
            Some(("chart.coef", vec![2, 0]))
        );
        for bad in ["q", "q[]", "[1]", "q[a]", "q[1,]", "a[1].b[2]", "q[-1]"] {
            assert_eq!(parse_element(bad), None, "{bad}");
        }
    }

    #[test]
    fn rectangles_in_row_major_order() {
        let v = |x: &[[u64; 2]]| x.iter().map(|r| r.to_vec()).collect::<Vec<_>>();
        assert_eq!(
            rectangle(&v(&[[1, 0], [1, 1], [1, 2], [2, 0], [2, 1], [2, 2]])),
            Some(vec![2, 3])
        );
        // The upper triangle of a 2 x 2 matrix.
        assert_eq!(rectangle(&v(&[[1, 1], [1, 2], [2, 2]])), None);
        // Column-major order is not row-major.
        assert_eq!(rectangle(&v(&[[1, 0], [2, 0], [1, 1], [2, 1]])), None);
        // The first index starts at 1.
        assert_eq!(rectangle(&v(&[[0, 0], [0, 1]])), None);
        assert_eq!(rectangle(&[vec![1], vec![2], vec![3]]), Some(vec![3]));
        assert_eq!(rectangle(&[vec![1], vec![3]]), None);
    }

    #[test]
    fn descriptions_become_templates() {
        let ix = [vec![1], vec![2]];
        assert_eq!(
            description_template(
                &[
                    "Angle of joint 1 (q[1] from the vertical)",
                    "Angle of joint 2 (q[1] from the vertical)"
                ],
                &ix
            )
            .as_deref(),
            Some("Angle of joint j (q[1] from the vertical)")
        );
        assert_eq!(
            description_template(&["mass 1", "length 2"], &ix),
            None,
            "different text"
        );
        assert_eq!(
            description_template(&["mass 3", "mass 7"], &ix),
            None,
            "digits that are not the index"
        );
        let ix2 = [vec![1, 0], vec![1, 1], vec![2, 0], vec![2, 1]];
        assert_eq!(
            description_template(&["X_1 s^0", "X_1 s^1", "X_2 s^0", "X_2 s^1"], &ix2).as_deref(),
            Some("X_j s^k")
        );
    }

    #[test]
    fn arrays_scalars_and_value_references() {
        let mut vars = vec![Variable::real("e", 0).output()];
        for (j, vr) in [(1, 1), (2, 2), (3, 3)] {
            vars.push(
                Variable::real(format!("q[{j}]"), vr)
                    .input(Value::Real(0.0))
                    .describe(format!("angle {j}")),
            );
        }
        for (n, (j, k)) in [(1, 0), (1, 1), (2, 0), (2, 1)].into_iter().enumerate() {
            vars.push(
                Variable::real(format!("c[{j},{k}]"), 100 + n as u32).parameter(Value::Real(1.0)),
            );
        }
        for (n, (j, l)) in [(1, 1), (1, 2), (2, 2)].into_iter().enumerate() {
            vars.push(Variable::real(format!("A[{j},{l}]"), 200 + n as u32).output());
        }
        vars.push(Variable::integer("n", 0).parameter(Value::Integer(1)));
        vars.push(Variable::enumeration("mode", 1, "E").parameter(Value::Integer(1)));
        vars.push(Variable::boolean("b[1]", 0).input(Value::Boolean(false)));
        // Different min: no array, and `m[1]` alone would leave `m[2]`
        // outside its array, so both stay scalars.
        vars.push(
            Variable::real("m[1]", 300)
                .parameter(Value::Real(1.0))
                .min(0.0),
        );
        vars.push(Variable::real("m[2]", 301).parameter(Value::Real(1.0)));
        let d = description(vars);
        d.validate().unwrap();
        let layout = Layout::new(&d);
        let names: Vec<(&str, u32, &[usize])> = layout
            .variables
            .iter()
            .map(|v| (v.name.as_str(), v.value_reference, v.dimensions.as_slice()))
            .collect();
        assert_eq!(
            names,
            vec![
                ("time", TIME_VALUE_REFERENCE, &[][..]),
                ("e", 0, &[][..]),
                ("q", 1, &[3][..]),
                ("c", 100, &[2, 2][..]),
                ("A[1,1]", 200, &[][..]),
                ("A[1,2]", 201, &[][..]),
                ("A[2,2]", 202, &[][..]),
                ("n", INTEGER_VR_OFFSET, &[][..]),
                ("mode", INTEGER_VR_OFFSET + 1, &[][..]),
                ("b", BOOLEAN_VR_OFFSET, &[1][..]),
                ("m[1]", 300, &[][..]),
                ("m[2]", 301, &[][..]),
            ]
        );
        assert_eq!(layout.variable("q").unwrap().description, "angle j");
        assert_eq!(layout.find(1), Some(2));
        assert_eq!(layout.find(2), None, "inner elements have no reference");
        assert_eq!(layout.owner(3).name, "q");
    }
}
