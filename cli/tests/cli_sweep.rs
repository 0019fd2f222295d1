//! `eigenmpc sweep`: a TOML spec's grid and the options' random sample, the
//! same numbers on 1 and 2 threads, results that match the single closed
//! loop they repeat, clear errors before any run starts.

mod common;
use common::{eigenmpc, eigenmpc_ok};

/// The CSV without the machine-dependent solve-time columns.
fn physics_columns(csv: &str) -> Vec<Vec<String>> {
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let keep: Vec<usize> = (0..header.len())
        .filter(|&i| !header[i].starts_with("solve_time"))
        .collect();
    csv.lines()
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            keep.iter().map(|&i| cells[i].to_string()).collect()
        })
        .collect()
}

/// `eigenmpc simulate`'s time to the band (s).
fn band_of(simulate: &str) -> f64 {
    simulate
        .lines()
        .find_map(|l| l.strip_prefix("time to |E - E_ref| < 5 % for good:"))
        .and_then(|v| v.trim().trim_end_matches(" s").parse::<f64>().ok())
        .expect("simulate's time to band")
}

#[test]
fn a_grid_spec_runs_the_same_on_1_and_2_threads() {
    let base = std::env::temp_dir().join(format!("eigenmpc-sweep-{}", std::process::id()));
    std::fs::create_dir_all(&base).unwrap();
    let spec = base.join("spec.toml");
    std::fs::write(
        &spec,
        r#"
duration = 30.0
metric = "time_to_band"

[grid]
"controller.E_ref" = [10.0, 14.0]
"imperfections.delay" = { from = 0, to = 8, count = 2 }
"#,
    )
    .unwrap();
    let mut tables = vec![];
    for threads in ["1", "2"] {
        let dir = base.join(threads);
        let stdout = eigenmpc_ok(&[
            "sweep",
            "--spec",
            spec.to_str().unwrap(),
            "--threads",
            threads,
            "--out",
            dir.to_str().unwrap(),
        ]);
        assert!(stdout.contains("4 runs of 30 s"), "{stdout}");
        for file in ["sweep.csv", "sweep.json", "sweep.png", "sweep.svg"] {
            let len = std::fs::metadata(dir.join(file))
                .map(|m| m.len())
                .unwrap_or(0);
            assert!(len > 300, "{file}: {len} bytes");
        }
        tables.push(std::fs::read_to_string(dir.join("sweep.csv")).unwrap());
    }
    let rows = physics_columns(&tables[0]);
    assert_eq!(
        rows,
        physics_columns(&tables[1]),
        "the thread count changed the numbers"
    );
    assert_eq!(
        rows[0][..3],
        ["run", "controller.E_ref", "imperfections.delay"]
    );
    assert_eq!(rows.len(), 5);
    let col = |name: &str| rows[0].iter().position(|c| c == name).unwrap();
    let (band, success) = (col("time_to_band"), col("success"));
    // E_ref = 14 J without delay is `eigenmpc simulate`'s default run: the
    // band at 19.675 s (docs/book/src/demo.md).
    let row = rows
        .iter()
        .find(|r| r[1] == "14" && r[2] == "0")
        .expect("the 14 J row");
    assert_eq!(row[band], "19.675");
    assert_eq!(row[success], "1");
    // 8 samples (200 ms) of delay keep the energy out of the band.
    let delayed = rows.iter().find(|r| r[1] == "14" && r[2] == "8").unwrap();
    assert_eq!(delayed[success], "0");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(base.join("1/sweep.json")).unwrap()).unwrap();
    assert_eq!(json["runs"].as_array().unwrap().len(), 4);
    assert_eq!(json["runs"][3]["parameters"]["controller.E_ref"], 14.0);
    assert!(json["runs"][3]["metrics"]["rms_torque"].is_array());
}

#[test]
fn a_random_sample_from_the_options() {
    let dir = std::env::temp_dir().join(format!("eigenmpc-sweep-rand-{}", std::process::id()));
    let args = [
        "sweep",
        "--random",
        "3",
        "--range",
        "model.m[2]=0.9:1.1",
        "--seed",
        "5",
        "--set",
        "controller.E_ref=12",
        "--duration",
        "8",
        "--metric",
        "mean_energy_error",
        "--out",
        dir.to_str().unwrap(),
    ];
    eigenmpc_ok(&args);
    let first = std::fs::read_to_string(dir.join("sweep.csv")).unwrap();
    let rows = physics_columns(&first);
    assert_eq!(rows.len(), 4);
    assert_eq!(rows[0][1], "model.m[2]");
    let masses: Vec<f64> = rows[1..].iter().map(|r| r[1].parse().unwrap()).collect();
    assert!(masses.iter().all(|m| (0.9..=1.1).contains(m)), "{masses:?}");
    assert!(masses[0] != masses[1] && masses[1] != masses[2]);
    eigenmpc_ok(&args);
    let again = std::fs::read_to_string(dir.join("sweep.csv")).unwrap();
    assert_eq!(
        physics_columns(&again),
        rows,
        "the same seed, the same sample"
    );
}

#[test]
fn bad_sweeps_are_refused_before_any_run() {
    let dir = std::env::temp_dir().join(format!("eigenmpc-sweep-bad-{}", std::process::id()));
    let out = dir.to_str().unwrap();
    for (args, needle) in [
        (vec!["--grid", "E_ref=2,4"], "give the scope"),
        (
            vec!["--grid", "controller.E_rf=2,4"],
            "E_rf is not a variable of EigenMPC",
        ),
        (
            vec!["--grid", "controller.E_ref=2,x"],
            "'x' is not a number",
        ),
        (
            vec!["--grid", "controller.tau_max=1,0"],
            "run 1 (controller.tau_max = 0)",
        ),
        (
            vec!["--set", "plant.m[3]=1"],
            "m[3] is not a variable of DoublePendulum",
        ),
        (vec!["--range", "model.m[2]=1:2"], "--range needs --random"),
        (vec!["--metric", "speed"], "unknown metric `speed`"),
        (vec!["--duration", "3"], "more than the 5 s"),
        (
            vec!["--spec", "/nonexistent/spec.toml"],
            "/nonexistent/spec.toml",
        ),
    ] {
        let mut all = vec!["sweep", "--out", out];
        all.extend(args.iter().copied());
        let o = eigenmpc(&all);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    }
    // An unwritable output folder is found before the runs.
    let o = eigenmpc(&["sweep", "--out", "/proc/eigenmpc-sweep"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("/proc/eigenmpc-sweep"));
}

#[test]
fn a_robot_file_sweep_repeats_simulate() {
    let robot = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../robots/lab-double-pendulum-A0.yml"
    );
    let dir = std::env::temp_dir().join(format!("eigenmpc-sweep-file-{}", std::process::id()));
    eigenmpc_ok(&[
        "sweep",
        "--model",
        robot,
        "--set",
        "controller.tau_max=0.5",
        "--grid",
        "controller.E_ref=2",
        "--duration",
        "30",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let rows = physics_columns(&std::fs::read_to_string(dir.join("sweep.csv")).unwrap());
    let col = |name: &str| rows[0].iter().position(|c| c == name).unwrap();
    // `eigenmpc simulate` of the same robot, E_ref and torque bound (its
    // computed family is the FMU's default reference).
    let stdout = eigenmpc_ok(&[
        "simulate",
        "--model",
        robot,
        "--energy",
        "2",
        "--tau-max",
        "0.5",
        "--duration",
        "30",
        "--chart-family",
    ]);
    let band = band_of(&stdout);
    let sweep: f64 = rows[1][col("time_to_band")].parse().unwrap();
    assert!(
        (sweep - band).abs() < 1e-3,
        "sweep {sweep} s, simulate {band} s"
    );
    let error: f64 = rows[1][col("final_energy_error")].parse().unwrap();
    assert!(
        stdout.contains(&format!("{error:.4} J")),
        "{error}: {stdout}"
    );
}

#[test]
fn a_four_joint_robot_file_sweep_repeats_simulate() {
    let robot = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../robots/examples/four-link-rigid.yml"
    );
    let dir = std::env::temp_dir().join(format!("eigenmpc-sweep-4-{}", std::process::id()));
    let stdout = eigenmpc_ok(&[
        "sweep",
        "--model",
        robot,
        "--grid",
        "controller.E_ref=1",
        "--duration",
        "15",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(stdout.contains("1 reached the 5 % band"), "{stdout}");
    let rows = physics_columns(&std::fs::read_to_string(dir.join("sweep.csv")).unwrap());
    let col = |name: &str| rows[0].iter().position(|c| c == name).unwrap();
    // One torque column per joint, and no fifth.
    assert!(rows[0].iter().any(|c| c == "rms_torque_4"));
    assert!(!rows[0].iter().any(|c| c == "rms_torque_5"));
    let simulate = eigenmpc_ok(&[
        "simulate",
        "--model",
        robot,
        "--energy",
        "1",
        "--duration",
        "15",
        "--chart-family",
    ]);
    let band = band_of(&simulate);
    let sweep: f64 = rows[1][col("time_to_band")].parse().unwrap();
    assert!(
        (sweep - band).abs() < 1e-9,
        "sweep {sweep} s, simulate {band} s"
    );
    let torques: Vec<String> = (1..=4)
        .map(|j| {
            let t: f64 = rows[1][col(&format!("rms_torque_{j}"))].parse().unwrap();
            format!("{t:.4}")
        })
        .collect();
    let line = format!(
        "RMS torque, last 5 s:            {} N m",
        torques.join(" / ")
    );
    assert!(simulate.contains(&line), "{line}\n{simulate}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_sweep_split_in_parts_merges_into_the_same_outputs() {
    let base = std::env::temp_dir().join(format!("eigenmpc-sweep-parts-{}", std::process::id()));
    std::fs::create_dir_all(&base).unwrap();
    let spec = base.join("spec.toml");
    std::fs::write(
        &spec,
        "duration = 6.0\n[grid]\n\"controller.E_ref\" = [10.0, 14.0]\n\
         [random]\nsamples = 2\nseed = 5\n[random.ranges]\n\"model.m[2]\" = { from = 0.9, to = 1.1 }\n",
    )
    .unwrap();
    let spec = spec.to_str().unwrap();
    let plan: serde_json::Value =
        serde_json::from_str(&eigenmpc_ok(&["sweep", "--spec", spec, "--plan"])).unwrap();
    assert_eq!(
        plan,
        serde_json::json!({"runs": 4, "joints": 2, "swept": ["controller.E_ref", "model.m[2]"]})
    );
    let whole = base.join("whole");
    eigenmpc_ok(&["sweep", "--spec", spec, "--out", whole.to_str().unwrap()]);
    let mut parts = vec![];
    for (i, range) in ["0..1", "1..4"].iter().enumerate() {
        let part = base.join(format!("part{i}.json"));
        eigenmpc_ok(&[
            "sweep",
            "--spec",
            spec,
            "--only",
            range,
            "--rows-out",
            part.to_str().unwrap(),
        ]);
        parts.push(part);
    }
    let merged = base.join("merged");
    let stdout = eigenmpc_ok(&[
        "sweep",
        "--spec",
        spec,
        "--from-rows",
        parts[1].to_str().unwrap(),
        "--from-rows",
        parts[0].to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert!(
        stdout.contains("4 runs of 6 s merged from 2 record file(s)"),
        "{stdout}"
    );
    let read = |dir: &std::path::Path| std::fs::read_to_string(dir.join("sweep.csv")).unwrap();
    assert_eq!(
        physics_columns(&read(&merged)),
        physics_columns(&read(&whole))
    );
    // A part missing is an error naming the run, and nothing is written.
    let o = eigenmpc(&[
        "sweep",
        "--spec",
        spec,
        "--from-rows",
        parts[1].to_str().unwrap(),
        "--out",
        base.join("incomplete").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no record of run(s) 0"));
    assert!(!base.join("incomplete").join("sweep.csv").exists());
    std::fs::remove_dir_all(&base).ok();
}
