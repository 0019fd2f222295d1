//! The robustness report (`eigenmpc robustness`), in the style of the
//! published robustness benchmarks of double-pendulum controllers: one
//! controller configuration (the controller FMU's, on a nominal model)
//! against plants and set-ups that differ from it in one thing at a time:
//! each model parameter, measurement noise, torque noise, a sluggish motor,
//! measurement delay. Per run a success flag (the plant's true energy
//! reaches the 5 % band around `E_ref` and stays in it, at least over the
//! last 5 s), the energy error and the
//! torque; per category the share of runs that succeed; each run with and
//! without online adaptation.
//!
//! - this file: the cases and one closed loop per case;
//! - [`report`]: the Markdown table, the CSV and the plot.

pub mod report;

use eigenmpc::adapt::Adaptation;
use eigenmpc::mechanics::{PlanarChain, PlanarChainParams};
use eigenmpc::mpc::Variant;
use eigenmpc::mpc::closed_loop::{energy_tail, summarise};
use eigenmpc::robustness::{Imperfections, run_imperfect};
use eigenmpc_fmu_models::chain::ChainParameters;
use eigenmpc_fmu_models::controller::ControllerProduct;
use eigenmpc_fmu_models::controller::settings::{Settings, StateEstimator};
use eigenmpc_fmu_models::products::EigenMpc2;
use nalgebra::SVector;

/// What one case changes against the nominal set-up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Perturbation {
    /// Link `j`'s mass times a factor (its inertia about the COM kept).
    Mass(usize, f64),
    /// Link `j`'s centre-of-mass distance times a factor.
    CentreOfMass(usize, f64),
    /// Link `j`'s inertia about its joint times a factor `>= 1` (inertia
    /// added about the COM: a lighter one at the same mass and COM does
    /// not exist for a point mass).
    Inertia(usize, f64),
    /// Viscous friction on both joints (N m s/rad), added.
    Damping(f64),
    /// Coulomb friction on both joints (N m), added.
    Coulomb(f64),
    /// Rotor inertia on both joints (kg m^2), added.
    RotorInertia(f64),
    /// Measurement noise (rad and rad/s standard deviation).
    MeasurementNoise(f64),
    /// Torque noise (N m standard deviation, per sample and joint).
    TorqueNoise(f64),
    /// Motor responsiveness `a` in (0, 1].
    Responsiveness(f64),
    /// Measurement delay (samples).
    Delay(usize),
}

/// One run of the sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// Category (`mass`, `measurement noise`, ...): the unit of the score.
    pub category: &'static str,
    /// What is varied (`m[1]`, `b[j]`, `sigma`).
    pub parameter: String,
    /// The value on the report's axis (a factor for relative parameters).
    pub value: f64,
    /// Unit of `value` (`x nominal`, `N m s/rad`, `s`).
    pub unit: &'static str,
    /// The change.
    pub perturbation: Perturbation,
}

/// The categories in report order.
pub const CATEGORIES: [&str; 10] = [
    "mass",
    "centre of mass",
    "inertia",
    "damping",
    "Coulomb friction",
    "rotor inertia",
    "measurement noise",
    "torque noise",
    "motor responsiveness",
    "measurement delay",
];

/// The default sweep: each model parameter -50 % .. +50 % of the nominal
/// (inertia +6.25 % .. +50 %), friction and rotor inertia added 0.01 ..
/// 0.2, noise 0.01 .. 0.2, responsiveness 0.9 .. 0.1, delay 1 .. 8 samples.
pub fn default_cases(sample_period: f64) -> Vec<Case> {
    let factors = [0.5, 0.625, 0.75, 0.875, 1.125, 1.25, 1.375, 1.5];
    let levels = [0.01, 0.02, 0.05, 0.1, 0.2];
    let mut cases = vec![];
    let per_link = |cases: &mut Vec<Case>,
                    category,
                    name: &str,
                    values: &[f64],
                    make: fn(usize, f64) -> Perturbation| {
        for j in 0..2 {
            for &f in values {
                cases.push(Case {
                    category,
                    parameter: format!("{name}[{}]", j + 1),
                    value: f,
                    unit: "x nominal",
                    perturbation: make(j, f),
                });
            }
        }
    };
    per_link(&mut cases, "mass", "m", &factors, Perturbation::Mass);
    per_link(
        &mut cases,
        "centre of mass",
        "r",
        &factors,
        Perturbation::CentreOfMass,
    );
    per_link(
        &mut cases,
        "inertia",
        "I",
        &[1.0625, 1.125, 1.25, 1.375, 1.5],
        Perturbation::Inertia,
    );
    let mut both =
        |category, parameter: &str, unit, values: &[f64], make: fn(f64) -> Perturbation| {
            for &v in values {
                cases.push(Case {
                    category,
                    parameter: parameter.to_string(),
                    value: v,
                    unit,
                    perturbation: make(v),
                });
            }
        };
    both(
        "damping",
        "b[j]",
        "N m s/rad",
        &levels,
        Perturbation::Damping,
    );
    both(
        "Coulomb friction",
        "cf[j]",
        "N m",
        &levels,
        Perturbation::Coulomb,
    );
    both(
        "rotor inertia",
        "Ir[j]",
        "kg m^2",
        &levels,
        Perturbation::RotorInertia,
    );
    both(
        "measurement noise",
        "sigma",
        "rad, rad/s",
        &levels,
        Perturbation::MeasurementNoise,
    );
    both(
        "torque noise",
        "sigma",
        "N m",
        &levels,
        Perturbation::TorqueNoise,
    );
    both(
        "motor responsiveness",
        "a",
        "",
        &[0.9, 0.75, 0.5, 0.25, 0.1],
        Perturbation::Responsiveness,
    );
    for samples in [1usize, 2, 4, 8] {
        cases.push(Case {
            category: "measurement delay",
            parameter: "delay".into(),
            value: samples as f64 * sample_period,
            unit: "s",
            perturbation: Perturbation::Delay(samples),
        });
    }
    cases
}

/// The plant and the set-up of a case around the nominal model.
pub fn plant_and_imperfections(
    nominal: &PlanarChainParams<2>,
    perturbation: Perturbation,
    seed: u64,
) -> (PlanarChainParams<2>, Imperfections) {
    let mut p = *nominal;
    let mut imperfections = Imperfections {
        seed,
        ..Imperfections::default()
    };
    match perturbation {
        Perturbation::Mass(j, f) => p.links[j].mass *= f,
        Perturbation::CentreOfMass(j, f) => p.links[j].com *= f,
        Perturbation::Inertia(j, f) => {
            p.links[j].inertia += (f - 1.0) * p.links[j].inertia_about_joint();
        }
        Perturbation::Damping(b) => p.joints.iter_mut().for_each(|j| j.viscous += b),
        Perturbation::Coulomb(c) => p.joints.iter_mut().for_each(|j| j.coulomb += c),
        Perturbation::RotorInertia(i) => p.joints.iter_mut().for_each(|j| j.rotor_inertia += i),
        Perturbation::MeasurementNoise(s) => imperfections.measurement_noise = s,
        Perturbation::TorqueNoise(s) => imperfections.torque_noise = s,
        Perturbation::Responsiveness(a) => imperfections.responsiveness = a,
        Perturbation::Delay(n) => imperfections.delay_samples = n,
    }
    (p, imperfections)
}

/// The controller configuration every case runs.
#[derive(Clone, Debug)]
pub struct Setup {
    /// The controller FMU's settings (model = the nominal robot).
    pub settings: Settings<2>,
    /// Initial state of every run.
    pub z0: SVector<f64, 4>,
    /// Simulated time of every run (s).
    pub duration: f64,
    /// The controller filters the measurements with its extended Kalman
    /// filter, configured with each case's measurement noise (at least
    /// [`EKF_NOISE_FLOOR`]).
    pub ekf: bool,
}

/// Noise level the filter assumes for a clean sensor (rad, rad/s).
pub const EKF_NOISE_FLOOR: f64 = 0.005;

impl Setup {
    /// The controller FMU's default controller (curved, computed family,
    /// paper tuning) on `nominal` at `e_ref` with `tau_max`.
    pub fn new(
        nominal: &PlanarChainParams<2>,
        e_ref: f64,
        tau_max: f64,
        duration: f64,
    ) -> Result<Self, String> {
        let mut settings = EigenMpc2::settings(Variant::Curved);
        settings.model = ChainParameters::from_params(nominal)?;
        settings.tuning.e_ref = e_ref;
        settings.tau_max = tau_max;
        Ok(Self {
            settings,
            z0: SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0),
            duration,
            ekf: false,
        })
    }
}

/// What one run gave.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    /// The plant's energy reached the 5 % band and stayed in it, at least
    /// over the last 5 s that are scored.
    pub success: bool,
    /// When it entered the band for good (s).
    pub time_to_band: Option<f64>,
    /// Mean plant energy over the last 5 s minus `E_ref`, relative.
    pub energy_error: f64,
    /// RMS applied torque over the last 5 s, per joint (N m).
    pub rms_torque: [f64; 2],
    /// Samples whose solve did not succeed.
    pub failed_solves: usize,
    /// Models the adaptation swapped in.
    pub model_updates: usize,
}

/// Runs one case, with or without adaptation (synchronous: the numbers do
/// not depend on the machine). A case whose plant or controller cannot be
/// built, or whose integration fails, is an error.
pub fn run_case(setup: &Setup, case: &Case, seed: u64, adapt: bool) -> Result<Outcome, String> {
    let nominal = setup.settings.model.params();
    let (plant, imperfections) = plant_and_imperfections(&nominal, case.perturbation, seed);
    let plant = PlanarChain::new(plant).map_err(|e| format!("{}: {e}", case.parameter))?;
    let mut settings = setup.settings.clone();
    settings.adapt = adapt;
    if setup.ekf {
        // The filter is told the sensor's noise (a floor for clean ones).
        settings.state_estimator = StateEstimator::Ekf;
        let s = imperfections.measurement_noise.max(EKF_NOISE_FLOOR);
        settings.noise.angle_noise = s;
        settings.noise.speed_noise = s;
    }
    let mut controller = settings.build::<4>()?;
    let mut adaptation = if adapt {
        Some(
            Adaptation::<2, 4, 11>::new(&nominal, settings.adapt_options())
                .map_err(|e| e.to_string())?,
        )
    } else {
        None
    };
    let run = run_imperfect(
        &mut controller,
        adaptation.as_mut(),
        &plant,
        &setup.z0,
        setup.duration,
        &imperfections,
    )
    .map_err(|e| format!("{} = {}: {e}", case.parameter, case.value))?;
    let e_ref = settings.tuning.e_ref;
    let summary = summarise(&run.samples, e_ref, None, 5.0);
    let (mean, _) = energy_tail(&run.samples, e_ref, 5.0);
    Ok(Outcome {
        success: summary
            .time_to_5_percent
            .is_some_and(|t| t <= setup.duration - 5.0 + 1e-9),
        time_to_band: summary.time_to_5_percent,
        energy_error: (mean - e_ref) / e_ref,
        rms_torque: [summary.rms_torque[0], summary.rms_torque[1]],
        failed_solves: summary.failures,
        model_updates: run.model_updates,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cases_cover_every_category_and_perturb_one_thing() {
        let cases = default_cases(0.025);
        for c in CATEGORIES {
            assert!(cases.iter().any(|k| k.category == c), "{c}");
        }
        assert!(cases.iter().all(|k| CATEGORIES.contains(&k.category)));
        let nominal = PlanarChainParams::<2>::default();
        let (p, i) = plant_and_imperfections(&nominal, Perturbation::Mass(1, 1.5), 3);
        assert_eq!(p.links[1].mass, 1.5);
        assert_eq!(p.links[0], nominal.links[0]);
        assert_eq!(
            i,
            Imperfections {
                seed: 3,
                ..Imperfections::default()
            }
        );
        let (p, _) = plant_and_imperfections(&nominal, Perturbation::Inertia(0, 1.25), 3);
        assert!((p.links[0].inertia_about_joint() - 1.25).abs() < 1e-12);
        let (p, i) = plant_and_imperfections(&nominal, Perturbation::Delay(2), 3);
        assert_eq!((p, i.delay_samples), (nominal, 2));
    }
}
