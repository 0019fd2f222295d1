//! `modelDescription.xml` for FMI 3.0 Co-Simulation, generated from the
//! [`ModelDescription`] and its [`Layout`] (the arrays, value references and
//! `time` the binary dispatches on).

use crate::instance::instantiation_token;
use crate::layout::{Fmi3Type, Fmi3Variable, Layout};
use fmi2_slave::xml::escape;
use fmu_core::LOG_CATEGORIES;
use fmu_core::variables::{Causality, Initial, ModelDescription, Value, VarType, Variability};
use std::fmt::Write;

/// A real in XML form: shortest round-trip representation.
fn real(x: f64) -> String {
    format!("{x:?}")
}

fn causality(c: Causality) -> &'static str {
    match c {
        Causality::Parameter => "parameter",
        Causality::CalculatedParameter => "calculatedParameter",
        Causality::Input => "input",
        Causality::Output => "output",
        Causality::Local => "local",
    }
}

fn variability(v: Variability) -> &'static str {
    match v {
        Variability::Constant => "constant",
        Variability::Fixed => "fixed",
        Variability::Tunable => "tunable",
        Variability::Discrete => "discrete",
        Variability::Continuous => "continuous",
    }
}

fn initial(i: Initial) -> &'static str {
    match i {
        Initial::Exact => "exact",
        Initial::Approx => "approx",
        Initial::Calculated => "calculated",
    }
}

fn value_text(v: Value) -> String {
    match v {
        Value::Real(x) => real(x),
        Value::Integer(i) => i.to_string(),
        Value::Boolean(b) => b.to_string(),
    }
}

/// The element of one FMI 3.0 variable (`<Float64 .../>` or, for an array,
/// with its `<Dimension>`s).
fn variable_element(d: &ModelDescription, v: &Fmi3Variable) -> String {
    let tag = v.fmi3_type.xml_name();
    let mut s = format!(
        r#"<{tag} name="{}" valueReference="{}""#,
        escape(&v.name),
        v.value_reference
    );
    if !v.description.is_empty() {
        write!(s, r#" description="{}""#, escape(&v.description)).unwrap();
    }
    let Some(first) = v.first(d) else {
        // The independent variable.
        s.push_str(r#" causality="independent" variability="continuous"/>"#);
        return s;
    };
    if let VarType::Enumeration(t) = &first.var_type {
        write!(s, r#" declaredType="{}""#, escape(t)).unwrap();
    }
    write!(
        s,
        r#" causality="{}" variability="{}""#,
        causality(first.causality),
        variability(first.variability)
    )
    .unwrap();
    if let Some(init) = first.initial {
        write!(s, r#" initial="{}""#, initial(init)).unwrap();
    }
    if let Some(u) = &first.unit {
        write!(s, r#" unit="{}""#, escape(u)).unwrap();
    }
    let bound = |x: f64| match v.fmi3_type {
        Fmi3Type::Float64 => real(x),
        _ => format!("{}", x as i64),
    };
    if let Some(min) = first.min {
        write!(s, r#" min="{}""#, bound(min)).unwrap();
    }
    if let Some(max) = first.max {
        write!(s, r#" max="{}""#, bound(max)).unwrap();
    }
    if first.start.is_some() {
        let starts: Vec<String> = v
            .elements
            .clone()
            .filter_map(|i| d.variables[i].start.map(value_text))
            .collect();
        write!(s, r#" start="{}""#, starts.join(" ")).unwrap();
    }
    if v.dimensions.is_empty() {
        s.push_str("/>");
    } else {
        s.push('>');
        for n in &v.dimensions {
            write!(s, r#"<Dimension start="{n}"/>"#).unwrap();
        }
        write!(s, "</{tag}>").unwrap();
    }
    s
}

/// The value references of the FMI 3.0 variables holding the FMI 2.0
/// variables `names`, ascending, each once.
fn dependency_list(d: &ModelDescription, layout: &Layout, names: &[String]) -> String {
    let mut vrs: Vec<u32> = names
        .iter()
        .filter_map(|n| d.variables.iter().position(|v| &v.name == n))
        .map(|i| layout.owner(i).value_reference)
        .collect();
    vrs.sort_unstable();
    vrs.dedup();
    vrs.iter()
        .map(|i| i.to_string())
        .collect::<Vec<_>>()
        .join(" ")
}

/// The union of the elements' dependency lists (`None`: all, when any
/// element depends on all).
fn union(lists: impl Iterator<Item = Option<Vec<String>>>) -> Option<Vec<String>> {
    let mut all = Vec::new();
    for list in lists {
        all.extend(list?);
    }
    Some(all)
}

/// The complete FMI 3.0 `modelDescription.xml` of `d` (instantiation token:
/// the FMI 2.0 GUID of the same description).
pub fn model_description_xml(d: &ModelDescription) -> String {
    let layout = Layout::new(d);
    let mut x = String::new();
    let w = &mut x;
    writeln!(w, r#"<?xml version="1.0" encoding="UTF-8"?>"#).unwrap();
    writeln!(
        w,
        r#"<fmiModelDescription fmiVersion="3.0" modelName="{}" instantiationToken="{}" description="{}" author="{}" version="{}" generationTool="{}" variableNamingConvention="structured">"#,
        escape(&d.model_name),
        instantiation_token(d),
        escape(&d.description),
        escape(&d.author),
        escape(&d.version),
        escape(&d.generation_tool)
    )
    .unwrap();
    writeln!(
        w,
        r#"  <CoSimulation modelIdentifier="{}" canHandleVariableCommunicationStepSize="{}" canGetAndSetFMUState="{}" canSerializeFMUState="{}" providesDirectionalDerivatives="false" providesAdjointDerivatives="false" providesPerElementDependencies="false" maxOutputDerivativeOrder="0" providesIntermediateUpdate="false" mightReturnEarlyFromDoStep="false" canReturnEarlyAfterIntermediateUpdate="false" hasEventMode="false" providesEvaluateDiscreteStates="false"/>"#,
        escape(&d.model_identifier),
        d.can_handle_variable_communication_step_size,
        d.can_save_state,
        d.can_save_state
    )
    .unwrap();
    if !d.units.is_empty() {
        writeln!(w, "  <UnitDefinitions>").unwrap();
        for u in &d.units {
            let mut base = String::new();
            for (name, e) in [("kg", u.kg), ("m", u.m), ("s", u.s), ("rad", u.rad)] {
                if e != 0 {
                    write!(base, r#" {name}="{e}""#).unwrap();
                }
            }
            writeln!(
                w,
                r#"    <Unit name="{}"><BaseUnit{base}/></Unit>"#,
                escape(&u.name)
            )
            .unwrap();
        }
        writeln!(w, "  </UnitDefinitions>").unwrap();
    }
    if !d.enumerations.is_empty() {
        writeln!(w, "  <TypeDefinitions>").unwrap();
        for e in &d.enumerations {
            writeln!(w, r#"    <EnumerationType name="{}">"#, escape(&e.name)).unwrap();
            for (name, value, desc) in &e.items {
                let desc = if desc.is_empty() {
                    String::new()
                } else {
                    format!(r#" description="{}""#, escape(desc))
                };
                writeln!(
                    w,
                    r#"      <Item name="{}" value="{value}"{desc}/>"#,
                    escape(name)
                )
                .unwrap();
            }
            writeln!(w, "    </EnumerationType>").unwrap();
        }
        writeln!(w, "  </TypeDefinitions>").unwrap();
    }
    writeln!(w, "  <LogCategories>").unwrap();
    for (name, desc) in LOG_CATEGORIES {
        // The descriptions name fmi2 statuses; FMI 3.0's are the same.
        let desc = desc.replace("fmi2", "fmi3");
        writeln!(
            w,
            r#"    <Category name="{name}" description="{}"/>"#,
            escape(&desc)
        )
        .unwrap();
    }
    writeln!(w, "  </LogCategories>").unwrap();
    if let Some(e) = d.default_experiment {
        let tolerance = e
            .tolerance
            .map(|t| format!(r#" tolerance="{}""#, real(t)))
            .unwrap_or_default();
        writeln!(
            w,
            r#"  <DefaultExperiment startTime="{}" stopTime="{}"{tolerance} stepSize="{}"/>"#,
            real(e.start_time),
            real(e.stop_time),
            real(e.step_size)
        )
        .unwrap();
    }
    writeln!(w, "  <ModelVariables>").unwrap();
    for v in &layout.variables {
        writeln!(w, "    {}", variable_element(d, v)).unwrap();
    }
    writeln!(w, "  </ModelVariables>").unwrap();
    writeln!(w, "  <ModelStructure>").unwrap();
    let unknown = |tag: &str, v: &Fmi3Variable, deps: Option<Vec<String>>| match deps {
        Some(names) => format!(
            r#"<{tag} valueReference="{}" dependencies="{}"/>"#,
            v.value_reference,
            dependency_list(d, &layout, &names)
        ),
        None => format!(r#"<{tag} valueReference="{}"/>"#, v.value_reference),
    };
    for v in &layout.variables {
        if let Some(first) = v.first(d)
            && first.causality == Causality::Output
        {
            let deps = union(
                v.elements
                    .clone()
                    .map(|i| d.variables[i].dependencies.clone()),
            );
            writeln!(w, "    {}", unknown("Output", v, deps)).unwrap();
        }
    }
    for v in &layout.variables {
        if let Some(first) = v.first(d)
            && first.is_initial_unknown()
        {
            let deps = union(
                v.elements
                    .clone()
                    .map(|i| d.variables[i].initial_dependencies.clone()),
            );
            writeln!(w, "    {}", unknown("InitialUnknown", v, deps)).unwrap();
        }
    }
    writeln!(w, "  </ModelStructure>").unwrap();
    writeln!(w, "</fmiModelDescription>").unwrap();
    x
}
