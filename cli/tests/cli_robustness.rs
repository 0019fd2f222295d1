//! `eigenmpc robustness`: the report's files, its verdicts on a category
//! whose outcome is known, the same numbers on 1 and 2 threads, clear errors.

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
            "--duration",
            "30",
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
        assert!(md.contains("| measurement delay | 4 |"), "{md}");
        tables.push(std::fs::read_to_string(dir.join("robustness.csv")).unwrap());
    }
    assert_eq!(tables[0], tables[1], "the thread count changed the numbers");
    // one row per case and adaptation setting
    let rows: Vec<Vec<&str>> = tables[0]
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 8);
    // without adaptation: 25 ms of delay costs nothing (the band at about
    // 20 s, as without delay), 200 ms keeps the energy out of it
    let off = |value: &str| {
        rows.iter()
            .find(|r| r[2] == value && r[4] == "false")
            .unwrap_or_else(|| panic!("no row for {value}"))
            .clone()
    };
    assert_eq!(off("0.025")[5], "true");
    let band: f64 = off("0.025")[6].parse().unwrap();
    assert!((18.0..22.0).contains(&band), "{band}");
    assert_eq!(off("0.2")[5], "false");
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
    ] {
        let out = eigenmpc(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
}
