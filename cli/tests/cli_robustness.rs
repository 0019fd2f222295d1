//! `eigenmpc robustness` (v2): the report's files, its verdicts on a
//! category whose outcome is known, the same numbers on 1 and 2 threads,
//! clear errors.

mod common;
use common::{eigenmpc, eigenmpc_ok};

#[test]
fn robustness_report_is_written_and_deterministic() {
    let base = std::env::temp_dir().join(format!("eigenmpc-rob-{}", std::process::id()));
    let mut tables = vec![];
    for threads in ["1", "2"] {
        let dir = base.join(threads);
        let stdout = eigenmpc_ok(&[
            "robustness",
            "--categories",
            "measurement delay",
            "--steps",
            "3",
            "--duration",
            "40",
            "--threads",
            threads,
            // The controller not told the delay: what it costs unmodelled.
            "--undeclared",
            "--out",
            dir.to_str().unwrap(),
        ]);
        assert!(stdout.contains("measurement delay:"), "{stdout}");
        for file in ["robustness.md", "robustness.png", "robustness.svg"] {
            let len = std::fs::metadata(dir.join(file))
                .map(|m| m.len())
                .unwrap_or(0);
            assert!(len > 1000, "{file}: {len} bytes");
        }
        let md = std::fs::read_to_string(dir.join("robustness.md")).unwrap();
        assert!(md.contains("| measurement delay | 3 |"), "{md}");
        assert!(md.contains("robustness v2"), "{md}");
        tables.push(std::fs::read_to_string(dir.join("robustness.csv")).unwrap());
    }
    assert_eq!(tables[0], tables[1], "the thread count changed the numbers");
    // one row per case and adaptation setting: 0, 20 and 40 ms
    let header: Vec<&str> = tables[0].lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = tables[0]
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 6);
    let off = |value: &str| {
        rows.iter()
            .find(|r| r[col("value")] == value && r[col("adapt")] == "false")
            .unwrap_or_else(|| panic!("no row for {value}"))
            .clone()
    };
    let number = |r: &[&str], name: &str| -> f64 { r[col(name)].parse().unwrap() };
    // 40 ms of delay (1.6 samples) costs torque but not the energy: the
    // mean of the last 5 s within 1 % either way, the RMS torque of joint
    // 2 up by a quarter or more (0.013 -> 0.021 N m at 60 s)
    for value in ["0", "0.02", "0.04"] {
        let r = off(value);
        assert!(number(&r, "energy_error").abs() < 0.01, "{r:?}");
        assert_eq!(r[col("ekf")], "false", "clean sensors need no filter");
    }
    let (clean, late) = (off("0"), off("0.04"));
    assert_eq!(clean[col("success")], "true", "{clean:?}");
    assert!(
        number(&late, "rms_tau2_Nm") > 1.25 * number(&clean, "rms_tau2_Nm"),
        "{clean:?} {late:?}"
    );
    // a frictionless plant: the allowance is the 0.03 N m alone
    assert_eq!(number(&clean, "rms_friction1_Nm"), 0.0);
    // Told the delay (the default), the controller predicts it away: the
    // 40 ms run's torque is the undelayed one's within 2 %.
    let dir = base.join("declared");
    eigenmpc_ok(&[
        "robustness",
        "--categories",
        "measurement delay",
        "--steps",
        "3",
        "--duration",
        "40",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let declared = std::fs::read_to_string(dir.join("robustness.csv")).unwrap();
    let row = |value: &str| -> Vec<String> {
        declared
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(String::from).collect::<Vec<_>>())
            .find(|r| r[col("value")] == value && r[col("adapt")] == "false")
            .unwrap()
    };
    let tau2 = |r: &[String]| -> f64 { r[col("rms_tau2_Nm")].parse().unwrap() };
    let (clean, late) = (row("0"), row("0.04"));
    assert_eq!(late[col("success")], "true", "{late:?}");
    assert!(
        (tau2(&late) - tau2(&clean)).abs() < 0.02 * tau2(&clean),
        "{clean:?} {late:?}"
    );
    std::fs::remove_dir_all(&base).ok();
}

#[test]
fn robustness_refuses_bad_input_with_a_message() {
    for (args, needle) in [
        (
            vec!["robustness", "--categories", "mass,colour"],
            "unknown category 'colour'",
        ),
        (
            vec!["robustness", "--duration", "4"],
            "must be more than the 5 s",
        ),
        (vec!["robustness", "--energy", "-1"], "e_ref"),
        (vec!["robustness", "--steps", "1"], "at least 2"),
    ] {
        let out = eigenmpc(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
}

#[test]
fn a_four_joint_robot_gets_its_report() {
    let robot = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../robots/examples/four-link-rigid.yml"
    );
    let dir = std::env::temp_dir().join(format!("eigenmpc-robustness-4-{}", std::process::id()));
    let stdout = eigenmpc_ok(&[
        "robustness",
        "--model",
        robot,
        "--energy",
        "1",
        "--tau-max",
        "2",
        "--duration",
        "12",
        "--steps",
        "2",
        "--categories",
        "measurement delay",
        "--undeclared",
        "--out",
        dir.to_str().unwrap(),
    ]);
    // No delay: the nominal loop holds 1 J on the friction alone.
    assert!(
        stdout.contains("measurement delay: 0.50 -> 0.50"),
        "{stdout}"
    );
    let csv = std::fs::read_to_string(dir.join("robustness.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert!(header.contains(&"rms_tau4_Nm") && header.contains(&"rms_friction4_Nm"));
    assert!(!header.contains(&"rms_tau5_Nm"));
    let first: Vec<&str> = csv.lines().nth(1).unwrap().split(',').collect();
    assert_eq!(first.len(), header.len());
    let cell = |name: &str| first[header.iter().position(|h| *h == name).unwrap()];
    assert_eq!((cell("value"), cell("success")), ("0", "true"));
    // Torque on the friction: within the 0.03 N m allowance of it, per joint.
    for j in 1..=4 {
        let tau: f64 = cell(&format!("rms_tau{j}_Nm")).parse().unwrap();
        let friction: f64 = cell(&format!("rms_friction{j}_Nm")).parse().unwrap();
        assert!(
            (tau - friction).abs() < 0.005,
            "joint {j}: {tau} vs {friction}"
        );
    }
    let md = std::fs::read_to_string(dir.join("robustness.md")).unwrap();
    assert!(md.contains("every joint from 0.05 rad at rest"), "{md}");
    std::fs::remove_dir_all(&dir).ok();
}
