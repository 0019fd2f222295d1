//! What the variable table generates besides the run time: the
//! `modelDescription.xml` variables and enumeration types, the C header's
//! constants and the documentation rows (Markdown). The run-time half
//! (layout, lookups, reading values into settings) is `table/mod.rs`.

use super::{Deps, Element, Kind, Role, Row, Shape, Table, fill};
use crate::variables::{BaseType, EnumerationType, Value, Variability, Variable, compact};
use std::collections::HashSet;
use std::fmt::Write;

impl<S> Table<S> {
    /// The variables (one per element), start values from `defaults`.
    pub fn variables(&self, defaults: &S) -> Vec<Variable> {
        let mut out = vec![];
        for (i, row) in self.rows.iter().enumerate() {
            for e in row.shape.elements(self.n) {
                out.push(self.variable(i, row, e, defaults));
            }
        }
        out
    }

    fn variable(&self, i: usize, row: &Row<S>, e: Element, defaults: &S) -> Variable {
        let name = row.element_name(e);
        let vr = self.vr_at(i, e);
        let mut v = match &row.kind {
            Kind::Real => Variable::real(name, vr),
            Kind::Integer => Variable::integer(name, vr),
            Kind::Enumeration(t) => Variable::enumeration(name, vr, t.name.clone()),
            Kind::Boolean => Variable::boolean(name, vr),
        };
        let start = row.start(defaults, e);
        v = match &row.role {
            Role::Input { .. } => v.input(start.expect("inputs have a start")),
            Role::Output { variability } => {
                let mut v = v.output().variability(*variability).depends_on(&[]);
                v.initial_dependencies = match &row.initial_dependencies {
                    Deps::All => None,
                    Deps::Rows(names) => Some(
                        names
                            .iter()
                            .flat_map(|n| {
                                let r = self.row(n).unwrap_or_else(|| {
                                    panic!("{}: unknown dependency row {n}", row.name)
                                });
                                r.shape
                                    .elements(self.n)
                                    .into_iter()
                                    .map(|e| r.element_name(e))
                                    .collect::<Vec<_>>()
                            })
                            .collect(),
                    ),
                    Deps::SameJoint(n) => {
                        let r = self
                            .row(n)
                            .unwrap_or_else(|| panic!("{}: unknown dependency row {n}", row.name));
                        Some(vec![r.element_name(e)])
                    }
                };
                v
            }
            Role::Parameter { tunable: false, .. } => v.parameter(start.expect("parameter")),
            Role::Parameter { tunable: true, .. } => v.tunable(start.expect("parameter")),
        };
        if let Some(u) = row.unit {
            v = v.unit(u);
        }
        if let Some(m) = row.min {
            v = v.min(m);
        }
        if let Some(m) = row.max {
            v = v.max(m);
        }
        v.describe(fill(&row.description, e))
    }

    /// The enumeration types the rows use (each once, in row order).
    pub fn enumerations(&self) -> Vec<EnumerationType> {
        let mut out: Vec<EnumerationType> = vec![];
        for row in &self.rows {
            if let Kind::Enumeration(t) = &row.kind
                && !out.iter().any(|o| o.name == t.name)
            {
                out.push(t.clone());
            }
        }
        out
    }

    /// The C header's constants: `#define <prefix>VR_<NAME><j> <vr>` per
    /// element (`VR_Q1`, `VR_E_REF`, `VR_Q0_1`), for a joint-power row its
    /// first reference and an indexing macro `<prefix>VR_<NAME>_JK(j, k)`,
    /// and `#define <prefix><ROW>_<ITEM> <value>` per enumeration item.
    pub fn c_defines(&self, prefix: &str, model: &str) -> Result<String, String> {
        let mut s = String::new();
        let mut seen = HashSet::new();
        let mut define = |s: &mut String, name: String, value: String, doc: String| {
            if !seen.insert(name.clone()) {
                return Err(format!("{model}: duplicate C constant {name}"));
            }
            writeln!(s, "/* {doc} */\n#define {name} {value}").unwrap();
            Ok(())
        };
        writeln!(
            s,
            "/* {model}: value references (generated from its variable table). */"
        )
        .unwrap();
        for (i, row) in self.rows.iter().enumerate() {
            let base = c_identifier(row.name);
            let family = match row.kind.base() {
                BaseType::Real => "Real",
                BaseType::Integer => "Integer",
                BaseType::Boolean => "Boolean",
            };
            match row.shape {
                Shape::JointPowers(powers) => {
                    let first = self.vr_at(i, Element::default());
                    define(
                        &mut s,
                        format!("{prefix}VR_{base}"),
                        first.to_string(),
                        format!(
                            "{family} value reference of {}",
                            row.element_name(Element::default())
                        ),
                    )?;
                    define(
                        &mut s,
                        format!("{prefix}VR_{base}_JK(j, k)"),
                        format!("({first} + {powers} * ((j) - 1) + (k))"),
                        format!(
                            "{family} value reference of {}[j,k], j = 1..{}, k = 0..{}",
                            row.name,
                            self.n,
                            powers - 1
                        ),
                    )?;
                }
                _ => {
                    for e in row.shape.elements(self.n) {
                        let suffix = match row.shape {
                            Shape::Scalar => String::new(),
                            Shape::JointPairs => format!("_{}_{}", e.j + 1, e.k + 1),
                            _ if base.ends_with(|c: char| c.is_ascii_digit()) => {
                                format!("_{}", e.j + 1)
                            }
                            _ => (e.j + 1).to_string(),
                        };
                        define(
                            &mut s,
                            format!("{prefix}VR_{base}{suffix}"),
                            self.vr_at(i, e).to_string(),
                            format!("{family} value reference of {}", row.element_name(e)),
                        )?;
                    }
                }
            }
            if let Kind::Enumeration(t) = &row.kind {
                for (item, value, desc) in &t.items {
                    define(
                        &mut s,
                        format!("{prefix}{base}_{}", c_identifier(item)),
                        value.to_string(),
                        format!("{}: {desc}", row.name),
                    )?;
                }
            }
        }
        Ok(s)
    }

    /// The rows in documentation form (Markdown tables).
    pub fn docs(&self, defaults: &S) -> Vec<RowDoc> {
        self.rows
            .iter()
            .enumerate()
            .map(|(i, row)| {
                let elements = row.shape.elements(self.n);
                let prefix = match row.kind.base() {
                    BaseType::Real => "",
                    BaseType::Integer => "int ",
                    BaseType::Boolean => "bool ",
                };
                let vrs = match row.shape {
                    Shape::JointPowers(powers) => {
                        format!("{prefix}{} + {powers} (j-1) + k", self.first[i])
                    }
                    _ => {
                        let list: Vec<String> = elements
                            .iter()
                            .map(|&e| self.vr_at(i, e).to_string())
                            .collect();
                        format!("{prefix}{}", list.join(", "))
                    }
                };
                let causality = match (&row.role, &row.kind) {
                    (Role::Input { .. }, _) => "input".to_string(),
                    (
                        Role::Output {
                            variability: Variability::Discrete,
                        },
                        Kind::Real,
                    ) => "output (discrete)".to_string(),
                    (Role::Output { .. }, _) => "output".to_string(),
                    (Role::Parameter { tunable, .. }, kind) => format!(
                        "parameter ({}){}",
                        if *tunable { "**tunable**" } else { "fixed" },
                        if matches!(kind, Kind::Enumeration(_)) {
                            ", enumeration"
                        } else {
                            ""
                        }
                    ),
                };
                let start = row.start_text.clone().unwrap_or_else(|| {
                    let values: Vec<String> = elements
                        .iter()
                        .filter_map(|&e| row.start(defaults, e))
                        .map(|v| match (&row.kind, v) {
                            (Kind::Enumeration(t), Value::Integer(i)) => t
                                .items
                                .iter()
                                .find(|it| it.1 == i)
                                .map(|it| format!("{} ({i})", it.0))
                                .unwrap_or_else(|| i.to_string()),
                            (_, v) => value_text(v),
                        })
                        .collect();
                    if values.iter().all(|v| Some(v) == values.first()) {
                        values.first().cloned().unwrap_or_default()
                    } else {
                        values.join(", ")
                    }
                });
                let range =
                    row.range_text
                        .clone()
                        .unwrap_or_else(|| match (&row.kind, row.min, row.max) {
                            (Kind::Enumeration(t), _, _) => t
                                .items
                                .iter()
                                .map(|(name, v, _)| format!("{name} ({v})"))
                                .collect::<Vec<_>>()
                                .join(", "),
                            (_, Some(a), Some(b)) => format!("[{}, {}]", compact(a), compact(b)),
                            (_, Some(a), None) => format!(">= {}", compact(a)),
                            (_, None, Some(b)) => format!("<= {}", compact(b)),
                            (Kind::Real, None, None)
                                if !matches!(row.role, Role::Output { .. }) =>
                            {
                                "finite".into()
                            }
                            _ => String::new(),
                        });
                let meaning = row
                    .summary
                    .clone()
                    .unwrap_or_else(|| row.description.replace("{j}", "j").replace("{k}", "k"));
                RowDoc {
                    name: row.pattern(),
                    vrs,
                    causality,
                    unit: row.unit.unwrap_or("").to_string(),
                    start,
                    range,
                    meaning,
                }
            })
            .collect()
    }
}

/// One row of a Markdown variable table.
#[derive(Clone, Debug, PartialEq)]
pub struct RowDoc {
    /// Name pattern (`q[j]`).
    pub name: String,
    /// Value references.
    pub vrs: String,
    /// Causality and variability.
    pub causality: String,
    /// Unit.
    pub unit: String,
    /// Start value(s).
    pub start: String,
    /// Allowed range.
    pub range: String,
    /// Meaning.
    pub meaning: String,
}

/// A Markdown table of several FMUs with the same rows (one value-reference
/// column per FMU; the other columns from the first).
pub fn markdown(fmus: &[(&str, Vec<RowDoc>)]) -> Result<String, String> {
    let Some((_, first)) = fmus.first() else {
        return Ok(String::new());
    };
    for (name, docs) in fmus {
        let names: Vec<&String> = docs.iter().map(|d| &d.name).collect();
        let expected: Vec<&String> = first.iter().map(|d| &d.name).collect();
        if names != expected {
            return Err(format!("{name}: rows differ from {}", fmus[0].0));
        }
        for (d, f) in docs.iter().zip(first) {
            let same = (&d.causality, &d.unit, &d.start, &d.range, &d.meaning)
                == (&f.causality, &f.unit, &f.start, &f.range, &f.meaning);
            if !same {
                return Err(format!(
                    "{}: row {} differs from {}'s in more than its value references \
                     ({d:?} vs {f:?}); give it a start text or summary that fits both",
                    name, d.name, fmus[0].0
                ));
            }
        }
    }
    let mut s = String::from("| name |");
    for (name, _) in fmus {
        write!(s, " vr `{name}` |").unwrap();
    }
    s.push_str(" causality | unit | start | range | meaning |\n|");
    for _ in 0..fmus.len() + 6 {
        s.push_str(" --- |");
    }
    s.push('\n');
    let cell = |t: &str| t.replace('|', "\\|");
    for (i, d) in first.iter().enumerate() {
        write!(s, "| `{}` |", d.name).unwrap();
        for (_, docs) in fmus {
            write!(s, " {} |", docs[i].vrs).unwrap();
        }
        writeln!(
            s,
            " {} | {} | {} | {} | {} |",
            d.causality,
            cell(&d.unit),
            cell(&d.start),
            cell(&d.range),
            cell(&d.meaning)
        )
        .unwrap();
    }
    Ok(s)
}

/// `E_ref` -> `E_REF`, `chart.coef` -> `CHART_COEF`.
fn c_identifier(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_uppercase()
            } else {
                '_'
            }
        })
        .collect()
}

fn value_text(v: Value) -> String {
    match v {
        Value::Real(x) => compact(x),
        Value::Integer(i) => i.to_string(),
        Value::Boolean(b) => b.to_string(),
    }
}
