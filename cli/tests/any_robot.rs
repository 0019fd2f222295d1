//! `eigenmpc modes` and `eigenmpc simulate` on robot files of every joint
//! count of the table (robots/examples: 1, 4, 5 and 6 joints, point masses
//! and rigid links with friction), checked against physics: the single
//! pendulum's half period against the elliptic integral, every turning
//! point at the requested energy, and the closed loop into the 5 % band.

use eigenmpc::math;
use eigenmpc::mechanics::MechanicalSystem;
use eigenmpc::model_file::RobotFile;
use serde_json::Value;
use std::path::PathBuf;

mod common;

fn run(args: &[&str]) -> (i32, String, String) {
    let out = common::eigenmpc(args);
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn example(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../robots/examples")
        .join(name)
        .display()
        .to_string()
}

/// Potential energy of the file's chain at `q` (the chain's own count).
fn potential(file: &str, q: &[f64]) -> f64 {
    let robot = RobotFile::load(file).unwrap();
    eigenmpc::with_joint_count!(
        robot.links(),
        |N, S, NP| {
            let chain = robot.chain::<N>().unwrap();
            chain.potential(&eigenmpc::mechanics::Vector::<N>::from_column_slice(q))
        },
        otherwise panic!("unsupported")
    )
}

fn modes(file: &str, energies: &str) -> Value {
    let (code, stdout, stderr) = run(&["modes", "--model", file, "--energies", energies]);
    assert_eq!(code, 0, "{stderr}");
    serde_json::from_str(&stdout).expect("valid JSON")
}

/// Complete elliptic integral of the first kind K(k), by the AGM.
fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - k * k).sqrt());
    for _ in 0..30 {
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    std::f64::consts::PI / (2.0 * a)
}

#[test]
fn a_single_pendulum_swings_with_the_elliptic_period() {
    let file = example("single-pendulum.yml");
    let doc = modes(&file, "0.2,1,5");
    // 1 kg at 1 m, g = 9.81: omega = sqrt(g / l).
    let omega = doc["linear"]["omega"].as_f64().unwrap();
    assert!((omega - 9.81f64.sqrt()).abs() < 1e-12, "{omega}");
    for m in doc["modes"].as_array().unwrap() {
        let energy = m["energy"].as_f64().unwrap();
        let amplitude = math::acos(1.0 - energy / 9.81);
        let tp = m["turning_point"][0].as_f64().unwrap();
        assert!((tp.abs() - amplitude).abs() < 1e-9, "{energy} J: {tp}");
        let half = 2.0 * (1.0 / 9.81f64).sqrt() * elliptic_k(math::sin(0.5 * amplitude));
        let got = m["half_period"].as_f64().unwrap();
        assert!((got - half).abs() < 1e-8, "{energy} J: {got} vs {half}");
    }
}

#[test]
fn chains_of_four_five_and_six_joints_have_closed_modes_at_the_energy() {
    for (name, joints) in [
        ("four-link-rigid.yml", 4),
        ("five-link-point-masses.yml", 5),
        ("six-link-rigid.yml", 6),
    ] {
        let file = example(name);
        let doc = modes(&file, "0.2,1");
        assert_eq!(doc["model"]["kind"], "planar-chain");
        let c: Vec<f64> = serde_json::from_value(doc["linear"]["eigenvector"].clone()).unwrap();
        assert_eq!(c.len(), joints, "{name}");
        assert!((c.iter().map(|x| x * x).sum::<f64>() - 1.0).abs() < 1e-12);
        for m in doc["modes"].as_array().unwrap() {
            let energy = m["energy"].as_f64().unwrap();
            let tp: Vec<f64> = serde_json::from_value(m["turning_point"].clone()).unwrap();
            assert_eq!(tp.len(), joints);
            // A brake orbit: at rest at the turning point, all energy potential.
            let v = potential(&file, &tp);
            assert!(
                (v - energy).abs() < 1e-8 * energy.max(1.0),
                "{name}: V = {v}"
            );
            assert!(m["closing_error"].as_f64().unwrap() < 1e-9, "{name}");
            let coef: Vec<Vec<f64>> =
                serde_json::from_value(m["chart"]["coefficients"].clone()).unwrap();
            assert_eq!(coef.len(), joints);
            let residual = m["chart"]["max_residual"].as_f64().unwrap();
            assert!(
                residual < 1e-4,
                "{name} {energy} J: chart residual {residual}"
            );
            let path = m["path"].as_array().unwrap();
            assert!(path.iter().all(|p| p.as_array().unwrap().len() == joints));
        }
    }
}

/// The summary's band time and mean energy over the last 5 s.
fn band_and_energy(stdout: &str) -> (f64, f64) {
    let band = stdout
        .lines()
        .find_map(|l| l.strip_prefix("time to |E - E_ref| < 5 % for good:"))
        .and_then(|v| v.trim().trim_end_matches(" s").parse().ok())
        .unwrap_or_else(|| panic!("no band time in:\n{stdout}"));
    let mean = stdout
        .lines()
        .find_map(|l| l.split_once("mean ").map(|(_, r)| r))
        .and_then(|r| r.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no mean energy in:\n{stdout}"));
    (band, mean)
}

#[test]
fn every_joint_count_closes_the_loop_into_the_band() {
    let dir = std::env::temp_dir().join(format!("eigenmpc-any-robot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, energy, duration, joints) in [
        ("single-pendulum.yml", 2.0, 15.0, 1),
        ("four-link-rigid.yml", 1.0, 15.0, 4),
        ("five-link-point-masses.yml", 2.0, 30.0, 5),
        ("six-link-rigid.yml", 1.0, 15.0, 6),
    ] {
        let file = example(name);
        let csv = dir.join(format!("{name}.csv"));
        let plot = dir.join(format!("{name}.png"));
        let (code, stdout, stderr) = run(&[
            "simulate",
            "--model",
            &file,
            "--energy",
            &energy.to_string(),
            "--duration",
            &duration.to_string(),
            "--csv",
            csv.to_str().unwrap(),
            "--plot",
            plot.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{name}: {stderr}");
        let (band, mean) = band_and_energy(&stdout);
        eprintln!("{name}: band at {band} s, mean energy {mean} J");
        assert!(band < duration - 5.0, "{name}: band at {band} s");
        assert!(
            (mean - energy).abs() < 0.01 * energy,
            "{name}: {mean} J, E_ref {energy} J"
        );
        // Every joint in the CSV, every panel in the figure.
        let header = std::fs::read_to_string(&csv).unwrap();
        let header = header.lines().next().unwrap();
        assert!(header.contains(&format!("q{joints}")), "{header}");
        assert!(header.contains(&format!("tau{joints}")), "{header}");
        assert!(std::fs::metadata(&plot).unwrap().len() > 10_000);
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_wrong_joint_count_is_a_clear_error() {
    let dir = std::env::temp_dir().join(format!("eigenmpc-seven-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let seven = dir.join("seven.yml");
    let text: String = (1..=7).map(|j| format!("m{j}: 1\nl{j}: 1\n")).collect();
    std::fs::write(&seven, text + "g: 9.81\n").unwrap();
    let (code, _, stderr) = run(&[
        "modes",
        "--model",
        seven.to_str().unwrap(),
        "--energies",
        "1",
    ]);
    assert_eq!(code, 1);
    assert!(stderr.contains("at most 6 links"), "{stderr}");

    // One joint has one mode: the anti-phase family is an error, not a panic.
    let single = example("single-pendulum.yml");
    for command in [
        &[
            "modes",
            "--model",
            &single,
            "--energies",
            "1",
            "--family",
            "anti-phase",
        ][..],
        &[
            "simulate",
            "--model",
            &single,
            "--variant",
            "straight",
            "--family",
            "anti-phase",
        ],
    ] {
        let (code, _, stderr) = run(command);
        assert_eq!(code, 1, "{command:?}: {stderr}");
        assert!(
            stderr.contains("1-joint chain has no anti-phase family"),
            "{stderr}"
        );
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    }

    let four = example("four-link-rigid.yml");
    let (code, _, stderr) = run(&[
        "simulate",
        "--model",
        &four,
        "--x0",
        "0.1,0.1,0,0",
        "--duration",
        "1",
    ]);
    assert_eq!(code, 1);
    assert!(stderr.contains("--x0 needs 8"), "{stderr}");

    let (code, _, stderr) = run(&[
        "simulate",
        "--model",
        &four,
        "--plant",
        &example("six-link-rigid.yml"),
        "--duration",
        "1",
    ]);
    assert_eq!(code, 1);
    assert!(stderr.contains("the plant has 6 joints"), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}
