//! `eigenmpc simulate --adapt --plant FILE`: the controller's model (the
//! paper's pendulum) drives a plant whose second link is 20 % lighter and
//! adapts; the CSV's estimate ends at the plant's base parameters, the
//! adaptation figure is written; bad plants give a clear error.

mod common;
use common::{eigenmpc, eigenmpc_ok};
use std::path::{Path, PathBuf};

/// A fresh folder for one test's files.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("eigenmpc-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The paper's pendulum (1 kg, 1 m point masses) with `m2` instead of 1 kg.
fn pendulum_file(dir: &Path, m2: f64) -> PathBuf {
    let path = dir.join("plant.yml");
    std::fs::write(
        &path,
        format!("name: paper's pendulum, m2 = {m2} kg\nm1: 1\nm2: {m2}\nl1: 1\nl2: 1\ng: 9.81\n"),
    )
    .unwrap();
    path
}

/// The cells of one CSV line; a quoted cell may hold commas
/// (`"estimate.A[1,2]"`).
fn cells(line: &str) -> Vec<String> {
    let mut out = vec![String::new()];
    let mut quoted = false;
    for c in line.chars() {
        match c {
            '"' => quoted = !quoted,
            ',' if !quoted => out.push(String::new()),
            c => out.last_mut().unwrap().push(c),
        }
    }
    out
}

#[test]
fn adaptation_finds_the_lighter_plant_and_plots_it() {
    let dir = scratch("adapt");
    let plant = pendulum_file(&dir, 0.8);
    let csv = dir.join("run.csv");
    let png = dir.join("run.png");
    let stdout = eigenmpc_ok(&[
        "simulate",
        "--adapt",
        "--plant",
        plant.to_str().unwrap(),
        "--duration",
        "60",
        "--csv",
        csv.to_str().unwrap(),
        "--plot",
        png.to_str().unwrap(),
    ]);
    assert!(
        stdout.contains("controller's model the paper's pendulum"),
        "{stdout}"
    );
    assert!(stdout.contains("adaptation:"), "{stdout}");

    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header = cells(lines.next().unwrap());
    let rows: Vec<Vec<String>> = lines.map(cells).collect();
    assert_eq!(rows.len(), 2401, "60 s at 25 ms plus the initial sample");
    let col = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
    };
    // The FMU's output names for the estimate, the model in use after them.
    assert_eq!(header[9], "estimate.A[1,1]");
    assert!(header.len() == 9 + 11 + 11 + 4, "{header:?}");
    let value = |row: &[String], name: &str| -> f64 { row[col(name)].parse().unwrap() };
    let (first, last) = (&rows[0], rows.last().unwrap());
    // The plant's base parameters with m2 = 0.8 kg: G2 = m2 g l2,
    // A22 = m2 l2^2, G1 = (m1 + m2) g l1; the model's are 25 % above.
    let truth = [
        ("estimate.G[2]", 0.8 * 9.81),
        ("estimate.A[2,2]", 0.8),
        ("estimate.G[1]", 1.8 * 9.81),
        ("in_use.G[2]", 0.8 * 9.81),
        ("in_use.A[2,2]", 0.8),
    ];
    for (name, plant_value) in truth {
        let start = value(first, name);
        let end = value(last, name);
        assert!(
            (start - plant_value).abs() > 0.1 * plant_value,
            "{name} starts at the model's {start}, not the plant's {plant_value}"
        );
        assert!(
            (end - plant_value).abs() < 0.005 * plant_value,
            "{name} ends at {end}, the plant's is {plant_value}"
        );
    }
    assert!(value(last, "model_updates") >= 1.0, "{last:?}");
    assert_eq!(value(last, "adapt_reverts"), 0.0, "{last:?}");
    assert_eq!(last[col("adaptation_status")], "converged", "{last:?}");
    // With the model taken the plant's energy is held at E_ref (without
    // adaptation it ends 17 % low: docs/book/src/adaptation.md).
    let energy: Vec<f64> = rows[rows.len() - 200..]
        .iter()
        .map(|r| value(r, "energy"))
        .collect();
    let mean = energy.iter().sum::<f64>() / energy.len() as f64;
    assert!((mean - 14.0).abs() < 0.01 * 14.0, "mean energy {mean} J");

    // The summary compares the final estimate with the plant.
    let g2 = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("G[2] (N m)"))
        .unwrap_or_else(|| panic!("no G[2] row: {stdout}"));
    assert!(g2.contains("7.84800"), "{g2}");

    for (path, least) in [
        (png.clone(), 50_000),
        (dir.join("run_adaptation.png"), 100_000),
    ] {
        let bytes = std::fs::read(&path).unwrap_or_default();
        assert!(
            bytes.len() > least,
            "{}: {} bytes",
            path.display(),
            bytes.len()
        );
        assert_eq!(&bytes[1..4], b"PNG", "{}", path.display());
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_adaptation_figure_follows_the_plot_format() {
    let dir = scratch("adapt-svg");
    let svg = dir.join("short.svg");
    eigenmpc_ok(&[
        "simulate",
        "--adapt",
        "--duration",
        "2",
        "--plot",
        svg.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(dir.join("short_adaptation.svg")).unwrap();
    assert!(text.contains("<svg") && text.contains("G[2] gravity amplitude"));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_bad_plant_is_refused_with_a_message() {
    let dir = scratch("adapt-bad");
    let three = dir.join("three.yml");
    std::fs::write(
        &three,
        "m1: 1\nm2: 1\nm3: 1\nl1: 1\nl2: 1\nl3: 1\ng: 9.81\n",
    )
    .unwrap();
    let springs = dir.join("springs.yml");
    std::fs::write(&springs, "m1: 1\nm2: 1\nl1: 1\nl2: 1\ng: 9.81\nk1: 2\n").unwrap();
    let missing = dir.join("missing.yml");
    let lab = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../robots/lab-double-pendulum-A0.yml"
    );
    for (args, needle) in [
        (
            vec!["simulate", "--adapt", "--plant", three.to_str().unwrap()],
            "the plant has 3 joints, the controller's model (the paper's pendulum) has 2".into(),
        ),
        (
            vec![
                "simulate",
                "--plant",
                three.to_str().unwrap(),
                "--model",
                lab,
            ],
            format!("the plant has 3 joints, the controller's model ({lab}) has 2"),
        ),
        (
            vec!["simulate", "--plant", missing.to_str().unwrap()],
            format!("--plant: {}: cannot read", missing.display()),
        ),
        (
            vec!["simulate", "--adapt", "--model", springs.to_str().unwrap()],
            "--adapt: identification needs a chain without joint springs".into(),
        ),
    ] {
        let out = eigenmpc(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains(&needle), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{args:?}: {stderr}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
