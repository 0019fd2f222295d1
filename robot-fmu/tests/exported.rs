//! The exported robots' binary through its FMI 2.0 C functions: one binary,
//! told by its resources, is the controller or the plant of a 1- or a
//! 5-joint robot file and closes the loop into the 5 % band; it refuses an
//! instance without resources or with a joint count outside the table; its
//! shared library exports the 34 FMI 2.0 functions and nothing foreign.

use eigenmpc::model_file::RobotFile;
use eigenmpc::modes::linear_modes;
use eigenmpc::mpc::closed_loop::mode_and_chart;
use eigenmpc_fmu_models::exported::{ExportSpec, ExportedFmu, PairNames, RobotExport, SPEC_FILE};
use eigenmpc_robot::fmi2_exports::*;
use fmi2_slave::testing::TestInstance;
use fmi2_slave::{Model, ffi};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

const OK: ffi::fmi2Status = ffi::fmi2Status_fmi2OK;
const DT: f64 = 0.025;

fn example(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../robots/examples")
        .join(name)
}

/// Writes the controller's and the plant's `resources/` folders of the
/// robot file under `dir`, as `eigenmpc export` does.
fn export<const N: usize, const S: usize>(file: &Path, energy: f64, dir: &Path) -> [PathBuf; 2] {
    let robot = RobotFile::load(file).unwrap();
    let system = robot.chain::<N>().unwrap();
    let eigenvector = linear_modes(&system).unwrap()[0].eigenvector;
    let (_, chart) = mode_and_chart::<_, N, S>(&system, 0, energy, 9).unwrap();
    let specs = RobotExport {
        names: &PairNames::of_robot("Robot", "test", N, "in-phase"),
        model: system.params(),
        e_ref: energy,
        eigenvector: &std::array::from_fn(|j| eigenvector[j]),
        chart: &chart.coefficients,
        tau_max: 1.0,
    }
    .specs()
    .unwrap();
    specs.map(|spec| {
        let resources = dir.join(&spec.model_name).join("resources");
        std::fs::create_dir_all(&resources).unwrap();
        std::fs::write(
            resources.join(SPEC_FILE),
            serde_json::to_string(&spec).unwrap(),
        )
        .unwrap();
        resources
    })
}

struct Fmu {
    c: ffi::fmi2Component,
    instance: TestInstance,
    vr: HashMap<String, u32>,
    t: f64,
}

impl Fmu {
    fn new(resources: &Path, start: &[(String, f64)]) -> Self {
        let instance = TestInstance::with_resources::<ExportedFmu>(
            Some(fmi2Instantiate),
            "robot",
            Some(resources),
        );
        let vr = ExportedFmu::description_for(Some(resources))
            .unwrap()
            .variables
            .iter()
            .map(|v| (v.name.clone(), v.value_reference))
            .collect();
        let fmu = Self {
            c: instance.component,
            instance,
            vr,
            t: 0.0,
        };
        unsafe {
            assert_eq!(fmi2SetupExperiment(fmu.c, 0, 0.0, 0.0, 0, 0.0), OK);
            assert_eq!(fmi2EnterInitializationMode(fmu.c), OK);
        }
        for (name, v) in start {
            fmu.set(&[name.as_str()], &[*v]);
        }
        let status = unsafe { fmi2ExitInitializationMode(fmu.c) };
        assert_eq!(status, OK, "{:?}", fmu.instance.log.lines());
        fmu
    }

    fn refs(&self, names: &[&str]) -> Vec<u32> {
        names.iter().map(|n| self.vr[*n]).collect()
    }

    fn set(&self, names: &[&str], v: &[f64]) {
        let vr = self.refs(names);
        let status = unsafe { fmi2SetReal(self.c, vr.as_ptr(), vr.len(), v.as_ptr()) };
        assert_eq!(status, OK, "{:?}", self.instance.log.lines());
    }

    fn get(&self, names: &[&str]) -> Vec<f64> {
        let vr = self.refs(names);
        let mut v = vec![f64::NAN; vr.len()];
        let status = unsafe { fmi2GetReal(self.c, vr.as_ptr(), vr.len(), v.as_mut_ptr()) };
        assert_eq!(status, OK);
        v
    }

    fn step(&mut self) {
        let status = unsafe { fmi2DoStep(self.c, self.t, DT, 1) };
        assert_eq!(status, OK, "{:?}", self.instance.log.lines());
        self.t += DT;
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        unsafe { fmi2FreeInstance(self.c) }
    }
}

/// The band entry time and the mean energy over the last 5 s.
fn closed_loop(resources: &[PathBuf; 2], joints: usize, energy: f64, seconds: f64) -> (f64, f64) {
    let names =
        |base: &str| -> Vec<String> { (1..=joints).map(|j| format!("{base}[{j}]")).collect() };
    let start =
        |base: &str| -> Vec<(String, f64)> { names(base).into_iter().map(|n| (n, 0.05)).collect() };
    let mut controller = Fmu::new(&resources[0], &start("q"));
    let mut plant = Fmu::new(&resources[1], &start("q0"));
    let state: Vec<String> = names("q").into_iter().chain(names("qd")).collect();
    let state: Vec<&str> = state.iter().map(String::as_str).collect();
    let tau = names("tau");
    let tau: Vec<&str> = tau.iter().map(String::as_str).collect();
    let mut energies = vec![];
    for _ in 0..(seconds / DT).round() as usize {
        controller.set(&state, &plant.get(&state));
        controller.step();
        plant.set(&tau, &controller.get(&tau));
        plant.step();
        energies.push(plant.get(&["energy"])[0]);
    }
    let band = (0..energies.len())
        .find(|&i| {
            energies[i..]
                .iter()
                .all(|e| (e - energy).abs() < 0.05 * energy)
        })
        .map_or(f64::INFINITY, |i| DT * (i + 1) as f64);
    let tail = &energies[energies.len() - (5.0 / DT) as usize..];
    (band, tail.iter().sum::<f64>() / tail.len() as f64)
}

#[test]
fn one_binary_is_the_controller_and_the_plant_of_any_joint_count() {
    let dir = std::env::temp_dir().join(format!("eigenmpc-robot-fmu-{}", std::process::id()));
    for (file, joints, energy, seconds) in [
        ("single-pendulum.yml", 1, 2.0, 15.0),
        ("five-link-point-masses.yml", 5, 2.0, 30.0),
    ] {
        let out = dir.join(file);
        let resources = match joints {
            1 => export::<1, 2>(&example(file), energy, &out),
            5 => export::<5, 10>(&example(file), energy, &out),
            _ => unreachable!(),
        };
        let (band, mean) = closed_loop(&resources, joints, energy, seconds);
        eprintln!("{file}: band at {band} s, mean energy {mean} J");
        assert!(band < seconds - 5.0, "{file}: band at {band} s");
        assert!((mean - energy).abs() < 0.01 * energy, "{file}: {mean} J");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn an_instance_needs_its_resources_and_a_supported_joint_count() {
    let instantiate = |resources: Option<&Path>| {
        let log = fmi2_slave::testing::LogCapture::new();
        let callbacks = log.callbacks();
        let name = std::ffi::CString::new("robot").unwrap();
        let guid = std::ffi::CString::new("{00000000-0000-0000-0000-000000000000}").unwrap();
        let uri =
            resources.map(|d| std::ffi::CString::new(format!("file://{}", d.display())).unwrap());
        let c = unsafe {
            fmi2Instantiate(
                name.as_ptr(),
                ffi::fmi2Type_fmi2CoSimulation,
                guid.as_ptr(),
                uri.as_ref().map_or(std::ptr::null(), |u| u.as_ptr()),
                &callbacks,
                0,
                0,
            )
        };
        assert!(c.is_null());
        log.lines()
            .into_iter()
            .map(|l| l.message)
            .collect::<Vec<_>>()
            .join("; ")
    };
    assert!(instantiate(None).contains("needs its resources/ folder"));
    let dir = std::env::temp_dir().join(format!("eigenmpc-robot-fmu-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let spec = ExportSpec {
        kind: eigenmpc_fmu_models::exported::Kind::Controller,
        joints: 7,
        model_name: "Seven".into(),
        description: String::new(),
        start_values: Default::default(),
    };
    std::fs::write(dir.join(SPEC_FILE), serde_json::to_string(&spec).unwrap()).unwrap();
    assert!(instantiate(Some(&dir)).contains("7 joints are not supported"));
    std::fs::write(dir.join(SPEC_FILE), "{\"kind\": \"robot\"}").unwrap();
    assert!(instantiate(Some(&dir)).contains(SPEC_FILE));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_shared_library_exports_the_fmi_functions_only() {
    // The 34 FMI 2.0 functions and the 75 of FMI 3.0, nothing else.
    let exported = fmi2_slave::testing::assert_exports_fmi2_cs(&fmi2_slave::testing::test_cdylib(
        "eigenmpc_robot",
    ));
    for name in fmi3_slave::FMI3_FUNCTIONS {
        assert!(exported.iter().any(|e| e == name), "{name} not exported");
    }
    let foreign: Vec<&String> = exported
        .iter()
        .filter(|s| !s.starts_with("fmi2") && !s.starts_with("fmi3"))
        .collect();
    assert!(foreign.is_empty(), "{foreign:?}");
    assert_eq!(exported.len(), 34 + fmi3_slave::FMI3_FUNCTIONS.len());
}
