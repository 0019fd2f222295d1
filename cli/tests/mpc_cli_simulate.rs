//! `eigenmpc simulate`: summary, CSV columns, plots, clear errors.

mod common;
use common::{eigenmpc, eigenmpc_ok};

#[test]
fn simulate_writes_csv_and_plots() {
    let dir = std::env::temp_dir().join(format!("eigenmpc-sim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("out.csv");
    let png = dir.join("out.png");
    let out = eigenmpc(&[
        "simulate",
        "--variant",
        "straight",
        "--family",
        "anti-phase",
        "--energy",
        "2",
        "--x0",
        "0.05,-0.05,0,0",
        "--duration",
        "2",
        "--N",
        "20",
        "--csv",
        csv.to_str().unwrap(),
        "--plot",
        png.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("solve time per sample"), "{stdout}");
    assert!(stdout.contains("RMS distance to the mode"), "{stdout}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("time,q1,q2,qd1,qd2,tau1,tau2,energy,solve_ms")
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 81, "2 s at 25 ms plus the initial sample");
    assert!((rows[0][1] - 0.05).abs() < 1e-15 && (rows[0][2] + 0.05).abs() < 1e-15);
    assert!(
        rows.iter()
            .all(|r| r[5].abs() <= 1.0 + 1e-12 && r[6].abs() <= 1.0 + 1e-12)
    );
    // The energy column is the plant energy: it must grow under the controller.
    assert!(rows[80][7] > rows[0][7]);
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    let svg = dir.join("out.svg");
    let out = eigenmpc(&[
        "simulate",
        "--energy",
        "3",
        "--duration",
        "0.5",
        "--N",
        "10",
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn simulate_refuses_bad_input_with_a_message() {
    for (args, needle) in [
        (vec!["simulate", "--x0", "1,2"], "--x0"),
        (vec!["simulate", "--dt", "-1", "--duration", "1"], "dt"),
        (vec!["simulate", "--energy", "nan"], "--energy"),
        (vec!["simulate", "--qp", "hpipm"], "unknown QP backend"),
        (vec!["simulate", "--ekf", "0.05,0.05"], "--ekf needs three"),
        (
            vec!["simulate", "--ekf", "0.05,0,0.3", "--duration", "1"],
            "speed_noise = 0 is invalid",
        ),
        (
            vec!["simulate", "--noise", "-1", "--duration", "1"],
            "--noise",
        ),
        (
            vec!["simulate", "--measurement-delay", "1.5", "--duration", "1"],
            "measurement_delay = 1.5 is invalid",
        ),
        (
            vec![
                "simulate",
                "--actuator-time-constant",
                "-0.1",
                "--duration",
                "1",
            ],
            "actuator_time_constant = -0.1 is invalid",
        ),
        (
            vec![
                "simulate",
                "--variant",
                "curved",
                "--chart",
                "/nonexistent.json",
                "--duration",
                "1",
            ],
            "nonexistent",
        ),
        // Flag errors: one line and exit code 1, as every other error.
        (vec!["simulate", "--bogus"], "unexpected argument '--bogus'"),
        (vec!["simulate", "--duration"], "a value is required"),
        (
            vec!["modes"],
            "required arguments were not provided: --energies <ENERGIES>",
        ),
        // Output paths are checked before the run (a 3600 s run would
        // otherwise end in the error).
        (
            vec!["simulate", "--duration", "3600", "--plot", "/tmp/x.jpg"],
            "PNG or SVG",
        ),
        (
            vec![
                "simulate",
                "--duration",
                "3600",
                "--csv",
                "/nonexistent/run.csv",
            ],
            "--csv /nonexistent/run.csv: cannot write",
        ),
    ] {
        let out = eigenmpc(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{args:?}: {stderr}");
    }
    // The variants are clap's values, from the core's table: the one-line
    // usage error lists them.
    let out = eigenmpc(&["simulate", "--variant", "wobbly"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("invalid value 'wobbly' for '--variant <VARIANT>'")
            && stderr.contains("[possible values: straight, curved, hybrid]"),
        "{stderr}"
    );
}

#[test]
fn a_run_shorter_than_the_window_says_so() {
    let stdout = eigenmpc_ok(&["simulate", "--duration", "2"]);
    assert!(stdout.contains("RMS torque, whole run (2 s):"), "{stdout}");
    assert!(!stdout.contains("last 5 s"), "{stdout}");
}

#[test]
fn simulate_qp_backends_agree() {
    // The same 2 s closed loop with each QP backend: the energy columns of
    // the CSVs agree (both QPs are solved well below 1e-6).
    let dir = std::env::temp_dir().join(format!("eigenmpc-simqp-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut energies = Vec::new();
    for qp in ["clarabel", "riccati"] {
        let csv = dir.join(format!("{qp}.csv"));
        let out = eigenmpc(&[
            "simulate",
            "--variant",
            "straight",
            "--energy",
            "4",
            "--duration",
            "2",
            "--N",
            "40",
            "--qp",
            qp,
            "--csv",
            csv.to_str().unwrap(),
        ]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{stdout}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(stdout.contains(&format!("QP {qp}")), "{stdout}");
        let text = std::fs::read_to_string(&csv).unwrap();
        let energy: Vec<f64> = text
            .lines()
            .skip(1)
            .map(|l| l.split(',').nth(7).unwrap().parse().unwrap())
            .collect();
        assert_eq!(energy.len(), 81);
        energies.push(energy);
    }
    let worst = energies[0]
        .iter()
        .zip(&energies[1])
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    // The controller pumps energy in, so the comparison is not of two idle runs.
    assert!(energies[0][80] > 2.0 * energies[0][0], "{:?}", energies[0]);
    assert!(
        worst < 1e-4,
        "clarabel vs riccati energy differ by {worst:e} J"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Measurement noise of 0.05 rad and rad/s: the EKF keeps it out of the torque.
#[test]
fn simulate_noise_with_and_without_the_estimator() {
    let rms = |extra: &[&str]| -> f64 {
        let mut args = vec!["simulate", "--noise", "0.05", "--duration", "30"];
        args.extend_from_slice(extra);
        let out = eigenmpc(&args);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{stdout}");
        let line = stdout
            .lines()
            .find(|l| l.starts_with("RMS torque, last 5 s:"))
            .unwrap();
        line.split_once(':')
            .unwrap()
            .1
            .split_whitespace()
            .filter_map(|w| w.parse::<f64>().ok())
            .fold(0.0, f64::max)
    };
    let with = rms(&["--ekf", "0.05,0.05,0.3"]);
    let without = rms(&[]);
    assert!(
        with < 0.1 && without > 0.3,
        "with EKF {with}, without {without}"
    );
}

#[test]
fn a_chart_of_the_other_family_is_refused() {
    let path = std::env::temp_dir().join(format!("eigenmpc-anti-{}.json", std::process::id()));
    let json = eigenmpc_ok(&["modes", "--family", "anti-phase", "--energies", "12"]);
    std::fs::write(&path, json).unwrap();
    let out = eigenmpc(&[
        "simulate",
        "--variant",
        "curved",
        "--family",
        "in-phase",
        "--energy",
        "14",
        "--chart",
        path.to_str().unwrap(),
        "--duration",
        "1",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(
            "its modes are of the anti-phase family, this run follows the in-phase family"
        ),
        "{stderr}"
    );
    // The same file for an anti-phase run is taken.
    eigenmpc_ok(&[
        "simulate",
        "--variant",
        "curved",
        "--family",
        "anti-phase",
        "--energy",
        "12",
        "--chart",
        path.to_str().unwrap(),
        "--duration",
        "1",
    ]);
    std::fs::remove_file(&path).ok();
}

/// A 2-sample measurement delay (`--delay-samples`): declared with
/// `--measurement-delay`, the torque is the undelayed run's (measured in
/// tests/mpc_delay.rs: the same to four digits); undeclared it grows by
/// two thirds.
#[test]
fn simulate_compensates_a_declared_delay() {
    let rms = |extra: &[&str]| -> f64 {
        let mut args = vec!["simulate", "--duration", "30"];
        args.extend_from_slice(extra);
        let out = eigenmpc(&args);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{stdout}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let line = stdout
            .lines()
            .find(|l| l.starts_with("RMS torque, last 5 s:"))
            .unwrap();
        line.split_once(':')
            .unwrap()
            .1
            .split_whitespace()
            .filter_map(|w| w.parse::<f64>().ok())
            .fold(0.0, f64::max)
    };
    let none = rms(&[]);
    let declared = rms(&["--delay-samples", "2", "--measurement-delay", "0.05"]);
    let undeclared = rms(&["--delay-samples", "2"]);
    assert!(
        (declared - none).abs() < 0.03 * none && undeclared > 1.3 * none,
        "none {none}, declared {declared}, undeclared {undeclared}"
    );
}
