//! A robot exported by `eigenmpc export`: one FMU binary serves every joint
//! count of the table (`eigenmpc::joints`) and both kinds, controller and
//! plant. What an instance is (kind, joints, name, the robot's parameters as
//! start values) is the archive's `resources/eigenmpc-export.json`
//! ([`ExportSpec`]); the binary builds its variable table from it, so the
//! archive's `modelDescription.xml` (written by the exporter from the same
//! spec) and the instance agree, GUID included. No compiler on the user's
//! machine: exporting a robot writes files, it builds nothing.

use crate::controller::ControllerFmu;
use crate::controller::precomputed::{FAMILY_FILE, PrecomputedFamily};
use crate::controller::settings::{ChartSource, Settings};
use crate::plant::PlantFmu;
use crate::plant::settings::PlantSettings;
pub use crate::products::{BINARY_NAME, Exported};
use crate::{controller, plant};
use eigenmpc::joints;
use fmi2_slave::{Context, Model, ModelDescription, ModelError, Values};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// The spec's file name inside `resources/`.
pub const SPEC_FILE: &str = "eigenmpc-export.json";

/// Which model an exported FMU is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// The EigenMPC controller (state in, torques out).
    Controller,
    /// The robot as a plant (torques in, state out).
    Plant,
}

/// What an exported FMU is: written by the exporter into `resources/`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExportSpec {
    /// Controller or plant.
    pub kind: Kind,
    /// Joints of the chain (a count of the joint-count table).
    pub joints: usize,
    /// `modelName` and `modelIdentifier` (the binary's file name too).
    pub model_name: String,
    /// One-line description.
    pub description: String,
    /// Start values by FMU variable name (`m[1]`, `E_ref`, ...), each
    /// checked as `fmi2Set*` would check it.
    pub start_values: BTreeMap<String, f64>,
}

impl ExportSpec {
    /// Reads `resources/eigenmpc-export.json`.
    pub fn load(resources: &Path) -> Result<Self, String> {
        let path = resources.join(SPEC_FILE);
        let text = std::fs::read_to_string(&path).map_err(|e| {
            format!(
                "{}: {e} (an exported robot's FMU needs its resources/ folder)",
                path.display()
            )
        })?;
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
    }

    fn pairs(&self) -> Vec<(&str, f64)> {
        self.start_values
            .iter()
            .map(|(k, v)| (k.as_str(), *v))
            .collect()
    }

    /// The controller settings of an `N`-joint spec.
    pub fn controller_settings<const N: usize>(&self) -> Result<Settings<N>, String> {
        controller::named::settings_from_named::<Exported, N>(&self.pairs())
    }

    /// The plant settings of an `N`-joint spec.
    pub fn plant_settings<const N: usize>(&self) -> Result<PlantSettings<N>, String> {
        plant::settings_from_named::<Exported, N>(&self.pairs())
    }

    /// The FMU's model description: the table of its kind and joint count
    /// with the spec's start values.
    pub fn description(&self) -> Result<ModelDescription, String> {
        let n = self.joints;
        eigenmpc::with_joint_count!(
            n,
            |N, S, NP| match self.kind {
                Kind::Controller => Ok(controller::description_with::<N>(
                    &self.model_name,
                    &self.description,
                    &self.controller_settings::<N>()?,
                )),
                Kind::Plant => Ok(plant::description_with::<N>(
                    &self.model_name,
                    &self.description,
                    &self.plant_settings::<N>()?,
                )),
            },
            otherwise Err(joints::unsupported(n))
        )
    }
}

/// The calls of a built model, object-safe: the joint count and kind are
/// chosen at `fmi2ExitInitializationMode`, from the resources.
trait Running: Send {
    fn do_step(
        &mut self,
        values: &mut Values,
        t: f64,
        h: f64,
        ctx: &Context,
    ) -> Result<(), ModelError>;
    fn save_state(&self) -> Result<Vec<u8>, ModelError>;
    fn restore_state(
        &mut self,
        state: &[u8],
        values: &Values,
        ctx: &Context,
    ) -> Result<(), ModelError>;
    fn update_tunables(&mut self, values: &mut Values, ctx: &Context) -> Result<(), ModelError>;
}

impl<M: Model> Running for M {
    fn do_step(
        &mut self,
        values: &mut Values,
        t: f64,
        h: f64,
        ctx: &Context,
    ) -> Result<(), ModelError> {
        Model::do_step(self, values, t, h, ctx)
    }
    fn save_state(&self) -> Result<Vec<u8>, ModelError> {
        Model::save_state(self)
    }
    fn restore_state(
        &mut self,
        state: &[u8],
        values: &Values,
        ctx: &Context,
    ) -> Result<(), ModelError> {
        Model::restore_state(self, state, values, ctx)
    }
    fn update_tunables(&mut self, values: &mut Values, ctx: &Context) -> Result<(), ModelError> {
        Model::update_tunables(self, values, ctx)
    }
}

/// The FMU model of every exported robot (the `eigenmpc-robot-fmu` binary):
/// the controller or plant of the resources' spec, for its joint count.
pub struct ExportedFmu {
    running: Box<dyn Running>,
}

fn spec_of(ctx: &Context) -> Result<ExportSpec, ModelError> {
    let dir = ctx.resources.ok_or_else(|| {
        ModelError::Error(
            "no fmuResourceLocation: an exported robot's FMU needs its resources/ folder".into(),
        )
    })?;
    ExportSpec::load(dir).map_err(ModelError::Error)
}

impl Model for ExportedFmu {
    /// Documentation only: the 2-joint controller with the library's
    /// defaults (an instance without its resources is refused).
    fn description() -> ModelDescription {
        controller::description::<Exported, 2>()
    }

    fn description_for(resources: Option<&Path>) -> Result<ModelDescription, String> {
        let dir = resources
            .ok_or("no fmuResourceLocation: an exported robot's FMU needs its resources/ folder")?;
        ExportSpec::load(dir)?.description()
    }

    fn initialize(values: &mut Values, ctx: &Context) -> Result<Self, ModelError> {
        let spec = spec_of(ctx)?;
        let n = spec.joints;
        let running: Box<dyn Running> = eigenmpc::with_joint_count!(
            n,
            |N, S, NP, NA| match spec.kind {
                Kind::Controller => {
                    let defaults = spec.controller_settings::<N>().map_err(ModelError::Error)?;
                    let family = precomputed_family::<N>(ctx);
                    Box::new(ControllerFmu::<Exported, N, S, NP, NA>::initialize_with(
                        values,
                        ctx,
                        defaults,
                        family.as_ref(),
                    )?)
                }
                Kind::Plant => Box::new(PlantFmu::<Exported, N, S>::initialize(values, ctx)?),
            },
            otherwise return Err(ModelError::Error(joints::unsupported(n)))
        );
        Ok(Self { running })
    }

    fn do_step(
        &mut self,
        values: &mut Values,
        t: f64,
        h: f64,
        ctx: &Context,
    ) -> Result<(), ModelError> {
        self.running.do_step(values, t, h, ctx)
    }

    fn save_state(&self) -> Result<Vec<u8>, ModelError> {
        self.running.save_state()
    }

    fn restore_state(
        &mut self,
        state: &[u8],
        values: &Values,
        ctx: &Context,
    ) -> Result<(), ModelError> {
        self.running.restore_state(state, values, ctx)
    }

    fn update_tunables(&mut self, values: &mut Values, ctx: &Context) -> Result<(), ModelError> {
        self.running.update_tunables(values, ctx)
    }
}

/// The mode family in `resources/` (None: there is none, or it does not
/// read, which is logged: the controller then computes its own).
fn precomputed_family<const N: usize>(ctx: &Context) -> Option<PrecomputedFamily<N>> {
    let path = ctx.resources?.join(FAMILY_FILE);
    if !path.exists() {
        return None;
    }
    let read = std::fs::read_to_string(&path)
        .map_err(|e| e.to_string())
        .and_then(|text| serde_json::from_str(&text).map_err(|e| e.to_string()));
    match read {
        Ok(family) => Some(family),
        Err(e) => {
            ctx.log.warning(&format!(
                "{}: {e}; the mode family is computed instead",
                path.display()
            ));
            None
        }
    }
}

/// The mode family of an exported controller `spec`, to ship in its
/// `resources/` ([`FAMILY_FILE`]): JSON, None when its reference needs none.
pub fn family_resource<const N: usize, const S: usize>(
    spec: &ExportSpec,
) -> Result<Option<String>, String> {
    let settings = spec.controller_settings::<N>()?;
    if settings.chart_source != ChartSource::Computed || !settings.variant.uses_chart() {
        return Ok(None);
    }
    let family = PrecomputedFamily::compute::<S>(&settings)?;
    serde_json::to_string(&family)
        .map(Some)
        .map_err(|e| e.to_string())
}

/// A number for the spec: Integer and enumeration values are integral,
/// Booleans 0 or 1 (as the C API's named values).
fn number(value: fmi2_slave::Value) -> f64 {
    match value {
        fmi2_slave::Value::Real(v) => v,
        fmi2_slave::Value::Integer(i) => i as f64,
        fmi2_slave::Value::Boolean(b) => f64::from(u8::from(b)),
    }
}

/// An FMU's `modelName` (and `modelIdentifier`) and one-line description.
#[derive(Clone, Debug, PartialEq)]
pub struct Named {
    /// `modelName` and `modelIdentifier`.
    pub model_name: String,
    /// `description`.
    pub description: String,
}

/// What the FMUs of an exported pair are called and say.
#[derive(Clone, Debug, PartialEq)]
pub struct PairNames {
    /// The controller FMU.
    pub controller: Named,
    /// The plant FMU.
    pub plant: Named,
}

impl PairNames {
    /// `<base>EigenMPC` and `<base>Plant` of an `joints`-joint robot from
    /// `source` (a file name), whose `family` (e.g. `in-phase`) the
    /// controller excites: the names `eigenmpc export` gives.
    pub fn of_robot(base: &str, source: &str, joints: usize, family: &str) -> Self {
        Self {
            controller: Named {
                model_name: format!("{base}EigenMPC"),
                description: format!(
                    "EigenMPC controller of the {joints}-joint robot {source}: joint angles and \
                     speeds in, joint torques out; excites its {family} eigenmode at E_ref"
                ),
            },
            plant: Named {
                model_name: format!("{base}Plant"),
                description: format!(
                    "The {joints}-joint robot {source} as a plant: joint torques in, joint \
                     angles, speeds and energy out; adaptive Dormand-Prince inside doStep"
                ),
            },
        }
    }
}

/// What an exported pair is made of: the robot, its reference and bounds.
pub struct RobotExport<'a, const N: usize> {
    /// The FMUs' names and descriptions.
    pub names: &'a PairNames,
    /// The robot (controller's model and plant).
    pub model: &'a eigenmpc::mechanics::PlanarChainParams<N>,
    /// `E_ref` (J).
    pub e_ref: f64,
    /// Unit eigenvector of the chart's family.
    pub eigenvector: &'a [f64; N],
    /// The chart at `e_ref`, per joint the coefficients of `s^0, s^1, ...`.
    pub chart: &'a [Vec<f64>; N],
    /// Torque bound `tau_max` (N m).
    pub tau_max: f64,
}

impl<const N: usize> RobotExport<'_, N> {
    /// The controller's and the plant's specs, every value checked against
    /// its variable as `fmi2Set*` would (a value out of range is refused
    /// here, naming it, not in the user's tool).
    pub fn specs(&self) -> Result<[ExportSpec; 2], String> {
        let mut controller: BTreeMap<String, f64> = controller::start_values::start_values::<N>(
            self.model,
            self.e_ref,
            self.eigenvector,
            self.chart,
        )?
        .into_iter()
        .map(|(name, value)| (name, number(value)))
        .collect();
        controller.insert("tau_max".into(), self.tau_max);
        // The reference follows E_ref along the mode family, as on the
        // shipped controllers; the family comes precomputed in resources/
        // ([`family_resource`]) and the chart at E_ref stays in c / chart
        // for chart_source = parameters.
        controller.insert(
            "chart_source".into(),
            f64::from(crate::enums::CHART_SOURCE.item(ChartSource::Computed)),
        );
        let chain = crate::chain::ChainParameters::from_params(self.model)?;
        let plant_settings = PlantSettings::<N> {
            model: chain,
            ..PlantSettings::default()
        };
        let plant: BTreeMap<String, f64> = plant::table::table::<N>()
            .start_values(&plant_settings, |r| {
                r.group == Some(crate::chain::MODEL_GROUP)
            })
            .into_iter()
            .map(|(name, value)| (name, number(value)))
            .collect();
        let specs = [
            ExportSpec {
                kind: Kind::Controller,
                joints: N,
                model_name: self.names.controller.model_name.clone(),
                description: self.names.controller.description.clone(),
                start_values: controller,
            },
            ExportSpec {
                kind: Kind::Plant,
                joints: N,
                model_name: self.names.plant.model_name.clone(),
                description: self.names.plant.description.clone(),
                start_values: plant,
            },
        ];
        for spec in &specs {
            spec.description()?;
        }
        Ok(specs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use eigenmpc::mechanics::PlanarChainParams;

    #[test]
    fn a_spec_round_trips_and_describes_its_robot() {
        let model = PlanarChainParams::<4>::point_masses([0.5; 4], [0.4; 4], 9.81);
        let chart: [Vec<f64>; 4] = std::array::from_fn(|_| vec![0.0, 0.5]);
        let names = PairNames::of_robot("Four", "four.yml", 4, "in-phase");
        let export = RobotExport {
            names: &names,
            model: &model,
            e_ref: 1.0,
            eigenvector: &[0.5; 4],
            chart: &chart,
            tau_max: 0.7,
        };
        let [controller, plant] = export.specs().unwrap();
        let text = serde_json::to_string(&controller).unwrap();
        assert_eq!(
            serde_json::from_str::<ExportSpec>(&text).unwrap(),
            controller
        );
        let d = controller.description().unwrap();
        assert_eq!(d.model_identifier, "FourEigenMPC");
        let start = |d: &ModelDescription, name: &str| {
            d.variables
                .iter()
                .find(|v| v.name == name)
                .and_then(|v| v.start)
                .unwrap_or_else(|| panic!("{name}"))
        };
        assert_eq!(start(&d, "tau_max"), fmi2_slave::Value::Real(0.7));
        assert_eq!(start(&d, "m[4]"), fmi2_slave::Value::Real(0.5));
        assert_eq!(start(&d, "l[3]"), fmi2_slave::Value::Real(0.4));
        let p = plant.description().unwrap();
        assert_eq!(p.model_identifier, "FourPlant");
        assert_eq!(start(&p, "m[4]"), fmi2_slave::Value::Real(0.5));
        assert!(p.variables.iter().any(|v| v.name == "q0[4]"));
        // Out of range is refused with the variable's name.
        let bad = RobotExport {
            tau_max: -1.0,
            ..export
        };
        assert!(bad.specs().unwrap_err().contains("tau_max"));
    }

    #[test]
    fn a_joint_count_outside_the_table_is_an_error() {
        let spec = ExportSpec {
            kind: Kind::Plant,
            joints: 9,
            model_name: "Nine".into(),
            description: String::new(),
            start_values: BTreeMap::new(),
        };
        assert!(spec.description().unwrap_err().contains("9 joints"));
        assert!(ExportedFmu::description_for(None).is_err());
    }
}
