//! The chain of masses built as a shared library with both export macros
//! (examples/chain_fmu.rs, built by `cargo test`): its exported symbols,
//! and a run of it as an FMI 3.0 FMU under fmpy.

mod common;

use common::*;
use fmi3_slave::{Model, xml};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The example's library next to the test executable's folder
/// (`target/<profile>/examples`), if cargo built it.
fn library() -> Option<PathBuf> {
    let exe = std::env::current_exe().ok()?;
    let lib = exe.parent()?.parent()?.join("examples/libchain_fmu.so");
    lib.exists().then_some(lib)
}

fn skip(test: &str, why: &str) {
    eprintln!("SKIP {test}: {why}");
}

#[test]
fn exports_exactly_the_fmi2_and_fmi3_functions() {
    let Some(lib) = library() else {
        return skip(
            "exports_exactly_the_fmi2_and_fmi3_functions",
            "examples/libchain_fmu.so not built (run `cargo test -p fmi3-slave`, which builds examples)",
        );
    };
    let Ok(out) = Command::new("nm")
        .args(["-D", "--defined-only"])
        .arg(&lib)
        .output()
    else {
        return skip(
            "exports_exactly_the_fmi2_and_fmi3_functions",
            "nm (binutils) not found",
        );
    };
    let text = String::from_utf8_lossy(&out.stdout);
    let exported: Vec<&str> = text
        .lines()
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            (f.len() == 3 && f[1] == "T").then(|| f[2])
        })
        .collect();
    for name in fmi3_slave::FMI3_FUNCTIONS {
        assert!(exported.contains(&name), "{name} not exported");
    }
    let fmi3 = exported.iter().filter(|s| s.starts_with("fmi3")).count();
    let fmi2 = exported.iter().filter(|s| s.starts_with("fmi2")).count();
    assert_eq!((fmi3, fmi2), (75, 34), "{exported:?}");
    let other: Vec<&&str> = exported
        .iter()
        .filter(|s| !s.starts_with("fmi2") && !s.starts_with("fmi3"))
        .collect();
    assert!(other.is_empty(), "other exported functions: {other:?}");
}

#[test]
fn fmpy_simulates_the_fmi3_fmu() {
    let Some(lib) = library() else {
        return skip(
            "fmpy_simulates_the_fmi3_fmu",
            "examples/libchain_fmu.so not built",
        );
    };
    let python = Path::new(env!("CARGO_MANIFEST_DIR")).join("../.venv/bin/python");
    if !Command::new(&python)
        .args(["-c", "import fmpy"])
        .output()
        .is_ok_and(|o| o.status.success())
    {
        return skip(
            "fmpy_simulates_the_fmi3_fmu",
            "no Python with fmpy at ../.venv/bin/python",
        );
    }
    // An unpacked FMU: modelDescription.xml and binaries/x86_64-linux/Chain.so.
    let dir = std::env::temp_dir().join(format!("fmi3-slave-fmu-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let bin = dir.join("binaries/x86_64-linux");
    std::fs::create_dir_all(&bin).unwrap();
    std::fs::create_dir_all(dir.join("resources")).unwrap();
    std::fs::copy(&lib, bin.join("Chain.so")).unwrap();
    std::fs::write(
        dir.join("modelDescription.xml"),
        xml::model_description_xml(&Chain::description()),
    )
    .unwrap();
    // fmpy drives it: start values for the force array and the 2-D
    // parameter array (row-major), 200 steps of 5 ms, then the outputs.
    let script = r#"
import sys
import numpy as np
from fmpy import simulate_fmu
r = simulate_fmu(sys.argv[1], fmi_type='CoSimulation', stop_time=1.0, output_interval=0.005,
                 start_values={'f': np.array([0.0, 0.0, 2.0]),
                               'init': np.array([0.1, 0.0, 0.2, 0.5, 0.3, 0.0]),
                               'integrator': 2},
                 output=['x', 'energy', 'steps'])
last = r[-1]
print("TIME", repr(float(last['time'])))
print("X", " ".join(repr(float(v)) for v in np.ravel(last['x'])))
print("STEPS", int(last['steps']))
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
    let field = |key: &str| -> Vec<f64> {
        let line = stdout
            .lines()
            .find_map(|l| l.strip_prefix(&format!("{key} ")))
            .unwrap_or_else(|| panic!("no {key} in\n{stdout}\n{stderr}"));
        line.split_whitespace()
            .map(|v| v.parse().unwrap())
            .collect()
    };
    assert_eq!(field("TIME"), vec![1.0]);
    assert_eq!(field("STEPS"), vec![200.0]);
    // The same run written out here (explicit Euler, k = 100, m = 1).
    let mut x = [0.1, 0.2, 0.3];
    let mut v = [0.0, 0.5, 0.0];
    for _ in 0..200 {
        step(
            &mut x,
            &mut v,
            &[0.0, 0.0, 2.0],
            100.0,
            1.0,
            0.005,
            EXPLICIT,
        );
    }
    let got = field("X");
    assert_eq!(got.len(), N);
    for j in 0..N {
        // fmpy sums the communication points (0.005 n): the same steps.
        assert!(
            (got[j] - x[j]).abs() < 1e-9 * (1.0 + x[j].abs()),
            "x[{j}]: fmpy {} vs {}",
            got[j],
            x[j]
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
