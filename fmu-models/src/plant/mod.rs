//! A planar `N`-link chain (`eigenmpc::mechanics::PlanarChain`) as an FMI
//! 2.0 Co-Simulation model: joint torques in, joint angles, speeds and
//! energy out. `fmi2DoStep` integrates with the adaptive Dormand-Prince
//! 5(4) integrator carried across steps (step size and FSAL stage survive a
//! communication point; the stage is dropped when the torque changes), so
//! the result does not depend on the communication step size.
//!
//! - [`table`]: the variable table; [`settings`]: what it fills in;
//!   [`docs`]: the documentation page's introduction.

pub mod docs;
pub mod settings;
pub mod table;

use crate::units;
use eigenmpc::integrate::Dopri5;
use eigenmpc::mechanics::{PlanarChain, Vector, state_derivative, state_energy};
use fmi2_slave::table::{Element, Table};
use fmi2_slave::{Context, DefaultExperiment, Model, ModelDescription, ModelError, Values};
use nalgebra::SVector;
use settings::PlantSettings;
use std::marker::PhantomData;

/// Integrator steps one `fmi2DoStep` may take before it is discarded.
pub const MAX_STEPS_PER_CALL: usize = 100_000;

/// One plant FMU product: its name.
pub trait PlantProduct<const N: usize>: 'static {
    /// `modelName` and `modelIdentifier`.
    const MODEL_NAME: &'static str;
    /// One-line description.
    const DESCRIPTION: &'static str;
}

#[derive(Clone, Copy, Debug)]
struct Io<const N: usize> {
    tau: [u32; N],
    q: [u32; N],
    qd: [u32; N],
    energy: u32,
}

impl<const N: usize> Io<N> {
    fn new(t: &Table<PlantSettings<N>>) -> Result<Self, String> {
        let joints = |name| {
            t.joint_vrs::<N>(name)
                .ok_or_else(|| format!("no row {name}"))
        };
        Ok(Self {
            tau: joints("tau")?,
            q: joints("q")?,
            qd: joints("qd")?,
            energy: t.vr("energy", Element::default()).ok_or("no row energy")?,
        })
    }
}

/// The plant FMU model for `N` links (`NX = 2 N`).
pub struct PlantFmu<P, const N: usize, const NX: usize> {
    system: PlanarChain<N>,
    ode: Dopri5<SVector<f64, NX>>,
    /// Torque the integrator's cached derivative was computed with.
    tau: Vector<N>,
    io: Io<N>,
    product: PhantomData<fn() -> P>,
}

/// The model description of product `P`.
pub fn description<P: PlantProduct<N>, const N: usize>() -> ModelDescription {
    description_with(
        P::MODEL_NAME,
        P::DESCRIPTION,
        &PlantSettings::<N>::default(),
    )
}

/// The model description of an `N`-link plant FMU called `name` whose
/// start values are `defaults` (a product's, or an exported robot's).
pub fn description_with<const N: usize>(
    name: &str,
    text: &str,
    defaults: &PlantSettings<N>,
) -> ModelDescription {
    let t = table::table::<N>();
    let variables = t.variables(defaults);
    ModelDescription {
        model_name: name.into(),
        model_identifier: name.into(),
        description: text.into(),
        version: env!("CARGO_PKG_VERSION").into(),
        author: "EigenMPC project".into(),
        generation_tool: format!("fmi2-slave (EigenMPC) {}", env!("CARGO_PKG_VERSION")),
        can_handle_variable_communication_step_size: true,
        can_save_state: true,
        default_experiment: Some(DefaultExperiment {
            start_time: 0.0,
            stop_time: 10.0,
            step_size: 0.01,
            // The integrator's default relative tolerance (rtol's start).
            tolerance: Some(PlantSettings::<N>::default().tolerances.rtol),
        }),
        units: units::used_by(&variables),
        enumerations: t.enumerations(),
        variables,
    }
}

/// The plant settings of product `P` with the FMU parameters `(name, value)`
/// set over the defaults, each checked as `fmi2Set*` would check it (as
/// the controller's [`crate::controller::named::settings_from_named`]).
pub fn settings_from_named<P: PlantProduct<N>, const N: usize>(
    values: &[(&str, f64)],
) -> Result<PlantSettings<N>, String> {
    table::table::<N>().settings_from_named(
        &description::<P, N>(),
        PlantSettings::default(),
        values,
    )
}

impl<P: PlantProduct<N>, const N: usize, const NX: usize> Model for PlantFmu<P, N, NX> {
    fn description() -> ModelDescription {
        description::<P, N>()
    }

    fn initialize(values: &mut Values, ctx: &Context) -> Result<Self, ModelError> {
        let table = table::table::<N>();
        let io = Io::new(&table).map_err(ModelError::Error)?;
        let defaults = PlantSettings::<N>::default();
        let mut settings = defaults.clone();
        table.read(values, &mut settings, |_| true);
        // A master's tolerance (fmi2SetupExperiment with toleranceDefined)
        // sets the relative tolerance unless rtol itself was changed.
        if let Some(tolerance) = ctx.experiment.tolerance
            && settings.tolerances.rtol == defaults.tolerances.rtol
        {
            settings.tolerances.rtol = tolerance;
            ctx.log.event(&format!(
                "rtol = {tolerance} from fmi2SetupExperiment's tolerance (set the rtol parameter \
                 to choose another)"
            ));
        }
        let system = settings.system().map_err(ModelError::Error)?;
        let z0 = SVector::<f64, NX>::from_fn(|i, _| {
            if i < N {
                settings.q0[i]
            } else {
                settings.qd0[i - N]
            }
        });
        let mut ode = Dopri5::new(ctx.experiment.start_time, z0, settings.tolerances);
        // Bounded work per call (about 0.3 s): a 25 ms step takes tens.
        ode.max_steps = MAX_STEPS_PER_CALL;
        let model = Self {
            system,
            ode,
            tau: Vector::<N>::from_fn(|j, _| values.real(io.tau[j])),
            io,
            product: PhantomData,
        };
        model.write_outputs(values);
        Ok(model)
    }

    fn save_state(&self) -> Result<Vec<u8>, ModelError> {
        fmi2_slave::state::encode_model(&(&self.ode, &self.tau))
    }

    fn restore_state(
        &mut self,
        state: &[u8],
        _values: &Values,
        _ctx: &Context,
    ) -> Result<(), ModelError> {
        // The model was built from the same parameters: only the
        // integrator (time, state, step size, FSAL stage, counters) and
        // the torque of its cached stage move.
        let (ode, tau): (Dopri5<SVector<f64, NX>>, Vector<N>) =
            fmi2_slave::state::decode_model(state)?;
        if !(ode.time().is_finite() && ode.state().iter().all(|v| v.is_finite())) {
            return Err(ModelError::Error(
                "malformed plant state: non-finite time or state".into(),
            ));
        }
        self.ode = ode;
        self.tau = tau;
        Ok(())
    }

    fn do_step(
        &mut self,
        values: &mut Values,
        t: f64,
        h: f64,
        _ctx: &Context,
    ) -> Result<(), ModelError> {
        let tau = Vector::<N>::from_fn(|j, _| values.real(self.io.tau[j]));
        if tau != self.tau {
            // The cached first stage was evaluated with the old torque.
            let (t0, z) = (self.ode.time(), *self.ode.state());
            self.ode.reset(t0, z);
            self.tau = tau;
        }
        let system = &self.system;
        let result = self.ode.advance_to(
            |_, z: &SVector<f64, NX>| state_derivative::<PlanarChain<N>, N, NX>(system, z, &tau),
            t + h,
        );
        let result = result.map(|_| ()).map_err(|e| {
            format!(
                "integration failed: {e} (at most {MAX_STEPS_PER_CALL} integrator steps per \
                 fmi2DoStep: take shorter communication steps)"
            )
        });
        self.write_outputs(values);
        result.map_err(|message| ModelError::Discard {
            message,
            last_successful_time: self.ode.time(),
        })
    }
}

impl<P, const N: usize, const NX: usize> PlantFmu<P, N, NX> {
    fn write_outputs(&self, values: &mut Values) {
        let z = self.ode.state();
        for j in 0..N {
            values.set_real(self.io.q[j], z[j]);
            values.set_real(self.io.qd[j], z[N + j]);
        }
        values.set_real(
            self.io.energy,
            state_energy::<PlanarChain<N>, N, NX>(&self.system, z),
        );
    }

    /// Accepted integrator steps so far (diagnostics and tests).
    pub fn integrator_steps(&self) -> usize {
        self.ode.steps()
    }

    /// The chain being integrated.
    pub fn system(&self) -> &PlanarChain<N> {
        &self.system
    }
}
