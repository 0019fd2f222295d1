//! `modelDescription.xml` and the FMU's `documentation/index.html`,
//! generated from the [`ModelDescription`] the binary dispatches on.

use crate::logger::LOG_CATEGORIES;
use crate::variables::{
    Causality, Initial, ModelDescription, Value, VarType, Variability, Variable,
};
use std::fmt::Write;

const GUID_PLACEHOLDER: &str = "@GUID@";

/// Escapes text for an XML/HTML attribute or element.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            _ => out.push(ch),
        }
    }
    out
}

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

fn type_element(v: &Variable) -> String {
    let (tag, declared) = match &v.var_type {
        VarType::Real => ("Real", None),
        VarType::Integer => ("Integer", None),
        VarType::Boolean => ("Boolean", None),
        VarType::Enumeration(t) => ("Enumeration", Some(t)),
    };
    let mut s = format!("<{tag}");
    if let Some(t) = declared {
        write!(s, " declaredType=\"{}\"", escape(t)).unwrap();
    }
    if let Some(u) = &v.unit {
        write!(s, " unit=\"{}\"", escape(u)).unwrap();
    }
    let bound = |x: f64| match v.var_type {
        VarType::Real => real(x),
        _ => format!("{}", x as i64),
    };
    if let Some(min) = v.min {
        write!(s, " min=\"{}\"", bound(min)).unwrap();
    }
    if let Some(max) = v.max {
        write!(s, " max=\"{}\"", bound(max)).unwrap();
    }
    if let Some(start) = v.start {
        write!(s, " start=\"{}\"", value_text(start)).unwrap();
    }
    s.push_str("/>");
    s
}

fn index_list(d: &ModelDescription, names: &[String]) -> String {
    let mut idx: Vec<usize> = names
        .iter()
        .filter_map(|n| d.variables.iter().position(|v| &v.name == n))
        .map(|i| i + 1)
        .collect();
    idx.sort_unstable();
    idx.iter()
        .map(|i| i.to_string())
        .collect::<Vec<_>>()
        .join(" ")
}

fn render(d: &ModelDescription, guid: &str) -> String {
    let mut x = String::new();
    let w = &mut x;
    writeln!(w, r#"<?xml version="1.0" encoding="UTF-8"?>"#).unwrap();
    writeln!(
        w,
        r#"<fmiModelDescription fmiVersion="2.0" modelName="{}" guid="{}" description="{}" author="{}" version="{}" generationTool="{}" variableNamingConvention="structured" numberOfEventIndicators="0">"#,
        escape(&d.model_name),
        guid,
        escape(&d.description),
        escape(&d.author),
        escape(&d.version),
        escape(&d.generation_tool)
    )
    .unwrap();
    writeln!(
        w,
        r#"  <CoSimulation modelIdentifier="{}" canHandleVariableCommunicationStepSize="{}" canInterpolateInputs="false" maxOutputDerivativeOrder="0" canRunAsynchronuously="false" canBeInstantiatedOnlyOncePerProcess="false" canNotUseMemoryManagementFunctions="true" canGetAndSetFMUstate="{}" canSerializeFMUstate="{}" providesDirectionalDerivative="false"/>"#,
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
            writeln!(w, r#"    <SimpleType name="{}">"#, escape(&e.name)).unwrap();
            writeln!(w, "      <Enumeration>").unwrap();
            for (name, value, desc) in &e.items {
                writeln!(
                    w,
                    r#"        <Item name="{}" value="{value}" description="{}"/>"#,
                    escape(name),
                    escape(desc)
                )
                .unwrap();
            }
            writeln!(w, "      </Enumeration>").unwrap();
            writeln!(w, "    </SimpleType>").unwrap();
        }
        writeln!(w, "  </TypeDefinitions>").unwrap();
    }
    writeln!(w, "  <LogCategories>").unwrap();
    for (name, desc) in LOG_CATEGORIES {
        writeln!(
            w,
            r#"    <Category name="{name}" description="{}"/>"#,
            escape(desc)
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
    for (i, v) in d.variables.iter().enumerate() {
        writeln!(w, "    <!-- index {} -->", i + 1).unwrap();
        let mut attrs = format!(
            r#"name="{}" valueReference="{}""#,
            escape(&v.name),
            v.value_reference
        );
        if !v.description.is_empty() {
            write!(attrs, r#" description="{}""#, escape(&v.description)).unwrap();
        }
        write!(
            attrs,
            r#" causality="{}" variability="{}""#,
            causality(v.causality),
            variability(v.variability)
        )
        .unwrap();
        if let Some(init) = v.initial {
            write!(attrs, r#" initial="{}""#, initial(init)).unwrap();
        }
        writeln!(w, "    <ScalarVariable {attrs}>").unwrap();
        writeln!(w, "      {}", type_element(v)).unwrap();
        writeln!(w, "    </ScalarVariable>").unwrap();
    }
    writeln!(w, "  </ModelVariables>").unwrap();
    writeln!(w, "  <ModelStructure>").unwrap();
    let unknown = |v: &Variable, deps: &Option<Vec<String>>| {
        let i = d.variables.iter().position(|x| x.name == v.name).unwrap() + 1;
        match deps {
            Some(names) => format!(
                r#"<Unknown index="{i}" dependencies="{}"/>"#,
                index_list(d, names)
            ),
            None => format!(r#"<Unknown index="{i}"/>"#),
        }
    };
    let outputs: Vec<&Variable> = d
        .variables
        .iter()
        .filter(|v| v.causality == Causality::Output)
        .collect();
    if !outputs.is_empty() {
        writeln!(w, "    <Outputs>").unwrap();
        for v in &outputs {
            writeln!(w, "      {}", unknown(v, &v.dependencies)).unwrap();
        }
        writeln!(w, "    </Outputs>").unwrap();
    }
    let initial_unknowns: Vec<&Variable> = d
        .variables
        .iter()
        .filter(|v| v.is_initial_unknown())
        .collect();
    if !initial_unknowns.is_empty() {
        writeln!(w, "    <InitialUnknowns>").unwrap();
        for v in &initial_unknowns {
            writeln!(w, "      {}", unknown(v, &v.initial_dependencies)).unwrap();
        }
        writeln!(w, "    </InitialUnknowns>").unwrap();
    }
    writeln!(w, "  </ModelStructure>").unwrap();
    writeln!(w, "</fmiModelDescription>").unwrap();
    x
}

/// A 128-bit FNV-1a hash, for a GUID that changes whenever the interface does.
fn fnv1a_128(bytes: &[u8]) -> u128 {
    const OFFSET: u128 = 0x6c62272e07bb014262b821756295c58d;
    const PRIME: u128 = 0x0000000001000000000000000000013B;
    bytes
        .iter()
        .fold(OFFSET, |h, &b| (h ^ b as u128).wrapping_mul(PRIME))
}

/// The model's GUID: a hash of its model description, so the XML and the
/// binary agree exactly when they were built from the same table.
pub fn guid(d: &ModelDescription) -> String {
    let h = fnv1a_128(render(d, GUID_PLACEHOLDER).as_bytes());
    let hex = format!("{h:032x}");
    format!(
        "{{{}-{}-{}-{}-{}}}",
        &hex[0..8],
        &hex[8..12],
        &hex[12..16],
        &hex[16..20],
        &hex[20..32]
    )
}

/// The complete `modelDescription.xml`.
pub fn model_description_xml(d: &ModelDescription) -> String {
    render(d, &guid(d))
}

/// `documentation/index.html`: the variable table in human form.
pub fn documentation_html(d: &ModelDescription, intro_html: &str) -> String {
    let mut h = String::new();
    let w = &mut h;
    writeln!(
        w,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head><meta charset=\"utf-8\"><title>{}</title>",
        escape(&d.model_name)
    )
    .unwrap();
    writeln!(w, "<style>body{{font-family:sans-serif;max-width:60em;margin:auto}}table{{border-collapse:collapse}}td,th{{border:1px solid #bbb;padding:2px 6px;text-align:left}}</style></head><body>").unwrap();
    writeln!(
        w,
        "<h1>{}</h1>\n<p>{}</p>\n{intro_html}",
        escape(&d.model_name),
        escape(&d.description)
    )
    .unwrap();
    writeln!(w, "<p>FMI 2.0 Co-Simulation, model identifier <code>{}</code>, version {}, GUID <code>{}</code>.</p>", escape(&d.model_identifier), escape(&d.version), guid(d)).unwrap();
    writeln!(w, "<h2>Variables</h2>\n<table><tr><th>name</th><th>vr</th><th>causality</th><th>variability</th><th>start</th><th>unit</th><th>min</th><th>max</th><th>description</th></tr>").unwrap();
    for v in &d.variables {
        let opt = |x: Option<f64>| x.map(real).unwrap_or_default();
        writeln!(
            w,
            "<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(&v.name),
            v.value_reference,
            causality(v.causality),
            variability(v.variability),
            v.start.map(value_text).unwrap_or_default(),
            escape(v.unit.as_deref().unwrap_or("")),
            opt(v.min),
            opt(v.max),
            escape(&v.description)
        )
        .unwrap();
    }
    writeln!(w, "</table>\n<h2>Log categories</h2>\n<ul>").unwrap();
    for (name, desc) in LOG_CATEGORIES {
        writeln!(w, "<li><code>{name}</code>: {}</li>", escape(desc)).unwrap();
    }
    writeln!(w, "</ul>\n</body>\n</html>").unwrap();
    h
}
