//! `eigenmpc paper`: every figure of the paper's section V and its
//! commented-out hybrid experiment, regenerated from this project's engine,
//! with `report.md` putting each claim of the paper's text next to the
//! measured figure and a verdict.
//!
//! One table ([`RUNS`]) names every closed loop; the figures
//! ([`figures`]) and the claims ([`claims`]) look runs up by id.

pub mod claims;
pub mod figures;

use eigenmpc::mechanics::{DoublePendulum, PlanarChainParams, Vector};
use eigenmpc::modes::{Chart, Eigenmode, Family, linear_modes};
use eigenmpc::mpc::closed_loop::{Sample, Summary, mode_and_chart, run, summarise};
use eigenmpc::mpc::{Controller, MpcConfig, Reference, ReferenceError, Variant};
use nalgebra::SVector;

/// The model the cost's chart is computed for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ChartModel {
    /// The plant itself (the paper's pendulum, 1 kg, 1 m).
    Plant,
    /// The paper's hybrid experiment: `m2` 20 % higher than the plant's.
    HeavierM2,
}

impl ChartModel {
    /// The model as a double pendulum.
    pub fn system(self) -> DoublePendulum {
        match self {
            ChartModel::Plant => DoublePendulum::default(),
            ChartModel::HeavierM2 => DoublePendulum::new(PlanarChainParams::point_masses(
                [1.0, 1.2],
                [1.0, 1.0],
                9.81,
            ))
            .expect("a valid point-mass pendulum"),
        }
    }
}

/// One closed loop of the paper's section V (the paper's gains, `N = 80`,
/// `dt = 25 ms`, `|tau| <= 1 N m`, from rest at `q0`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunSpec {
    /// Name the figures and claims look the run up by.
    pub id: &'static str,
    /// Cost variant.
    pub variant: Variant,
    /// Mode family.
    pub family: Family,
    /// Reference energy (J).
    pub e_ref: f64,
    /// Start angles (rad); the start speeds are zero.
    pub q0: [f64; 2],
    /// Exploration gain `alpha`.
    pub alpha: f64,
    /// Torque-weight offset `beta`.
    pub beta: f64,
    /// The model the chart (curved, hybrid) is computed for.
    pub chart: ChartModel,
    /// Simulated time (s) of the full run.
    pub duration: f64,
}

const REST: [f64; 2] = [0.05, 0.05];
const LARGE: [f64; 2] = [-1.1, 1.1];

const fn straight(id: &'static str, family: Family, e_ref: f64, alpha: f64) -> RunSpec {
    RunSpec {
        id,
        variant: Variant::Straight,
        family,
        e_ref,
        q0: REST,
        alpha,
        beta: 0.1,
        chart: ChartModel::Plant,
        duration: 30.0,
    }
}

const fn hybrid(id: &'static str, variant: Variant, family: Family) -> RunSpec {
    RunSpec {
        id,
        variant,
        family,
        e_ref: 14.0,
        q0: REST,
        alpha: 0.01,
        beta: 0.1,
        chart: ChartModel::HeavierM2,
        duration: 60.0,
    }
}

/// The exploration gains of Fig. 2 (the paper does not list its values).
pub const FIG2_ALPHAS: [f64; 5] = [0.0, 0.05, 0.1, 0.2, 0.5];

/// Every closed loop the figures and claims use.
pub const RUNS: &[RunSpec] = &[
    // Fig. 2: straight, in-phase, 14 J, for several alpha (0.1 is Fig. 4's run).
    straight("fig2-alpha-0", Family::InPhase, 14.0, FIG2_ALPHAS[0]),
    straight("fig2-alpha-0.05", Family::InPhase, 14.0, FIG2_ALPHAS[1]),
    straight("fig4-straight", Family::InPhase, 14.0, FIG2_ALPHAS[2]),
    straight("fig2-alpha-0.2", Family::InPhase, 14.0, FIG2_ALPHAS[3]),
    straight("fig2-alpha-0.5", Family::InPhase, 14.0, FIG2_ALPHAS[4]),
    // Fig. 3: modes found by the straight variant.
    straight("fig3-in-phase-2", Family::InPhase, 2.0, 0.1),
    straight("fig3-in-phase-16", Family::InPhase, 16.0, 0.1),
    straight("fig3-anti-phase-2", Family::AntiPhase, 2.0, 0.1),
    straight("fig3-anti-phase-12", Family::AntiPhase, 12.0, 0.1),
    // The text: 12 J is the highest anti-phase energy with a line-shaped result.
    straight("anti-phase-14", Family::AntiPhase, 14.0, 0.1),
    // Fig. 5 (Fig. 4 is in the alpha list).
    RunSpec {
        variant: Variant::Curved,
        id: "fig5-curved",
        ..straight("", Family::InPhase, 14.0, 0.1)
    },
    // Fig. 6: from (-1.1, 1.1).
    RunSpec {
        q0: LARGE,
        ..straight("fig6-straight", Family::InPhase, 14.0, 0.1)
    },
    RunSpec {
        q0: LARGE,
        variant: Variant::Curved,
        ..straight("fig6-curved", Family::InPhase, 14.0, 0.1)
    },
    // The hybrid experiment: the chart of a pendulum with m2 +20 %.
    hybrid("hybrid-in-phase", Variant::Hybrid, Family::InPhase),
    hybrid("curved-wrong-in-phase", Variant::Curved, Family::InPhase),
    hybrid("hybrid-anti-phase", Variant::Hybrid, Family::AntiPhase),
    hybrid(
        "curved-wrong-anti-phase",
        Variant::Curved,
        Family::AntiPhase,
    ),
];

/// Simulated time of every run in the reduced (`--quick`) variant (s).
pub const QUICK_DURATION: f64 = 3.0;

/// A true eigenmode and its degree-9 chart.
pub struct ModeEntry {
    /// Which model, family and energy.
    pub key: ModeKey,
    /// The brake orbit.
    pub mode: Eigenmode<2>,
    /// Its chart (degree 9, as the paper's curved cost).
    pub chart: Chart<2>,
}

/// Which eigenmode: model, family, energy (J).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModeKey {
    /// The model.
    pub model: ChartModel,
    /// The family.
    pub family: Family,
    /// The energy (J).
    pub energy: f64,
}

/// The eigenmodes the runs, figures and claims need: the plant's at every
/// run's `E_ref` (the distance metric), each chart model's (the cost).
pub fn mode_keys() -> Vec<ModeKey> {
    let mut keys: Vec<ModeKey> = vec![];
    let mut add = |k: ModeKey| {
        if !keys.contains(&k) {
            keys.push(k);
        }
    };
    for r in RUNS {
        add(ModeKey {
            model: ChartModel::Plant,
            family: r.family,
            energy: r.e_ref,
        });
        add(ModeKey {
            model: r.chart,
            family: r.family,
            energy: r.e_ref,
        });
    }
    keys
}

/// Computes one eigenmode and its chart.
pub fn compute_mode(key: ModeKey) -> Result<ModeEntry, String> {
    let (mode, chart) =
        mode_and_chart::<_, 2, 4>(&key.model.system(), key.family.index(), key.energy, 9).map_err(
            |e| {
                format!(
                    "{} eigenmode at {} J ({:?}): {e}",
                    key.family, key.energy, key.model
                )
            },
        )?;
    Ok(ModeEntry { key, mode, chart })
}

/// All eigenmodes, looked up by key.
pub struct Modes(pub Vec<ModeEntry>);

impl Modes {
    /// The entry of `model`, `family` at `energy`.
    pub fn get(&self, model: ChartModel, family: Family, energy: f64) -> &ModeEntry {
        self.0
            .iter()
            .find(|m| m.key.model == model && m.key.family == family && m.key.energy == energy)
            .expect("every mode a run needs is in mode_keys()")
    }

    /// The plant's eigenmode for a run.
    pub fn plant(&self, spec: &RunSpec) -> &ModeEntry {
        self.get(ChartModel::Plant, spec.family, spec.e_ref)
    }
}

/// A finished closed loop with the figures the claims compare.
pub struct RunResult {
    /// What was run.
    pub spec: RunSpec,
    /// Every sample.
    pub trace: Vec<Sample<2, 4>>,
    /// Summary against the plant's true eigenmode at `E_ref` (last 5 s).
    pub summary: Summary<2>,
    /// RMS distance of the last 5 s to the line through the equilibrium
    /// along the linear eigenvector (rad).
    pub line_distance: f64,
    /// RMS of the torque norm over the first 5 s (N m).
    pub early_torque: f64,
    /// First time the energy reaches 25 % of `E_ref` (s).
    pub time_to_quarter: Option<f64>,
    /// Mean controller time per sample (s).
    pub mean_solve: f64,
}

/// The unit linear eigenvector of the plant's `family`.
pub fn eigenvector(family: Family) -> Vector<2> {
    linear_modes(&DoublePendulum::default()).expect("the paper's pendulum has linear modes")
        [family.index()]
    .eigenvector
}

/// Distance of `q` to the line through the origin along the unit vector `e`.
pub fn distance_to_line(q: &Vector<2>, e: &Vector<2>) -> f64 {
    (q - e * q.dot(e)).norm()
}

/// RMS over `path` of the distance to the line along `e`.
pub fn rms_line_distance(path: impl Iterator<Item = Vector<2>>, e: &Vector<2>) -> f64 {
    let (sum, n) = path.fold((0.0, 0usize), |(s, n), q| {
        (s + distance_to_line(&q, e).powi(2), n + 1)
    });
    (sum / n.max(1) as f64).sqrt()
}

/// The samples of the last `window` seconds.
pub fn tail(trace: &[Sample<2, 4>], window: f64) -> impl Iterator<Item = &Sample<2, 4>> {
    let t_end = trace.last().map_or(0.0, |s| s.time);
    trace.iter().filter(move |s| s.time > t_end - window + 1e-9)
}

/// Runs one closed loop for `duration` seconds.
pub fn run_one(spec: &RunSpec, modes: &Modes, duration: f64) -> Result<RunResult, String> {
    let plant = DoublePendulum::default();
    let mut config = MpcConfig::paper(spec.variant);
    config.cost.e_ref = spec.e_ref;
    config.cost.alpha = spec.alpha;
    config.cost.beta = spec.beta;
    // The paper's residual r_E = E_ref - E: its Fig. 3 runs are at 2 and
    // 12 J (from 14 J up the default scale gives the same numbers, bit for bit).
    config.cost.energy_scale = 0.0;
    let reference = Reference::of::<ReferenceError>(
        spec.variant,
        || Ok(eigenvector(spec.family)),
        || Ok(modes.get(spec.chart, spec.family, spec.e_ref).chart.clone()),
    )
    .map_err(|e| format!("{}: {e}", spec.id))?;
    let fail = |e: String| format!("{}: {e}", spec.id);
    let mut controller =
        Controller::<_, 2, 4>::new(plant, config, reference).map_err(|e| fail(e.to_string()))?;
    let z0 = SVector::<f64, 4>::new(spec.q0[0], spec.q0[1], 0.0, 0.0);
    let trace = run(&mut controller, &plant, &z0, duration).map_err(|e| fail(e.to_string()))?;
    let summary = summarise(&trace, spec.e_ref, Some(&modes.plant(spec).mode.path), 5.0);
    let e = eigenvector(spec.family);
    let line_distance = rms_line_distance(
        tail(&trace, 5.0).map(|s| s.state.fixed_rows::<2>(0).into_owned()),
        &e,
    );
    let early: Vec<f64> = trace
        .iter()
        .filter(|s| s.time < 5.0 - 1e-9)
        .map(|s| s.tau.norm_squared())
        .collect();
    let early_torque = (early.iter().sum::<f64>() / early.len().max(1) as f64).sqrt();
    let time_to_quarter = trace
        .iter()
        .find(|s| s.energy >= 0.25 * spec.e_ref)
        .map(|s| s.time);
    let mean_solve = trace.iter().map(|s| s.solve_time).sum::<f64>() / trace.len().max(1) as f64;
    Ok(RunResult {
        spec: *spec,
        trace,
        summary,
        line_distance,
        early_torque,
        time_to_quarter,
        mean_solve,
    })
}

/// Every run's result, looked up by id.
pub struct Runs(pub Vec<RunResult>);

impl Runs {
    /// The run named `id` (one of [`RUNS`]).
    pub fn get(&self, id: &str) -> &RunResult {
        self.0
            .iter()
            .find(|r| r.spec.id == id)
            .unwrap_or_else(|| panic!("run {id} is not in RUNS"))
    }

    /// Fig. 2's runs (straight, in-phase, 14 J from rest), in the order of
    /// [`FIG2_ALPHAS`].
    pub fn fig2(&self) -> Vec<&RunResult> {
        FIG2_ALPHAS
            .iter()
            .map(|&a| {
                self.0
                    .iter()
                    .find(|r| {
                        r.spec.variant == Variant::Straight
                            && r.spec.family == Family::InPhase
                            && r.spec.e_ref == 14.0
                            && r.spec.q0 == REST
                            && r.spec.alpha == a
                    })
                    .expect("every Fig. 2 alpha has a run")
            })
            .collect()
    }
}

/// Whether the output is the full reproduction or the reduced check.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Extent {
    /// Every run for its full duration.
    Full,
    /// Every run for [`QUICK_DURATION`]: the files and the report's lines
    /// are all there, the verdicts are about 3 s runs.
    Quick,
}

impl Extent {
    /// The simulated time of `spec` under this extent.
    pub fn duration(self, spec: &RunSpec) -> f64 {
        match self {
            Extent::Full => spec.duration,
            Extent::Quick => QUICK_DURATION.min(spec.duration),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_unique_and_every_mode_is_listed() {
        for (i, r) in RUNS.iter().enumerate() {
            assert!(!r.id.is_empty());
            assert!(RUNS[..i].iter().all(|o| o.id != r.id), "{} twice", r.id);
        }
        let keys = mode_keys();
        for r in RUNS {
            assert!(
                keys.iter()
                    .any(|k| k.model == r.chart && k.family == r.family && k.energy == r.e_ref)
            );
        }
    }

    #[test]
    fn line_distance_is_the_perpendicular_part() {
        let e = Vector::<2>::new(0.6, 0.8);
        let q = Vector::<2>::new(0.8, -0.6) * 0.3 + e * 2.0;
        assert!((distance_to_line(&q, &e) - 0.3).abs() < 1e-12);
    }
}
