//! Parameter sweeps (`eigenmpc sweep`): many closed loops of the controller
//! FMU's controller against the plant FMU's chain, over a grid or a random
//! sample of any of their parameters (by FMU variable name) and of the
//! imperfections of the robustness report.
//!
//! A run is defined by FMU parameter names and values, exactly as the FMUs
//! take them (`controller.E_ref`, `plant.m[2]`, `model.l[1]` for both), so
//! that the Python/Dask runner of the same spec drives the FMUs with the
//! same values. The runs are independent and their order is fixed by the
//! spec: the numbers do not depend on the thread count.
//!
//! Any robot of the joint-count table: the spec's `model` file says how many
//! joints (2, the paper's pendulum, without one), and [`setups`] picks the
//! sizes once for the whole sweep.
//!
//! - this file: the spec, its expansion into runs, one run;
//! - [`report`]: CSV, JSON and the plot;
//! - [`rows`]: the rows as records, for a sweep spread over machines (the
//!   Python/Dask runner calls this sweep on each worker, `--only`, and merges
//!   the records, `--from-rows`).

pub mod report;
pub mod rows;

use eigenmpc::adapt::Adaptation;
use eigenmpc::mechanics::{PlanarChainParams, Vector};
use eigenmpc::model_file::RobotFile;
use eigenmpc::mpc::closed_loop::{GaussianNoise, energy_tail, mode_and_chart, summarise};
use eigenmpc::robustness::{Imperfections, run_imperfect};
use eigenmpc_fmu_models::chain::ChainParameters;
use eigenmpc_fmu_models::controller;
use eigenmpc_fmu_models::controller::settings::Settings;
use eigenmpc_fmu_models::plant::{self, settings::PlantSettings};
use eigenmpc_fmu_models::products::{
    default_settings, plant_settings_from_named, settings_from_named,
};
use fmi2_slave::Value;
use nalgebra::SVector;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Scored window at the end of every run (s).
pub const WINDOW: f64 = 5.0;

pub use eigenmpc::mpc::closed_loop::START_ANGLE;

/// `plant.q0[j] = START_ANGLE` for the `joints` joints.
pub fn base_values(joints: usize) -> Vec<(String, f64)> {
    (1..=joints)
        .map(|j| (format!("plant.q0[{j}]"), START_ANGLE))
        .collect()
}

/// The values of one swept parameter.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(untagged)]
pub enum Axis {
    /// These values.
    List(Vec<f64>),
    /// `count` values evenly spaced from `from` to `to` (both included).
    Range {
        /// First value.
        from: f64,
        /// Last value.
        to: f64,
        /// Number of values (>= 1; 1 gives `from`).
        count: usize,
    },
}

impl Axis {
    /// The values of the axis.
    pub fn values(&self) -> Vec<f64> {
        match self {
            Axis::List(v) => v.clone(),
            Axis::Range { from, to, count } => match count {
                0 => vec![],
                1 => vec![*from],
                n => (0..*n)
                    .map(|i| from + (to - from) * i as f64 / (*n - 1) as f64)
                    .collect(),
            },
        }
    }
}

/// A uniform range of a randomly sampled parameter.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Uniform {
    /// Lower end.
    pub from: f64,
    /// Upper end.
    pub to: f64,
}

/// A random sample instead of a grid.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RandomSample {
    /// Number of runs.
    pub samples: usize,
    /// Seed of the sample (the same seed, the same runs).
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// The sampled parameters and their ranges.
    pub ranges: BTreeMap<String, Uniform>,
}

fn default_seed() -> u64 {
    1
}

fn default_duration() -> f64 {
    30.0
}

/// A sweep: fixed values, the swept parameters and the run length. Names
/// are `controller.<FMU parameter>`, `plant.<FMU parameter>`,
/// `model.<chain parameter>` (both FMUs: the robot itself) and
/// `imperfections.<measurement_noise | torque_noise | responsiveness |
/// delay>` (delay in samples).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// Simulated time of every run (s).
    #[serde(default = "default_duration")]
    pub duration: f64,
    /// A robot parameter file for both FMUs (the fixed values below and
    /// the swept ones go on top of it).
    #[serde(default)]
    pub model: Option<PathBuf>,
    /// Fixed values by name (as in `grid`).
    #[serde(default)]
    pub fixed: BTreeMap<String, f64>,
    /// The grid: every combination of the axes' values, the first name
    /// (in name order) varying slowest.
    #[serde(default)]
    pub grid: BTreeMap<String, Axis>,
    /// A random sample (instead of, or on top of each point of, the grid).
    #[serde(default)]
    pub random: Option<RandomSample>,
    /// Seed of the measurement and torque noise (the same for every run:
    /// runs then differ only in their parameters).
    #[serde(default = "default_seed")]
    pub noise_seed: u64,
    /// Metric of the plot (a CSV column, e.g. `time_to_band`).
    #[serde(default)]
    pub metric: Option<String>,
}

impl Default for Spec {
    fn default() -> Self {
        Self {
            duration: default_duration(),
            model: None,
            fixed: BTreeMap::new(),
            grid: BTreeMap::new(),
            random: None,
            noise_seed: default_seed(),
            metric: None,
        }
    }
}

impl Spec {
    /// Reads a spec from a TOML (`.toml`) or JSON file.
    pub fn load(path: &Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let toml = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
        let spec: Spec = if toml {
            ::toml::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?
        } else {
            serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?
        };
        // A relative parameter file is relative to the spec.
        let model = spec.model.as_ref().map(|m| match path.parent() {
            Some(dir) if m.is_relative() => dir.join(m),
            _ => m.clone(),
        });
        Ok(Spec { model, ..spec })
    }

    /// Joints of the swept robot: the `model` file's, 2 (the paper's
    /// pendulum) without one.
    pub fn joint_count(&self) -> Result<usize, String> {
        eigenmpc::model_file::joint_count(self.model.as_deref()).map_err(|e| e.to_string())
    }

    /// The swept names, in the order of the CSV columns.
    pub fn swept(&self) -> Vec<String> {
        let mut names: Vec<String> = self.grid.keys().cloned().collect();
        if let Some(r) = &self.random {
            names.extend(
                r.ranges
                    .keys()
                    .filter(|k| !self.grid.contains_key(*k))
                    .cloned(),
            );
        }
        names
    }

    /// The runs: per run the swept names and values (in [`Spec::swept`]
    /// order). Checks the names, the axes and the duration.
    pub fn runs(&self) -> Result<Vec<Vec<(String, f64)>>, String> {
        if !(self.duration.is_finite() && self.duration > WINDOW) {
            return Err(format!(
                "duration = {} s must be more than the {WINDOW} s scored at the end",
                self.duration
            ));
        }
        for name in self.fixed.keys().chain(self.grid.keys()) {
            Target::parse(name)?;
        }
        let mut runs: Vec<Vec<(String, f64)>> = vec![vec![]];
        for (name, axis) in &self.grid {
            let values = axis.values();
            if values.is_empty() || values.iter().any(|v| !v.is_finite()) {
                return Err(format!("grid {name}: needs at least one finite value"));
            }
            runs = runs
                .into_iter()
                .flat_map(|run| {
                    values.iter().map(move |&v| {
                        let mut r = run.clone();
                        r.push((name.clone(), v));
                        r
                    })
                })
                .collect();
        }
        if let Some(random) = &self.random {
            if random.samples == 0 {
                return Err("random.samples must be at least 1".into());
            }
            for (name, u) in &random.ranges {
                Target::parse(name)?;
                if !(u.from.is_finite() && u.to.is_finite() && u.from <= u.to) {
                    return Err(format!(
                        "random {name}: from = {} and to = {} must be finite with from <= to",
                        u.from, u.to
                    ));
                }
            }
            let mut rng = GaussianNoise::new(random.seed);
            runs = runs
                .into_iter()
                .flat_map(|run| {
                    (0..random.samples)
                        .map(|_| {
                            let mut r = run.clone();
                            for (name, u) in &random.ranges {
                                r.push((name.clone(), u.from + (u.to - u.from) * rng.uniform()));
                            }
                            r
                        })
                        .collect::<Vec<_>>()
                })
                .collect();
        }
        Ok(runs)
    }
}

/// Where a named value goes.
#[derive(Clone, Debug, PartialEq)]
enum Target<'a> {
    Controller(&'a str),
    Plant(&'a str),
    /// Both FMUs' chain parameter.
    Model(&'a str),
    Imperfection(&'a str),
}

/// The imperfections a sweep may set.
pub const IMPERFECTIONS: [&str; 4] = [
    "measurement_noise",
    "torque_noise",
    "responsiveness",
    "delay",
];

impl<'a> Target<'a> {
    fn parse(name: &'a str) -> Result<Self, String> {
        let (scope, rest) = name.split_once('.').ok_or_else(|| {
            format!(
                "{name}: give the scope: controller.{name}, plant.{name}, model.{name} or \
                 imperfections.{name}"
            )
        })?;
        match scope {
            "controller" => Ok(Target::Controller(rest)),
            "plant" => Ok(Target::Plant(rest)),
            "model" => Ok(Target::Model(rest)),
            "imperfections" if IMPERFECTIONS.contains(&rest) => Ok(Target::Imperfection(rest)),
            "imperfections" => Err(format!(
                "{name}: unknown imperfection (known: {})",
                IMPERFECTIONS.join(", ")
            )),
            _ => Err(format!(
                "{name}: unknown scope `{scope}` (controller, plant, model, imperfections)"
            )),
        }
    }
}

/// One run's set-up: the controller and plant settings and the
/// imperfections, from the spec's fixed values and the run's swept ones.
#[derive(Clone, Debug)]
pub struct RunSetup<const N: usize> {
    /// The controller FMU's settings.
    pub controller: Settings<N>,
    /// The plant FMU's settings (initial state included).
    pub plant: PlantSettings<N>,
    /// Noise, motor and delay.
    pub imperfections: Imperfections,
}

/// FMU parameter names and values.
type Named = Vec<(String, f64)>;

/// FMU parameter values of a robot file, for the controller's and the
/// plant's tables.
fn file_values<const N: usize>(file: &Path) -> Result<(Named, Named), String> {
    let params = RobotFile::load(file)
        .and_then(|f| f.params::<N>())
        .map_err(|e| e.to_string())?;
    let chain = ChainParameters::from_params(&params)?;
    let number = |v: Value| match v {
        Value::Real(x) => x,
        Value::Integer(i) => i as f64,
        Value::Boolean(b) => f64::from(u8::from(b)),
    };
    let mut c = default_settings::<N>(eigenmpc::mpc::Variant::Curved);
    c.model = chain;
    let controller = controller::table::table::<N>()
        .start_values(&c, |_| true)
        .into_iter()
        .map(|(n, v)| (n, number(v)))
        .collect();
    let p = PlantSettings::<N> {
        model: chain,
        ..PlantSettings::default()
    };
    let plant = plant::table::table::<N>()
        .start_values(&p, |_| true)
        .into_iter()
        .map(|(n, v)| (n, number(v)))
        .collect();
    Ok((controller, plant))
}

impl<const N: usize> RunSetup<N> {
    /// The set-up of `spec` with the swept values `run`, each checked as
    /// the FMUs check them.
    pub fn new(spec: &Spec, run: &[(String, f64)]) -> Result<Self, String> {
        let (mut controller, mut plant) = match &spec.model {
            Some(file) => file_values::<N>(file)?,
            None => (vec![], vec![]),
        };
        let mut imperfections = Imperfections {
            seed: spec.noise_seed,
            ..Imperfections::default()
        };
        let base = base_values(N);
        let fixed = spec.fixed.iter().map(|(n, v)| (n.clone(), *v));
        for (name, value) in base.into_iter().chain(fixed).chain(run.iter().cloned()) {
            match Target::parse(&name)? {
                Target::Controller(n) => controller.push((n.to_string(), value)),
                Target::Plant(n) => plant.push((n.to_string(), value)),
                Target::Model(n) => {
                    controller.push((n.to_string(), value));
                    plant.push((n.to_string(), value));
                }
                Target::Imperfection(n) => match n {
                    "measurement_noise" => imperfections.measurement_noise = value,
                    "torque_noise" => imperfections.torque_noise = value,
                    "responsiveness" => imperfections.responsiveness = value,
                    _ => {
                        if !(value >= 0.0 && value.fract() == 0.0 && value <= 1e6) {
                            return Err(format!(
                                "{name} = {value}: a delay is a whole number of samples"
                            ));
                        }
                        imperfections.delay_samples = value as usize;
                    }
                },
            }
        }
        fn as_refs(v: &[(String, f64)]) -> Vec<(&str, f64)> {
            v.iter().map(|(n, x)| (n.as_str(), *x)).collect()
        }
        let controller = settings_from_named::<N>(&as_refs(&controller))
            .map_err(|e| format!("controller: {e}"))?;
        let plant =
            plant_settings_from_named::<N>(&as_refs(&plant)).map_err(|e| format!("plant: {e}"))?;
        imperfections.validate()?;
        Ok(Self {
            controller,
            plant,
            imperfections,
        })
    }
}

/// A checked run of any joint count, ready to go: the sizes were picked
/// once, by [`setups`].
pub trait SweepRun: Send + Sync {
    /// Runs the closed loop for `duration` seconds.
    fn run(&self, duration: f64) -> Result<Metrics, String>;
}

/// A [`RunSetup`] with the sizes its closed loop needs.
struct SizedRun<const N: usize, const S: usize, const NP: usize>(RunSetup<N>);

impl<const N: usize, const S: usize, const NP: usize> SweepRun for SizedRun<N, S, NP> {
    fn run(&self, duration: f64) -> Result<Metrics, String> {
        run::<N, S, NP>(&self.0, duration)
    }
}

/// The set-ups of `runs` (from [`Spec::runs`]), each checked before any
/// closed loop starts; an error names the run and its values.
pub fn setups(spec: &Spec, runs: &[Vec<(String, f64)>]) -> Result<Vec<Box<dyn SweepRun>>, String> {
    fn typed<const N: usize, const S: usize, const NP: usize>(
        spec: &Spec,
        runs: &[Vec<(String, f64)>],
    ) -> Result<Vec<Box<dyn SweepRun>>, String> {
        runs.iter()
            .enumerate()
            .map(|(i, run)| {
                RunSetup::<N>::new(spec, run)
                    .map(|s| Box::new(SizedRun::<N, S, NP>(s)) as Box<dyn SweepRun>)
                    .map_err(|e| {
                        let values: Vec<String> =
                            run.iter().map(|(n, v)| format!("{n} = {v}")).collect();
                        format!("run {i} ({}): {e}", values.join(", "))
                    })
            })
            .collect()
    }
    let n = spec.joint_count()?;
    eigenmpc::with_joint_count!(
        n,
        |N, S, NP| typed::<N, S, NP>(spec, runs),
        otherwise Err(eigenmpc::joints::unsupported(n))
    )
}

/// The figures of one run (one CSV row besides its parameters).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// The plant's energy entered the 5 % band for good at this time (s;
    /// None: never).
    pub time_to_band: Option<f64>,
    /// The band was reached and held at least over the last 5 s.
    pub success: bool,
    /// Plant energy minus `E_ref` at the end (J).
    #[serde(deserialize_with = "rows::number")]
    pub final_energy_error: f64,
    /// Mean plant energy over the last 5 s minus `E_ref`, relative.
    #[serde(deserialize_with = "rows::number")]
    pub mean_energy_error: f64,
    /// RMS applied torque over the last 5 s per joint (N m).
    #[serde(deserialize_with = "rows::numbers")]
    pub rms_torque: Vec<f64>,
    /// RMS distance of the last 5 s of the path to the plant's own
    /// eigenmode at `E_ref` (rad; None: no mode there).
    pub distance_to_mode: Option<f64>,
    /// Samples whose solve did not succeed.
    pub failed_solves: usize,
    /// Models the adaptation swapped in.
    pub model_updates: usize,
    /// Compute time per sample, median and p99 (s): the only columns that
    /// depend on the machine.
    #[serde(deserialize_with = "rows::pair")]
    pub solve_time: [f64; 2],
}

/// Runs one closed loop of `setup` for `duration` seconds (`S = 2 N`,
/// `NP` the chain's base parameters, as [`eigenmpc::with_joint_count`]
/// binds them).
pub fn run<const N: usize, const S: usize, const NP: usize>(
    setup: &RunSetup<N>,
    duration: f64,
) -> Result<Metrics, String> {
    let mut controller = setup.controller.build::<S>()?;
    let nominal: PlanarChainParams<N> = setup.controller.model.params();
    let mut adaptation = if setup.controller.adapt {
        Some(
            Adaptation::<N, S, NP>::new(&nominal, setup.controller.adapt_options())
                .map_err(|e| e.to_string())?,
        )
    } else {
        None
    };
    let plant = setup.plant.system()?;
    let p = &setup.plant;
    let z0 = SVector::<f64, S>::from_iterator(p.q0.iter().chain(p.qd0.iter()).copied());
    let out = run_imperfect(
        &mut controller,
        adaptation.as_mut(),
        &plant,
        &z0,
        duration,
        &setup.imperfections,
    )
    .map_err(|e| e.to_string())?;
    let e_ref = setup.controller.tuning.e_ref;
    // The plant's own mode at E_ref, in the family the controller follows.
    let mode = mode_and_chart::<_, N, S>(&plant, setup.controller.mode, e_ref, 9).ok();
    let path: Option<Vec<Vector<N>>> = mode.map(|(m, _)| m.path);
    let summary = summarise(&out.samples, e_ref, path.as_deref(), WINDOW);
    let (mean, _) = energy_tail(&out.samples, e_ref, WINDOW);
    Ok(Metrics {
        time_to_band: summary.time_to_5_percent,
        success: summary
            .time_to_5_percent
            .is_some_and(|t| t <= duration - WINDOW + 1e-9),
        final_energy_error: summary.final_energy_error,
        mean_energy_error: (mean - e_ref) / e_ref,
        rms_torque: summary.rms_torque.iter().copied().collect(),
        distance_to_mode: summary.rms_distance,
        failed_solves: summary.failures,
        model_updates: out.model_updates,
        solve_time: [summary.solve_time[0], summary.solve_time[2]],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_and_random_samples_expand_in_a_fixed_order() {
        let mut spec = Spec::default();
        spec.grid.insert(
            "controller.E_ref".into(),
            Axis::Range {
                from: 2.0,
                to: 6.0,
                count: 3,
            },
        );
        spec.grid
            .insert("controller.alpha".into(), Axis::List(vec![0.0, 1.0]));
        let runs = spec.runs().unwrap();
        assert_eq!(runs.len(), 6);
        // Byte order of the names: E_ref (slowest) before alpha.
        assert_eq!(
            runs[1],
            vec![
                ("controller.E_ref".to_string(), 2.0),
                ("controller.alpha".to_string(), 1.0)
            ]
        );
        assert_eq!(runs[5][0], ("controller.E_ref".to_string(), 6.0));
        spec.random = Some(RandomSample {
            samples: 2,
            seed: 7,
            ranges: [("plant.m[2]".to_string(), Uniform { from: 0.8, to: 1.2 })].into(),
        });
        let a = spec.runs().unwrap();
        assert_eq!(a.len(), 12);
        assert_eq!(a, spec.runs().unwrap(), "the same seed, the same sample");
        assert!(a.iter().all(|r| (0.8..=1.2).contains(&r[2].1)));
        assert_ne!(a[0][2].1, a[1][2].1);
    }

    #[test]
    fn bad_names_and_values_are_refused_naming_them() {
        for (name, value, needle) in [
            ("E_ref", 14.0, "give the scope"),
            ("robot.m[1]", 1.0, "unknown scope `robot`"),
            (
                "controller.E_rf",
                14.0,
                "E_rf is not a variable of EigenMPC",
            ),
            (
                "plant.m[3]",
                1.0,
                "m[3] is not a variable of DoublePendulum",
            ),
            (
                "controller.tau_max",
                0.0,
                "tau_max = 0 is below its minimum",
            ),
            ("imperfections.delay", 1.5, "whole number of samples"),
            ("imperfections.lag", 1.0, "unknown imperfection"),
            ("imperfections.responsiveness", 0.0, "responsiveness = 0"),
        ] {
            let spec = Spec::default();
            let e = RunSetup::<2>::new(&spec, &[(name.to_string(), value)]).unwrap_err();
            assert!(e.contains(needle), "{name}: {e}");
        }
        let spec = Spec {
            duration: 4.0,
            ..Spec::default()
        };
        assert!(spec.runs().unwrap_err().contains("more than the 5 s"));
    }

    #[test]
    fn model_values_reach_both_fmus() {
        let setup = RunSetup::<2>::new(
            &Spec::default(),
            &[
                ("model.m[2]".to_string(), 1.2),
                ("plant.q0[1]".to_string(), 0.3),
                ("controller.E_ref".to_string(), 10.0),
            ],
        )
        .unwrap();
        assert_eq!(setup.controller.model.mass[1], 1.2);
        assert_eq!(setup.plant.model.mass[1], 1.2);
        assert_eq!(setup.plant.q0[0], 0.3);
        assert_eq!(setup.controller.tuning.e_ref, 10.0);
    }
}
