//! # DoublePendulum FMU
//!
//! The paper's double pendulum (section V; `eigenmpc::mechanics::DoublePendulum`)
//! as an FMI 2.0 Co-Simulation FMU: joint torques in, joint angles, speeds
//! and energy out. `fmi2DoStep` integrates with the adaptive Dormand-Prince
//! 5(4) integrator carried across steps (step size and FSAL stage survive a
//! communication point; the stage is dropped when the torque changes), so
//! the result does not depend on the communication step size.

use eigenmpc::integrate::{Dopri5, Tolerances};
use eigenmpc::mechanics::{
    DoublePendulum, PlanarChainParams, Vector, pack_state, state_derivative, state_energy,
    unpack_state,
};
use fmi2_slave::{
    Context, DefaultExperiment, Model, ModelDescription, ModelError, Unit, Value, Values, Variable,
};
use nalgebra::SVector;

/// Value reference of input `tau[1]` (N.m).
pub const VR_TAU1: u32 = 0;
/// Value reference of input `tau[2]` (N.m).
pub const VR_TAU2: u32 = 1;
/// Value reference of output `q[1]` (rad).
pub const VR_Q1: u32 = 2;
/// Value reference of output `q[2]` (rad).
pub const VR_Q2: u32 = 3;
/// Value reference of output `qd[1]` (rad/s).
pub const VR_QD1: u32 = 4;
/// Value reference of output `qd[2]` (rad/s).
pub const VR_QD2: u32 = 5;
/// Value reference of output `energy` (J).
pub const VR_ENERGY: u32 = 6;
/// Value reference of parameter `m[1]` (kg).
pub const VR_M1: u32 = 7;
/// Value reference of parameter `m[2]` (kg).
pub const VR_M2: u32 = 8;
/// Value reference of parameter `l[1]` (m).
pub const VR_L1: u32 = 9;
/// Value reference of parameter `l[2]` (m).
pub const VR_L2: u32 = 10;
/// Value reference of parameter `g` (m/s2).
pub const VR_G: u32 = 11;
/// Value reference of parameter `damping[1]` (N.m.s/rad).
pub const VR_DAMPING1: u32 = 12;
/// Value reference of parameter `damping[2]` (N.m.s/rad).
pub const VR_DAMPING2: u32 = 13;
/// Value reference of parameter `q0[1]` (rad).
pub const VR_Q0_1: u32 = 14;
/// Value reference of parameter `q0[2]` (rad).
pub const VR_Q0_2: u32 = 15;
/// Value reference of parameter `qd0[1]` (rad/s).
pub const VR_QD0_1: u32 = 16;
/// Value reference of parameter `qd0[2]` (rad/s).
pub const VR_QD0_2: u32 = 17;
/// Value reference of parameter `rtol` (relative tolerance of the integrator).
pub const VR_RTOL: u32 = 18;
/// Value reference of parameter `atol` (absolute tolerance of the integrator).
pub const VR_ATOL: u32 = 19;

/// Introduction of the FMU's documentation page.
pub const DOCUMENTATION_HTML: &str = "<p>The planar double pendulum of the EigenMPC paper \
(section V): point masses <code>m[j]</code> at the tips of massless links <code>l[j]</code>, \
<code>q[1]</code> the absolute angle of the first link from the downward vertical, \
<code>q[2]</code> the angle of the second link relative to the first, gravity <code>g</code> \
and viscous joint damping. The inputs are the joint torques <code>tau[j]</code>, held \
constant over a communication step. <code>fmi2DoStep</code> integrates with an adaptive \
Dormand-Prince 5(4) method (tolerances <code>rtol</code>, <code>atol</code>), so the result \
does not depend on the communication step size; <code>energy</code> is the total mechanical \
energy (zero at rest hanging down).</p>";

type State = SVector<f64, 4>;

/// The DoublePendulum FMU model.
pub struct DoublePendulumFmu {
    system: DoublePendulum,
    ode: Dopri5<State>,
    /// Torque the integrator's cached derivative was computed with.
    tau: Vector<2>,
}

fn units() -> Vec<Unit> {
    vec![
        Unit::new("rad", 0, 0, 0, 1),
        Unit::new("rad/s", 0, 0, -1, 1),
        Unit::new("N.m", 1, 2, -2, 0),
        Unit::new("J", 1, 2, -2, 0),
        Unit::new("kg", 1, 0, 0, 0),
        Unit::new("m", 0, 1, 0, 0),
        Unit::new("m/s2", 0, 1, -2, 0),
        Unit::new("N.m.s/rad", 1, 2, -1, -1),
    ]
}

impl Model for DoublePendulumFmu {
    fn description() -> ModelDescription {
        let defaults = PlanarChainParams::<2>::default();
        let tol = Tolerances::default();
        let r = Value::Real;
        let mut variables = vec![];
        for (j, vr) in [(1, VR_TAU1), (2, VR_TAU2)] {
            variables.push(
                Variable::real(format!("tau[{j}]"), vr)
                    .input(r(0.0))
                    .unit("N.m")
                    .describe(format!(
                        "Torque at joint {j}, held over the communication step"
                    )),
            );
        }
        for (j, vr) in [(1, VR_Q1), (2, VR_Q2)] {
            let q0 = format!("q0[{j}]");
            let what = if j == 1 {
                "Angle of link 1 from the downward vertical"
            } else {
                "Angle of link 2 relative to link 1"
            };
            variables.push(
                Variable::real(format!("q[{j}]"), vr)
                    .output()
                    .unit("rad")
                    .describe(what)
                    .depends_on(&[])
                    .initially_depends_on(&[&q0]),
            );
        }
        for (j, vr) in [(1, VR_QD1), (2, VR_QD2)] {
            let qd0 = format!("qd0[{j}]");
            variables.push(
                Variable::real(format!("qd[{j}]"), vr)
                    .output()
                    .unit("rad/s")
                    .describe(format!("Speed of joint {j}"))
                    .depends_on(&[])
                    .initially_depends_on(&[&qd0]),
            );
        }
        variables.push(
            Variable::real("energy", VR_ENERGY)
                .output()
                .unit("J")
                .describe("Total mechanical energy, zero at rest hanging down")
                .depends_on(&[])
                .initially_depends_on(&[
                    "m[1]", "m[2]", "l[1]", "l[2]", "g", "q0[1]", "q0[2]", "qd0[1]", "qd0[2]",
                ]),
        );
        for (j, vr) in [(1, VR_M1), (2, VR_M2)] {
            variables.push(
                Variable::real(format!("m[{j}]"), vr)
                    .parameter(r(defaults.links[j - 1].mass))
                    .unit("kg")
                    .min(1e-6)
                    .max(1e6)
                    .describe(format!("Point mass at the tip of link {j}")),
            );
        }
        for (j, vr) in [(1, VR_L1), (2, VR_L2)] {
            variables.push(
                Variable::real(format!("l[{j}]"), vr)
                    .parameter(r(defaults.links[j - 1].length))
                    .unit("m")
                    .min(1e-6)
                    .max(1e3)
                    .describe(format!("Length of link {j}")),
            );
        }
        variables.push(
            Variable::real("g", VR_G)
                .parameter(r(defaults.gravity))
                .unit("m/s2")
                .min(1e-6)
                .max(1e3)
                .describe("Gravitational acceleration (along -y)"),
        );
        for (j, vr) in [(1, VR_DAMPING1), (2, VR_DAMPING2)] {
            variables.push(
                Variable::real(format!("damping[{j}]"), vr)
                    .parameter(r(defaults.joints[j - 1].viscous))
                    .unit("N.m.s/rad")
                    .min(0.0)
                    .max(1e6)
                    .describe(format!("Viscous damping at joint {j}")),
            );
        }
        for (j, vr) in [(1, VR_Q0_1), (2, VR_Q0_2)] {
            variables.push(
                Variable::real(format!("q0[{j}]"), vr)
                    .parameter(r(0.0))
                    .unit("rad")
                    .describe(format!("Initial angle q[{j}]")),
            );
        }
        for (j, vr) in [(1, VR_QD0_1), (2, VR_QD0_2)] {
            variables.push(
                Variable::real(format!("qd0[{j}]"), vr)
                    .parameter(r(0.0))
                    .unit("rad/s")
                    .describe(format!("Initial speed qd[{j}]")),
            );
        }
        variables.push(
            Variable::real("rtol", VR_RTOL)
                .parameter(r(tol.rtol))
                .min(1e-14)
                .max(1e-2)
                .describe("Relative tolerance of the adaptive integrator"),
        );
        variables.push(
            Variable::real("atol", VR_ATOL)
                .parameter(r(tol.atol))
                .min(1e-14)
                .max(1e-2)
                .describe("Absolute tolerance of the adaptive integrator"),
        );
        ModelDescription {
            model_name: "DoublePendulum".into(),
            model_identifier: "DoublePendulum".into(),
            description: "Double pendulum of the EigenMPC paper: joint torques in, joint \
                          angles, speeds and energy out; adaptive Dormand-Prince inside doStep"
                .into(),
            version: env!("CARGO_PKG_VERSION").into(),
            author: "EigenMPC project".into(),
            generation_tool: format!("fmi2-slave (EigenMPC) {}", env!("CARGO_PKG_VERSION")),
            can_handle_variable_communication_step_size: true,
            default_experiment: Some(DefaultExperiment {
                start_time: 0.0,
                stop_time: 10.0,
                step_size: 0.01,
            }),
            units: units(),
            enumerations: vec![],
            variables,
        }
    }

    fn initialize(values: &mut Values, ctx: &Context) -> Result<Self, ModelError> {
        let mut params = PlanarChainParams::point_masses(
            [values.real(VR_M1), values.real(VR_M2)],
            [values.real(VR_L1), values.real(VR_L2)],
            values.real(VR_G),
        );
        params.joints[0].viscous = values.real(VR_DAMPING1);
        params.joints[1].viscous = values.real(VR_DAMPING2);
        let system = DoublePendulum::new(params)
            .map_err(|e| ModelError::Error(format!("invalid pendulum parameters: {e}")))?;
        let q = Vector::<2>::new(values.real(VR_Q0_1), values.real(VR_Q0_2));
        let qd = Vector::<2>::new(values.real(VR_QD0_1), values.real(VR_QD0_2));
        let tol = Tolerances {
            rtol: values.real(VR_RTOL),
            atol: values.real(VR_ATOL),
        };
        let z0: State = pack_state::<2, 4>(&q, &qd);
        let model = Self {
            system,
            ode: Dopri5::new(ctx.experiment.start_time, z0, tol),
            tau: Vector::<2>::new(values.real(VR_TAU1), values.real(VR_TAU2)),
        };
        model.write_outputs(values);
        Ok(model)
    }

    fn do_step(
        &mut self,
        values: &mut Values,
        t: f64,
        h: f64,
        _ctx: &Context,
    ) -> Result<(), ModelError> {
        let tau = Vector::<2>::new(values.real(VR_TAU1), values.real(VR_TAU2));
        if tau != self.tau {
            // The cached first stage was evaluated with the old torque.
            let (t0, z) = (self.ode.time(), *self.ode.state());
            self.ode.reset(t0, z);
            self.tau = tau;
        }
        let system = &self.system;
        let result = self.ode.advance_to(
            |_, z: &State| state_derivative::<DoublePendulum, 2, 4>(system, z, &tau),
            t + h,
        );
        match result {
            Ok(_) => {
                self.write_outputs(values);
                Ok(())
            }
            Err(e) => {
                let reached = self.ode.time();
                self.write_outputs(values);
                Err(ModelError::Discard {
                    message: format!("integration failed: {e}"),
                    last_successful_time: reached,
                })
            }
        }
    }
}

impl DoublePendulumFmu {
    fn write_outputs(&self, values: &mut Values) {
        let z = self.ode.state();
        let (q, qd) = unpack_state::<2, 4>(z);
        values.set_real(VR_Q1, q[0]);
        values.set_real(VR_Q2, q[1]);
        values.set_real(VR_QD1, qd[0]);
        values.set_real(VR_QD2, qd[1]);
        values.set_real(
            VR_ENERGY,
            state_energy::<DoublePendulum, 2, 4>(&self.system, z),
        );
    }

    /// Accepted integrator steps so far (diagnostics and tests).
    pub fn integrator_steps(&self) -> usize {
        self.ode.steps()
    }
}

/// The 34 FMI 2.0 functions of this FMU.
pub mod fmi2_exports {
    fmi2_slave::export_fmi2!(crate::DoublePendulumFmu);
}
