//! The test model: a chain of `N` masses on springs (mass 1 tied to a wall
//! at 0, mass j to mass j - 1), with an array input (the forces `f`),
//! array outputs (positions `x`, velocities `v`), a two-dimensional
//! parameter array (`init[j,c]`: c = 0 position, c = 1 velocity, the second
//! index from 0 like the controller's chart), a tunable stiffness, an
//! enumeration (the integrator), an Integer step counter and a panic
//! trigger, and a Boolean input that holds the chain.

#![allow(dead_code)]

use fmi3_slave::{
    Context, DefaultExperiment, EnumerationType, Model, ModelDescription, ModelError, Unit, Value,
    Values, Variable,
};

/// Number of masses.
pub const N: usize = 3;

// Real value references (FMI 2.0 numbering; FMI 3.0 keeps Real ones).
pub const F: u32 = 0;
pub const X: u32 = 3;
pub const V: u32 = 6;
pub const K: u32 = 9;
pub const MASS: u32 = 10;
pub const ENERGY: u32 = 11;
pub const INIT: u32 = 20;
// Integer value references (FMI 2.0 numbering).
pub const STEPS: u32 = 0;
pub const PANIC_AT: u32 = 1;
pub const INTEGRATOR: u32 = 2;
// Boolean value reference (FMI 2.0 numbering).
pub const HOLD: u32 = 0;

/// A step that would move a mass beyond is discarded.
pub const X_LIMIT: f64 = 1000.0;

/// The integrator items.
pub const SYMPLECTIC: i32 = 1;
pub const EXPLICIT: i32 = 2;

pub struct Chain {
    pub x: [f64; N],
    pub v: [f64; N],
    pub k: f64,
    pub m: f64,
    pub integrator: i32,
    pub steps: i32,
    /// The last step size (for the stiffness check of `update_tunables`).
    pub last_h: f64,
}

/// Accelerations of the chain at positions `x` under forces `f`.
pub fn accelerations(x: &[f64; N], f: &[f64; N], k: f64, m: f64) -> [f64; N] {
    let mut a = [0.0; N];
    for j in 0..N {
        let left = if j == 0 { 0.0 } else { x[j - 1] };
        let mut force = f[j] - k * (x[j] - left);
        if j + 1 < N {
            force += k * (x[j + 1] - x[j]);
        }
        a[j] = force / m;
    }
    a
}

/// Kinetic plus spring energy.
pub fn energy(x: &[f64; N], v: &[f64; N], k: f64, m: f64) -> f64 {
    let mut e = 0.0;
    for j in 0..N {
        let left = if j == 0 { 0.0 } else { x[j - 1] };
        e += 0.5 * m * v[j] * v[j] + 0.5 * k * (x[j] - left).powi(2);
    }
    e
}

/// One step of the chosen integrator.
pub fn step(
    x: &mut [f64; N],
    v: &mut [f64; N],
    f: &[f64; N],
    k: f64,
    m: f64,
    h: f64,
    integrator: i32,
) {
    let a = accelerations(x, f, k, m);
    for j in 0..N {
        if integrator == SYMPLECTIC {
            v[j] += h * a[j];
            x[j] += h * v[j];
        } else {
            x[j] += h * v[j];
            v[j] += h * a[j];
        }
    }
}

impl Chain {
    fn write(&self, values: &mut Values) {
        for j in 0..N {
            values.set_real(X + j as u32, self.x[j]);
            values.set_real(V + j as u32, self.v[j]);
        }
        values.set_real(ENERGY, energy(&self.x, &self.v, self.k, self.m));
        values.set_integer(STEPS, self.steps);
    }
}

impl Model for Chain {
    fn description() -> ModelDescription {
        let mut variables = Vec::new();
        for j in 1..=N {
            variables.push(
                Variable::real(format!("f[{j}]"), F + j as u32 - 1)
                    .input(Value::Real(0.0))
                    .unit("N")
                    .min(-1e6)
                    .max(1e6)
                    .describe(format!("External force on mass {j}")),
            );
        }
        for j in 1..=N {
            variables.push(
                Variable::real(format!("x[{j}]"), X + j as u32 - 1)
                    .output()
                    .unit("m")
                    .depends_on(&[])
                    .describe(format!("Position of mass {j}")),
            );
        }
        for j in 1..=N {
            variables.push(
                Variable::real(format!("v[{j}]"), V + j as u32 - 1)
                    .output()
                    .unit("m/s")
                    .depends_on(&[])
                    .describe(format!("Velocity of mass {j}")),
            );
        }
        variables.push(
            Variable::real("k", K)
                .tunable(Value::Real(100.0))
                .unit("N/m")
                .min(0.0)
                .max(1e4)
                .describe("Spring stiffness; tunable between steps"),
        );
        variables.push(
            Variable::real("mass", MASS)
                .parameter(Value::Real(1.0))
                .unit("kg")
                .min(1e-3)
                .max(1e3)
                .describe("Mass of each body"),
        );
        variables.push(
            Variable::real("energy", ENERGY)
                .output()
                .unit("J")
                .depends_on(&[])
                .describe("Kinetic and spring energy"),
        );
        let mut vr = INIT;
        for j in 1..=N {
            for c in 0..2 {
                variables.push(
                    Variable::real(format!("init[{j},{c}]"), vr)
                        .parameter(Value::Real(if c == 0 { 0.1 * j as f64 } else { 0.0 }))
                        .min(-100.0)
                        .max(100.0)
                        .describe(format!(
                            "Initial state of mass {j}, component {c} (0: position, 1: velocity)"
                        )),
                );
                vr += 1;
            }
        }
        variables.push(
            Variable::integer("steps", STEPS)
                .output()
                .depends_on(&[])
                .initially_depends_on(&[])
                .describe("Steps taken"),
        );
        variables.push(
            Variable::integer("panic_at", PANIC_AT)
                .parameter(Value::Integer(-1))
                .min(-1.0)
                .describe("Panics at this step (test of catch_unwind)"),
        );
        variables.push(
            Variable::enumeration("integrator", INTEGRATOR, "Integrator")
                .parameter(Value::Integer(SYMPLECTIC))
                .min(1.0)
                .max(2.0)
                .describe("Time integration"),
        );
        variables.push(
            Variable::boolean("hold", HOLD)
                .input(Value::Boolean(false))
                .describe("Holds the chain still"),
        );
        ModelDescription {
            model_name: "Chain".into(),
            model_identifier: "Chain".into(),
            description: "A chain of masses on springs".into(),
            version: "1".into(),
            author: "test".into(),
            generation_tool: "fmi3-slave tests".into(),
            can_handle_variable_communication_step_size: true,
            can_save_state: true,
            default_experiment: Some(DefaultExperiment {
                start_time: 0.0,
                stop_time: 2.0,
                step_size: 0.001,
                tolerance: None,
            }),
            units: vec![
                Unit::new("N", 1, 1, -2, 0),
                Unit::new("m", 0, 1, 0, 0),
                Unit::new("m/s", 0, 1, -1, 0),
                Unit::new("N/m", 1, 0, -2, 0),
                Unit::new("kg", 1, 0, 0, 0),
                Unit::new("J", 1, 2, -2, 0),
            ],
            enumerations: vec![EnumerationType {
                name: "Integrator".into(),
                items: vec![
                    ("symplectic".into(), SYMPLECTIC, "Symplectic Euler".into()),
                    ("explicit".into(), EXPLICIT, "Explicit Euler".into()),
                ],
            }],
            variables,
        }
    }

    fn initialize(values: &mut Values, _ctx: &Context) -> Result<Self, ModelError> {
        let mut x = [0.0; N];
        let mut v = [0.0; N];
        for j in 0..N {
            x[j] = values.real(INIT + 2 * j as u32);
            v[j] = values.real(INIT + 2 * j as u32 + 1);
        }
        let chain = Self {
            x,
            v,
            k: values.real(K),
            m: values.real(MASS),
            integrator: values.integer(INTEGRATOR),
            steps: 0,
            last_h: 0.0,
        };
        chain.write(values);
        Ok(chain)
    }

    fn do_step(
        &mut self,
        values: &mut Values,
        t: f64,
        h: f64,
        _ctx: &Context,
    ) -> Result<(), ModelError> {
        if self.steps == values.integer(PANIC_AT) {
            panic!("deliberate test panic");
        }
        if !values.boolean(HOLD) {
            let mut f = [0.0; N];
            for (j, fj) in f.iter_mut().enumerate() {
                *fj = values.real(F + j as u32);
            }
            let (mut x, mut v) = (self.x, self.v);
            step(&mut x, &mut v, &f, self.k, self.m, h, self.integrator);
            if x.iter().any(|xj| xj.abs() > X_LIMIT) {
                return Err(ModelError::Discard {
                    message: format!("a mass would leave |x| <= {X_LIMIT}"),
                    last_successful_time: t,
                });
            }
            (self.x, self.v) = (x, v);
        }
        self.steps += 1;
        self.last_h = h;
        self.write(values);
        Ok(())
    }

    fn save_state(&self) -> Result<Vec<u8>, ModelError> {
        let mut out = Vec::new();
        for x in self.x.iter().chain(&self.v).chain([&self.k, &self.last_h]) {
            out.extend_from_slice(&x.to_le_bytes());
        }
        out.extend_from_slice(&self.steps.to_le_bytes());
        Ok(out)
    }

    fn restore_state(
        &mut self,
        state: &[u8],
        _values: &Values,
        _ctx: &Context,
    ) -> Result<(), ModelError> {
        let reals = 2 * N + 2;
        if state.len() != 8 * reals + 4 {
            return Err(ModelError::Error(format!(
                "{} state bytes, expected {}",
                state.len(),
                8 * reals + 4
            )));
        }
        let f = |i: usize| f64::from_le_bytes(state[8 * i..8 * i + 8].try_into().unwrap());
        for j in 0..N {
            self.x[j] = f(j);
            self.v[j] = f(N + j);
        }
        self.k = f(2 * N);
        self.last_h = f(2 * N + 1);
        self.steps = i32::from_le_bytes(state[8 * reals..].try_into().unwrap());
        Ok(())
    }

    fn update_tunables(&mut self, values: &mut Values, _ctx: &Context) -> Result<(), ModelError> {
        let k = values.real(K);
        // Symplectic Euler is stable for h * omega_max < 2, omega_max < 2 sqrt(k / m).
        if self.last_h * 2.0 * (k / self.m).sqrt() >= 2.0 {
            return Err(ModelError::Error(format!(
                "k = {k} is unstable with the step {} (needs k < m / h^2 = {})",
                self.last_h,
                self.m / (self.last_h * self.last_h)
            )));
        }
        self.k = k;
        Ok(())
    }
}
