//! `eigenmpc modes` end to end: JSON shape and values, and one-line errors.

use serde_json::Value;
use std::process::Command;

fn run(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_eigenmpc"))
        .args(args)
        .output()
        .expect("run eigenmpc");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn modes_prints_the_documented_json() {
    let (code, stdout, stderr) = run(&["modes", "--family", "in-phase", "--energies", "2,8,14"]);
    assert_eq!(code, 0, "{stderr}");
    let doc: Value = serde_json::from_str(&stdout).expect("valid JSON");
    assert_eq!(doc["model"]["kind"], "double-pendulum");
    for key in ["m1", "m2", "l1", "l2"] {
        assert_eq!(doc["model"][key], 1.0);
    }
    assert_eq!(doc["model"]["g"], 9.81);
    assert_eq!(doc["family"], "in-phase");
    let omega = doc["linear"]["omega"].as_f64().unwrap();
    assert!((omega - (9.81f64 * (2.0 - 2f64.sqrt())).sqrt()).abs() < 1e-12);
    let c = &doc["linear"]["eigenvector"];
    assert!((c[0].as_f64().unwrap() - 0.9239).abs() < 1e-4);
    assert!((c[1].as_f64().unwrap() - 0.3827).abs() < 1e-4);
    let modes = doc["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 3);
    let m = &modes[2];
    assert_eq!(m["energy"], 14.0);
    assert!((m["half_period"].as_f64().unwrap() - 1.3877).abs() < 1e-4);
    assert!(m["closing_error"].as_f64().unwrap() < 1e-9);
    let tp: Vec<f64> = serde_json::from_value(m["turning_point"].clone()).unwrap();
    let other: Vec<f64> = serde_json::from_value(m["other_turning_point"].clone()).unwrap();
    assert!(
        0.9239 * tp[0] + 0.3827 * tp[1] > 0.0,
        "turning_point has c'q > 0"
    );
    assert!((tp[0] + other[0]).abs() < 1e-8 && (tp[1] + other[1]).abs() < 1e-8);
    let path = m["path"].as_array().unwrap();
    assert_eq!(path.len(), 200);
    assert_eq!(path[0][0].as_f64().unwrap(), tp[0]);
    let chart = &m["chart"];
    assert_eq!(chart["degree"], 9);
    let coef: Vec<Vec<f64>> = serde_json::from_value(chart["coefficients"].clone()).unwrap();
    assert_eq!(coef.len(), 2);
    assert!(coef.iter().all(|c| c.len() == 10));
    let residual = chart["max_residual"].as_f64().unwrap();
    assert!(residual > 0.0 && residual < 2e-3, "{residual}");
    // The polynomial really passes near the turning point.
    let s = 0.923879532511287 * tp[0] + 0.38268343236508934 * tp[1];
    let x: Vec<f64> = coef
        .iter()
        .map(|c| c.iter().rev().fold(0.0, |acc, a| acc * s + a))
        .collect();
    assert!((x[0] - tp[0]).abs() < 3e-3 && (x[1] - tp[1]).abs() < 3e-3);
}

#[test]
fn modes_options_change_the_output() {
    let (code, stdout, stderr) = run(&[
        "modes",
        "--family",
        "anti-phase",
        "--energies",
        "2",
        "--degree",
        "5",
        "--samples",
        "50",
        "--m2",
        "0.5",
        "--l1",
        "1.2",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let doc: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(doc["family"], "anti-phase");
    assert_eq!(doc["model"]["m2"], 0.5);
    assert_eq!(doc["modes"][0]["path"].as_array().unwrap().len(), 50);
    assert_eq!(
        doc["modes"][0]["chart"]["coefficients"][0]
            .as_array()
            .unwrap()
            .len(),
        6
    );
    let c1 = doc["linear"]["eigenvector"][1].as_f64().unwrap();
    assert!(c1 < 0.0, "anti-phase eigenvector has opposite signs");
}

#[test]
fn bad_input_gives_one_line_errors_and_nonzero_exit() {
    for (args, needle) in [
        (
            vec!["modes", "--family", "sideways", "--energies", "2"],
            "unknown family",
        ),
        (
            vec!["modes", "--energies", "2,-1"],
            "energy -1 J is invalid",
        ),
        (vec!["modes", "--energies", "0"], "energy 0 J is invalid"),
        (vec!["modes", "--energies", "2", "--m1", "-1"], "m1"),
        (vec!["modes", "--energies", "abc"], "not a number"),
        (
            vec!["modes", "--energies", "70"],
            "cannot be continued beyond",
        ),
        // The controller FMU's ranges (m in [1e-6, 1e6] kg, l in
        // [1e-3, 1e3] m), naming the flag.
        (
            vec!["modes", "--energies", "14", "--m2", "1e-9"],
            "--m2: m[2] = 1e-9 is below its minimum 1e-6",
        ),
        (
            vec!["modes", "--energies", "14", "--l2", "1e9"],
            "--l2: l[2] = 1e9 is above its maximum 1e3",
        ),
        // A nearly massless second link (the smallest mass allowed): the
        // family by its name, and the energy asked for (not the
        // continuation's internal start).
        (
            vec!["modes", "--energies", "14", "--m2", "1e-6"],
            "the in-phase family cannot be continued beyond E = 0.0000 J (requested 14 J): no orbit \
             at the continuation's start energy 0.05 J",
        ),
        (
            vec!["modes", "--energies", "2", "--samples", "5"],
            "too few",
        ),
    ] {
        let (code, stdout, stderr) = run(&args);
        assert_eq!(code, 1, "{args:?} should fail with exit code 1");
        assert!(stdout.is_empty(), "{args:?} printed {stdout}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
}

#[test]
fn fmu_start_values_carry_the_chart_of_the_requested_mode() {
    let dir = std::env::temp_dir().join(format!("eigenmpc-sv-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("start.json");
    let file_arg = file.to_str().unwrap();
    let (code, stdout, stderr) =
        run(&["modes", "--energies", "14", "--fmu-start-values", file_arg]);
    assert_eq!(code, 0, "{stderr}");
    let doc: Value = serde_json::from_str(&stdout).unwrap();
    let values: Value = serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    assert_eq!(values["E_ref"], 14.0);
    assert_eq!(values["m[1]"], 1.0);
    assert_eq!(values["g"], 9.81);
    assert_eq!(values["c[1]"], doc["linear"]["eigenvector"][0]);
    assert_eq!(values["c[2]"], doc["linear"]["eigenvector"][1]);
    for j in 0..2 {
        for k in 0..10 {
            assert_eq!(
                values[format!("chart.coef[{},{k}]", j + 1)],
                doc["modes"][0]["chart"]["coefficients"][j][k]
            );
        }
    }
    // E_ref, the 22 model parameters of the FMU's table (point masses:
    // r[j] = I[j] = -1, "at the tip"), c[j], the 20 chart coefficients and
    // chart_source = 2 (parameters: the FMU uses this chart).
    assert_eq!(values.as_object().unwrap().len(), 1 + 22 + 2 + 20 + 1);
    assert_eq!(values["chart_source"], 2);
    assert_eq!(values["r[1]"], -1.0);
    assert_eq!(values["I[2]"], -1.0);
    assert_eq!(values["gr[1]"], 1.0);
    // Lower degree pads with zeros; several energies are refused.
    let (code, _, _) = run(&[
        "modes",
        "--energies",
        "14",
        "--degree",
        "5",
        "--fmu-start-values",
        file_arg,
    ]);
    assert_eq!(code, 0);
    let values: Value = serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    assert_eq!(values["chart.coef[2,9]"], 0.0);
    let (code, _, stderr) = run(&[
        "modes",
        "--energies",
        "2,14",
        "--fmu-start-values",
        file_arg,
    ]);
    assert_ne!(code, 0);
    assert!(stderr.contains("exactly one energy"), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

fn robot_file(name: &str) -> String {
    format!("{}/../robots/{name}", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn a_robot_parameter_file_gives_its_modes_and_fmu_start_values() {
    let a0 = robot_file("lab-double-pendulum-A0.yml");
    let out = std::env::temp_dir().join(format!("eigenmpc-a0-start-{}.json", std::process::id()));
    let (code, stdout, stderr) = run(&[
        "modes",
        "--model",
        &a0,
        "--energies",
        "2",
        "--fmu-start-values",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let doc: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(doc["model"]["kind"], "planar-chain");
    assert_eq!(doc["model"]["cf1"], 0.093);
    let m = &doc["modes"][0];
    assert!(m["closing_error"].as_f64().unwrap() < 1e-9);
    // A smaller, stiffer pendulum than the paper's: shorter half period.
    assert!(m["half_period"].as_f64().unwrap() < 1.0);
    let start: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(start["E_ref"], 2.0);
    assert_eq!(start["gr[2]"], 6.0);
    assert_eq!(start["I[1]"], 0.053470810264216295);
    assert_eq!(start["r[2]"], 0.18377686083653508);
    assert_eq!(start["coulomb_sharpness"], 100.0);
    std::fs::remove_file(out).ok();
}

#[test]
fn a_bad_parameter_file_gives_a_one_line_error_naming_key_and_file() {
    let dir = std::env::temp_dir().join(format!("eigenmpc-bad-model-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, text, needle) in [
        (
            "missing.yml",
            "m1: 1\nm2: 1\nl1: 1\nl2: 1\n",
            "missing key 'g'",
        ),
        (
            "unknown.yml",
            "m1: 1\nm2: 1\nl1: 1\nl2: 1\ng: 9.81\nmu: 3\n",
            "unknown key 'mu'",
        ),
        (
            "negative.json",
            r#"{"m1":1,"m2":1,"l1":1,"l2":1,"g":9.81,"b2":-1}"#,
            "key 'b2'",
        ),
        (
            "seven.json",
            r#"{"m1":1,"m2":1,"m3":1,"m4":1,"m5":1,"m6":1,"m7":1,"l1":1,"l2":1,"l3":1,"l4":1,"l5":1,"l6":1,"l7":1,"g":9.81}"#,
            "at most 6 links",
        ),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let (code, _, stderr) = run(&[
            "modes",
            "--model",
            path.to_str().unwrap(),
            "--energies",
            "1",
        ]);
        assert_eq!(code, 1, "{name}");
        assert!(
            stderr.contains(needle) && stderr.contains(name),
            "{name}: {stderr}"
        );
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    }
    let (code, _, stderr) = run(&[
        "modes",
        "--model",
        &robot_file("lab-double-pendulum-A0.yml"),
        "--m1",
        "2",
    ]);
    // Flag errors too: one line, exit code 1.
    assert_eq!(code, 1, "clap refuses --m1 with --model: {stderr}");
    assert!(
        stderr.contains("'--model <FILE>' cannot be used with '--m1 <M1>'"),
        "{stderr}"
    );
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
}
