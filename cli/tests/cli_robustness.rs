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
