//! The closed loops as SSP 1.0 archives (`target/fmu/<name>.ssp`): the
//! controller FMU and the plant FMU with their connections (plant state to
//! controller inputs, controller torques to plant inputs) and the start
//! state, so that an SSP importer (fmpy's `simulate_ssp`, ecos, OMSimulator)
//! runs the paper's 14 J scenario from one file.

use anyhow::Result;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use zip::write::SimpleFileOptions;

/// One closed loop shipped as an SSP.
pub struct SspSpec<'a> {
    /// Archive name (`<name>.ssp`).
    pub name: &'a str,
    /// The controller FMU's `modelIdentifier`.
    pub controller: &'a str,
    /// The plant FMU's `modelIdentifier`.
    pub plant: &'a str,
    /// Joints of the chain.
    pub joints: usize,
}

pub use eigenmpc::mpc::closed_loop::START_ANGLE;

/// Name of the parameter set with the start state (ecos: `init(parameter_set=...)`).
pub const PARAMETER_SET: &str = "initialValues";
/// Stop time of the default experiment (s).
pub const STOP_TIME: f64 = 30.0;

fn connector(out: &mut String, name: &str, kind: &str) {
    writeln!(
        out,
        r#"          <ssd:Connector name="{name}" kind="{kind}"><ssc:Real/></ssd:Connector>"#
    )
    .unwrap();
}

fn parameter_bindings(out: &mut String, values: &[(String, f64)]) {
    out.push_str("        <ssd:ParameterBindings>\n          <ssd:ParameterBinding>\n");
    out.push_str("            <ssd:ParameterValues>\n");
    writeln!(
        out,
        r#"              <ssv:ParameterSet version="1.0" name="{PARAMETER_SET}">"#
    )
    .unwrap();
    out.push_str("                <ssv:Parameters>\n");
    for (name, value) in values {
        writeln!(
            out,
            r#"                  <ssv:Parameter name="{name}"><ssv:Real value="{value}"/></ssv:Parameter>"#
        )
        .unwrap();
    }
    out.push_str("                </ssv:Parameters>\n              </ssv:ParameterSet>\n");
    out.push_str("            </ssd:ParameterValues>\n          </ssd:ParameterBinding>\n");
    out.push_str("        </ssd:ParameterBindings>\n");
}

/// One `<ssd:Component>`: its FMU, connectors (inputs, outputs, then the
/// energy output both FMUs have) and start-value bindings.
fn component(
    s: &mut String,
    name: &str,
    fmu: &str,
    inputs: &[String],
    outputs: &[String],
    bindings: &[(String, f64)],
) {
    writeln!(
        s,
        r#"      <ssd:Component name="{name}" type="application/x-fmu-sharedlibrary" source="resources/{fmu}.fmu">"#
    )
    .unwrap();
    s.push_str("        <ssd:Connectors>\n");
    for n in inputs {
        connector(s, n, "input");
    }
    for n in outputs {
        connector(s, n, "output");
    }
    connector(s, "energy", "output");
    s.push_str("        </ssd:Connectors>\n");
    parameter_bindings(s, bindings);
    s.push_str("      </ssd:Component>\n");
}

/// `SystemStructure.ssd` of `spec`.
pub fn system_structure(spec: &SspSpec<'_>) -> String {
    let joints: Vec<usize> = (1..=spec.joints).collect();
    let state: Vec<String> = joints
        .iter()
        .map(|j| format!("q[{j}]"))
        .chain(joints.iter().map(|j| format!("qd[{j}]")))
        .collect();
    let torques: Vec<String> = joints.iter().map(|j| format!("tau[{j}]")).collect();
    let mut s = String::new();
    s.push_str(r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    s.push('\n');
    writeln!(
        s,
        r#"<ssd:SystemStructureDescription xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" version="1.0" name="{}" generationTool="fmu-build (EigenMPC) {}">"#,
        spec.name,
        env!("CARGO_PKG_VERSION")
    )
    .unwrap();
    writeln!(
        s,
        r#"  <ssd:System name="loop" description="{} drives {}: the {}-link chain's state to the controller, its torques to the chain, from q = {START_ANGLE} rad at rest; communication step 25 ms (the controller's sample period)">"#,
        spec.controller, spec.plant, spec.joints
    )
    .unwrap();
    s.push_str("    <ssd:Elements>\n");
    let start = |name: &str| -> Vec<(String, f64)> {
        joints
            .iter()
            .map(|j| (format!("{name}[{j}]"), START_ANGLE))
            .collect()
    };
    // The controller: the chain's state in, torques and energy out; its
    // start inputs equal the plant's start state (the first solve uses them).
    component(
        &mut s,
        "controller",
        spec.controller,
        &state,
        &torques,
        &start("q"),
    );
    component(&mut s, "plant", spec.plant, &torques, &state, &start("q0"));
    s.push_str("    </ssd:Elements>\n    <ssd:Connections>\n");
    let connection = |s: &mut String, from: &str, to: &str, name: &str| {
        writeln!(
            s,
            r#"      <ssd:Connection startElement="{from}" startConnector="{name}" endElement="{to}" endConnector="{name}"/>"#
        )
        .unwrap();
    };
    for n in &state {
        connection(&mut s, "plant", "controller", n);
    }
    for n in &torques {
        connection(&mut s, "controller", "plant", n);
    }
    s.push_str("    </ssd:Connections>\n  </ssd:System>\n");
    writeln!(
        s,
        r#"  <ssd:DefaultExperiment startTime="0" stopTime="{STOP_TIME}"/>"#
    )
    .unwrap();
    s.push_str("</ssd:SystemStructureDescription>\n");
    s
}

/// Writes `<fmu_dir>/<name>.ssp` from the FMUs already packaged there.
pub fn package(fmu_dir: &Path, spec: &SspSpec<'_>) -> Result<PathBuf> {
    let path = fmu_dir.join(format!("{}.ssp", spec.name));
    let mut zip = zip::ZipWriter::new(std::fs::File::create(&path)?);
    let opts = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    zip.start_file("SystemStructure.ssd", opts)?;
    zip.write_all(system_structure(spec).as_bytes())?;
    for fmu in [spec.controller, spec.plant] {
        // Already compressed: stored as it is.
        let stored =
            SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
        zip.start_file(format!("resources/{fmu}.fmu"), stored)?;
        zip.write_all(&std::fs::read(fmu_dir.join(format!("{fmu}.fmu")))?)?;
    }
    zip.finish()?;
    Ok(path)
}

#[cfg(test)]
mod structure_check {
    #[test]
    fn every_state_and_torque_is_connected_once_and_both_fmus_start_at_rest_pose() {
        for pair in crate::shipped::SHIPPED {
            let spec = &pair.ssp_spec();
            let ssd = super::system_structure(spec);
            let count = |needle: &str| ssd.matches(needle).count();
            assert_eq!(count("<ssd:Component "), 2, "{}", spec.name);
            // State (2 per joint) plant -> controller, torques controller -> plant.
            assert_eq!(count("<ssd:Connection "), 3 * spec.joints, "{}", spec.name);
            for j in 1..=spec.joints {
                for (name, from, to) in [
                    (format!("q[{j}]"), "plant", "controller"),
                    (format!("qd[{j}]"), "plant", "controller"),
                    (format!("tau[{j}]"), "controller", "plant"),
                ] {
                    assert_eq!(
                        count(&format!(
                            r#"startElement="{from}" startConnector="{name}" endElement="{to}""#
                        )),
                        1,
                        "{}: {name}",
                        spec.name
                    );
                }
                assert_eq!(count(&format!(r#"name="q0[{j}]""#)), 1);
            }
            // Both components declare their energy output.
            assert_eq!(count(r#"<ssd:Connector name="energy" kind="output">"#), 2);
        }
    }
}
