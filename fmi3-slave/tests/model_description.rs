//! The FMI 3.0 modelDescription.xml of the chain of masses: its arrays,
//! types and structure, and fmpy's validation of it.

mod common;

use common::*;
use fmi3_slave::layout::{BOOLEAN_VR_OFFSET, INTEGER_VR_OFFSET, TIME_VALUE_REFERENCE};
use fmi3_slave::{Model, xml};
use std::path::{Path, PathBuf};
use std::process::Command;

/// A fresh temporary folder for this test.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fmi3-slave-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The workspace's Python with fmpy, if there is one.
pub fn fmpy_python() -> Option<PathBuf> {
    let python = Path::new(env!("CARGO_MANIFEST_DIR")).join("../.venv/bin/python");
    let ok = Command::new(&python)
        .args(["-c", "import fmpy"])
        .output()
        .is_ok_and(|o| o.status.success());
    ok.then_some(python)
}

#[test]
fn arrays_types_and_structure() {
    let xml = xml::model_description_xml(&Chain::description());
    let token = fmi3_slave::instance::instantiation_token(&Chain::description());
    for needle in [
        r#"fmiVersion="3.0""#.to_string(),
        format!(r#"instantiationToken="{token}""#),
        r#"<CoSimulation modelIdentifier="Chain" canHandleVariableCommunicationStepSize="true" canGetAndSetFMUState="true" canSerializeFMUState="true""#.into(),
        r#"providesIntermediateUpdate="false""#.into(),
        r#"hasEventMode="false""#.into(),
        format!(r#"<Float64 name="time" valueReference="{TIME_VALUE_REFERENCE}""#),
        r#"causality="independent" variability="continuous"/>"#.into(),
        r#"<Float64 name="f" valueReference="0" description="External force on mass j" causality="input" variability="continuous" unit="N" min="-1000000.0" max="1000000.0" start="0.0 0.0 0.0"><Dimension start="3"/></Float64>"#.into(),
        r#"<Float64 name="x" valueReference="3" description="Position of mass j" causality="output" variability="continuous" initial="calculated" unit="m"><Dimension start="3"/></Float64>"#.into(),
        r#"<Float64 name="init" valueReference="20" description="Initial state of mass j, component k (0: position, 1: velocity)" causality="parameter" variability="fixed" initial="exact" min="-100.0" max="100.0" start="0.1 0.0 0.2 0.0 0.30000000000000004 0.0"><Dimension start="3"/><Dimension start="2"/></Float64>"#.into(),
        r#"<Float64 name="k" valueReference="9" description="Spring stiffness; tunable between steps" causality="parameter" variability="tunable" initial="exact" unit="N/m" min="0.0" max="10000.0" start="100.0"/>"#.into(),
        format!(r#"<Int32 name="steps" valueReference="{}""#, INTEGER_VR_OFFSET + STEPS),
        format!(r#"<Enumeration name="integrator" valueReference="{}" description="Time integration" declaredType="Integrator" causality="parameter" variability="fixed" initial="exact" min="1" max="2" start="1"/>"#, INTEGER_VR_OFFSET + INTEGRATOR),
        format!(r#"<Boolean name="hold" valueReference="{}" description="Holds the chain still" causality="input" variability="discrete" start="false"/>"#, BOOLEAN_VR_OFFSET + HOLD),
        r#"<EnumerationType name="Integrator">"#.into(),
        r#"<Item name="symplectic" value="1" description="Symplectic Euler"/>"#.into(),
        r#"<Unit name="N"><BaseUnit kg="1" m="1" s="-2"/></Unit>"#.into(),
        r#"<Category name="logStatusError" description="Errors: why a call returned fmi3Error"/>"#.into(),
        r#"<DefaultExperiment startTime="0.0" stopTime="2.0" stepSize="0.001"/>"#.into(),
        r#"<Output valueReference="3" dependencies=""/>"#.into(),
        format!(r#"<Output valueReference="{}" dependencies=""/>"#, INTEGER_VR_OFFSET + STEPS),
        // x depends on all knowns at initialization (attribute omitted).
        r#"<InitialUnknown valueReference="3"/>"#.into(),
        format!(r#"<InitialUnknown valueReference="{}" dependencies=""/>"#, INTEGER_VR_OFFSET + STEPS),
    ] {
        assert!(xml.contains(&needle), "missing {needle}\n{xml}");
    }
    // One variable per array: no element names left.
    assert!(!xml.contains("f[1]") && !xml.contains("init[1,0]"), "{xml}");
    assert_eq!(xml.matches("<Output ").count(), 4, "x, v, energy, steps");
}

#[test]
fn fmpy_validates_the_model_description() {
    let Some(python) = fmpy_python() else {
        eprintln!(
            "SKIP fmpy_validates_the_model_description: no Python with fmpy at \
             ../.venv/bin/python (create the workspace's .venv with fmpy to run it)"
        );
        return;
    };
    let dir = temp_dir("xml");
    std::fs::write(
        dir.join("modelDescription.xml"),
        xml::model_description_xml(&Chain::description()),
    )
    .unwrap();
    let script = r#"
import sys
from fmpy import read_model_description
from fmpy.validation import validate_fmu
problems = validate_fmu(sys.argv[1])
for p in problems:
    print("PROBLEM", p)
md = read_model_description(sys.argv[1], validate=True)
for v in md.modelVariables:
    print("VAR", v.name, v.type, v.valueReference, v.causality, [d.start for d in v.dimensions], v.start)
print("OUTPUTS", sorted(u.variable.name for u in md.outputs))
print("INITIAL", sorted(u.variable.name for u in md.initialUnknowns))
"#;
    let out = Command::new(&python)
        .arg("-c")
        .arg(script)
        .arg(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "fmpy failed:\n{stdout}\n{stderr}");
    assert!(
        !stdout.contains("PROBLEM"),
        "fmpy found problems:\n{stdout}"
    );
    for line in [
        "VAR time Float64 3145728 independent [] None",
        "VAR f Float64 0 input [3] 0.0 0.0 0.0",
        "VAR init Float64 20 parameter [3, 2] 0.1 0.0 0.2 0.0 0.30000000000000004 0.0",
        "VAR integrator Enumeration 1048578 parameter [] 1",
        "VAR hold Boolean 2097152 input [] false",
        "OUTPUTS ['energy', 'steps', 'v', 'x']",
        "INITIAL ['energy', 'steps', 'v', 'x']",
    ] {
        assert!(stdout.contains(line), "missing {line:?} in\n{stdout}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
