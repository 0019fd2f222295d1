//! Nonlinear eigenmodes as brake orbits (Albu-Schaeffer & Della Santina
//! 2020): a free motion that starts at rest at a turning point `q0` with
//! `V(q0) = E` and comes to rest again at a second turning point after half a
//! period, then retraces the same line.
//!
//! Each family is computed by single shooting, unknowns `(q0, T/2)`, residual
//! `(V(q0) - E, qd(T/2))`, Newton on exact sensitivities from the variational
//! equations, and continuation in energy from the linear mode at small energy.

use super::{ModeError, linear_modes};
use crate::integrate::{Dopri5, IntegrationError, Tolerances, Variational, variational_rhs};
use crate::mechanics::{
    Conservative, MechanicalSystem, Vector, pack_state, state_derivative, state_jacobian,
    unpack_state,
};
use nalgebra::{DMatrix, DVector, SMatrix, SVector};

/// One eigenmode (brake orbit) at a given energy.
#[derive(Clone, Debug, PartialEq)]
pub struct Eigenmode<const N: usize> {
    /// Energy `E` of the orbit (J).
    pub energy: f64,
    /// Turning point on the positive side of the eigenvector (`c'(q - q_eq) > 0`).
    pub turning_point: Vector<N>,
    /// The turning point reached after half a period.
    pub other_turning_point: Vector<N>,
    /// Half period `T/2` (s).
    pub half_period: f64,
    /// `|z(T) - z(0)|_inf` after integrating one full period.
    pub closing_error: f64,
    /// `|qd(T/2)|_inf`, the speed at the second turning point.
    pub turning_speed: f64,
    /// Newton iterations used at this energy.
    pub newton_iterations: usize,
    /// Samples equally spaced in time from `turning_point` to `other_turning_point`.
    pub path: Vec<Vector<N>>,
}

/// Settings of the shooting and the energy continuation.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContinuationOptions {
    /// Path samples per orbit, turning point to turning point inclusive.
    pub samples: usize,
    /// Integrator tolerances for shooting and verification.
    pub tolerances: Tolerances,
    /// Newton stops when the residual's infinity norm is below this.
    pub newton_tolerance: f64,
    /// Newton iterations allowed per energy before the step is halved.
    pub max_newton_iterations: usize,
    /// First continuation step in energy (J).
    pub initial_energy_step: f64,
    /// Give up when the step has to shrink below this (J).
    pub min_energy_step: f64,
    /// Largest continuation step (J).
    pub max_energy_step: f64,
    /// Energy of the first orbit, started from the linear mode (J).
    pub start_energy: f64,
    /// Closing error and turning speed above this fail verification.
    pub verification_tolerance: f64,
    /// Work limit of one continuation: right-hand-side evaluations of the
    /// integrator over every shot and verification. A model whose time
    /// scales are far apart (a very light, heavy, long or stiff link) needs
    /// tiny steps; the limit stops it with [`ModeError::WorkLimit`] instead
    /// of an unbounded pause. Absent in files written before it existed.
    #[serde(default = "default_max_evaluations")]
    pub max_evaluations: usize,
}

/// [`ContinuationOptions::max_evaluations`] by default.
pub const DEFAULT_MAX_EVALUATIONS: usize = 3_000_000;

fn default_max_evaluations() -> usize {
    DEFAULT_MAX_EVALUATIONS
}

/// The integration work a continuation may still spend, shared by its shots
/// and verifications.
struct Work {
    left: usize,
}

impl Work {
    fn new(limit: usize) -> Self {
        Self { left: limit }
    }

    /// An integrator whose step budget is the work left (6 evaluations per
    /// attempted step): running out of it is [`IntegrationError::TooManySteps`].
    fn ode<Y: crate::integrate::OdeState>(&self, y0: Y, tol: Tolerances) -> Dopri5<Y> {
        let mut ode = Dopri5::new(0.0, y0, tol);
        ode.max_steps = self.left / 6;
        ode
    }

    /// Books the evaluations `ode` made.
    fn spend<Y: crate::integrate::OdeState>(&mut self, ode: &Dopri5<Y>) {
        self.left = self.left.saturating_sub(ode.evaluations());
    }
}

/// Why a shot failed: an ordinary failure (the step is halved) or the work
/// limit (the continuation stops).
enum ShotError {
    Failed(String),
    OutOfWork,
}

impl Default for ContinuationOptions {
    fn default() -> Self {
        Self {
            samples: 200,
            tolerances: Tolerances::default(),
            newton_tolerance: 1e-10,
            max_newton_iterations: 10,
            initial_energy_step: 0.25,
            min_energy_step: 1e-3,
            max_energy_step: 2.0,
            start_energy: 0.05,
            verification_tolerance: 1e-8,
            max_evaluations: DEFAULT_MAX_EVALUATIONS,
        }
    }
}

/// A converged shooting solution.
#[derive(Clone, Copy, Debug)]
struct Shot<const N: usize> {
    q0: Vector<N>,
    half_period: f64,
    iterations: usize,
}

/// Newton on `(V(q0) - E, qd(T/2)) = 0` from the guess `(q0, half)`.
fn shoot<S, const N: usize, const NX: usize>(
    system: &S,
    energy: f64,
    guess: Shot<N>,
    opts: &ContinuationOptions,
    work: &mut Work,
) -> Result<Shot<N>, ShotError>
where
    S: MechanicalSystem<N> + ?Sized,
{
    let zero = Vector::<N>::zeros();
    let (mut q0, mut half) = (guess.q0, guess.half_period);
    for iteration in 0..=opts.max_newton_iterations {
        if !(half > 0.0 && half.is_finite()) {
            return Err(ShotError::Failed(format!(
                "half period left the admissible range ({half})"
            )));
        }
        let start = Variational {
            z: pack_state::<N, NX>(&q0, &zero),
            phi: SMatrix::<f64, NX, NX>::identity(),
        };
        let mut ode = work.ode(start, opts.tolerances);
        let end = ode
            .advance_to(|_, v| variational_rhs::<S, N, NX>(system, &zero, v), half)
            .copied();
        work.spend(&ode);
        let end = match end {
            Ok(end) => end,
            Err(IntegrationError::TooManySteps { .. }) => return Err(ShotError::OutOfWork),
            Err(e) => return Err(ShotError::Failed(e.to_string())),
        };
        let (_, qd_end) = unpack_state::<N, NX>(&end.z);
        let residual_energy = system.potential(&q0) - energy;
        let residual = DVector::from_fn(N + 1, |i, _| {
            if i == 0 {
                residual_energy
            } else {
                qd_end[i - 1]
            }
        });
        if residual.amax() <= opts.newton_tolerance {
            return Ok(Shot {
                q0,
                half_period: half,
                iterations: iteration,
            });
        }
        if iteration == opts.max_newton_iterations {
            break;
        }
        let grad_v = system.potential_gradient(&q0);
        let (zd_end, _, _) = state_jacobian::<S, N, NX>(system, &end.z, &zero);
        let jac = DMatrix::from_fn(N + 1, N + 1, |i, j| match (i, j) {
            (0, j) if j < N => grad_v[j],
            (0, _) => 0.0,
            (i, j) if j < N => end.phi[(N + i - 1, j)],
            (i, _) => zd_end[N + i - 1],
        });
        let svd = jac.clone().svd(true, true);
        let (smax, smin) = (svd.singular_values.max(), svd.singular_values.min());
        if smin.is_nan() || smin <= 1e-12 * smax {
            return Err(ShotError::Failed(format!(
                "singular shooting Jacobian (condition {:.1e}): fold or bifurcation of the family",
                smax / smin
            )));
        }
        let mut step = svd
            .solve(&(-residual), 0.0)
            .map_err(|e| ShotError::Failed(format!("linear solve failed: {e}")))?;
        // Damp large steps: the continuation predictor is good, a big step
        // means Newton is heading for another branch.
        let size = step.rows(0, N).amax().max(step[N].abs() / half.max(1e-3));
        if size > 0.3 {
            step *= 0.3 / size;
        }
        for j in 0..N {
            q0[j] += step[j];
        }
        half += step[N];
    }
    Err(ShotError::Failed(format!(
        "Newton did not converge in {} iterations",
        opts.max_newton_iterations
    )))
}

/// Why a verification failed.
enum VerifyError {
    Mode(ModeError),
    OutOfWork,
}

/// Integrates the orbit for one full period: path samples, closing error, turning speed.
fn verify<S, const N: usize, const NX: usize>(
    system: &S,
    energy: f64,
    shot: &Shot<N>,
    opts: &ContinuationOptions,
    work: &mut Work,
) -> Result<Eigenmode<N>, VerifyError>
where
    S: MechanicalSystem<N> + ?Sized,
{
    let zero = Vector::<N>::zeros();
    let z0: SVector<f64, NX> = pack_state::<N, NX>(&shot.q0, &zero);
    let mut ode = work.ode(z0, opts.tolerances);
    let samples = opts.samples.max(2);
    let mut path = Vec::with_capacity(samples);
    let f = |_: f64, z: &SVector<f64, NX>| state_derivative::<S, N, NX>(system, z, &zero);
    path.push(shot.q0);
    let mut integrate = |ode: &mut Dopri5<SVector<f64, NX>>, t: f64| {
        let before = ode.evaluations();
        ode.max_steps = work.left / 6;
        let outcome = ode.advance_to(f, t).copied();
        let spent = ode.evaluations() - before;
        work.left = work.left.saturating_sub(spent);
        outcome.map_err(|e| match e {
            IntegrationError::TooManySteps { .. } => VerifyError::OutOfWork,
            e => VerifyError::Mode(e.into()),
        })
    };
    for i in 1..samples {
        let t = shot.half_period * i as f64 / (samples - 1) as f64;
        let z = integrate(&mut ode, t)?;
        path.push(unpack_state::<N, NX>(&z).0);
    }
    let (other, qd_half) = unpack_state::<N, NX>(ode.state());
    let z_end = integrate(&mut ode, 2.0 * shot.half_period)?;
    let closing_error = (z_end - z0).amax();
    let turning_speed = qd_half.amax();
    let tol = opts.verification_tolerance;
    if !(closing_error <= tol && turning_speed <= tol) {
        return Err(VerifyError::Mode(ModeError::VerificationFailed {
            energy,
            reason: format!(
                "closing error {closing_error:.2e}, turning speed {turning_speed:.2e} (limit {tol:.0e})"
            ),
        }));
    }
    Ok(Eigenmode {
        energy,
        turning_point: shot.q0,
        other_turning_point: other,
        half_period: shot.half_period,
        closing_error,
        turning_speed,
        newton_iterations: shot.iterations,
        path,
    })
}

/// Computes the eigenmodes of the family that grows from linear mode
/// `mode_index` (ascending frequency) at each of the requested energies.
///
/// Energies may be given in any order; results come back in that order. The
/// family is continued from `opts.start_energy` upwards; an energy beyond a
/// fold or a non-convergence gives [`ModeError::ContinuationFailed`] naming
/// the highest energy reached.
pub fn eigenmode_family<S, const N: usize, const NX: usize>(
    system: &S,
    mode_index: usize,
    energies: &[f64],
    opts: &ContinuationOptions,
) -> Result<Vec<Eigenmode<N>>, ModeError>
where
    S: MechanicalSystem<N> + ?Sized,
{
    eigenmode_family_with_progress::<S, N, NX>(system, mode_index, energies, opts, |_| {})
}

/// [`eigenmode_family`] calling `progress(k)` after the `k`-th requested energy is done.
pub fn eigenmode_family_with_progress<S, const N: usize, const NX: usize>(
    system: &S,
    mode_index: usize,
    energies: &[f64],
    opts: &ContinuationOptions,
    mut progress: impl FnMut(usize),
) -> Result<Vec<Eigenmode<N>>, ModeError>
where
    S: MechanicalSystem<N> + ?Sized,
{
    let mut order: Vec<usize> = (0..energies.len()).collect();
    order.sort_by(|&a, &b| energies[a].total_cmp(&energies[b]));
    let sorted: Vec<f64> = order.iter().map(|&i| energies[i]).collect();
    let mut results: Vec<Option<Eigenmode<N>>> = vec![None; energies.len()];
    let mut done = 0;
    continue_family::<S, N, NX>(system, mode_index, &sorted, opts, |mode| {
        results[order[done]] = Some(mode);
        done += 1;
        progress(done);
        true
    })?;
    Ok(results
        .into_iter()
        .map(|m| m.expect("every energy solved"))
        .collect())
}

/// Continues the family of linear mode `mode_index` through the energies
/// `sorted` (ascending), handing each verified orbit to `on_mode`, which
/// returns `false` to stop early (e.g. when the orbit can no longer be
/// charted). Friction is ignored: eigenmodes are those of the conservative
/// part.
pub fn continue_family<S, const N: usize, const NX: usize>(
    system: &S,
    mode_index: usize,
    sorted: &[f64],
    opts: &ContinuationOptions,
    mut on_mode: impl FnMut(Eigenmode<N>) -> bool,
) -> Result<(), ModeError>
where
    S: MechanicalSystem<N> + ?Sized,
{
    const { assert!(NX == 2 * N, "NX must equal 2 N") };
    // Eigenmodes are those of the conservative part: friction off.
    let conservative = Conservative(system);
    let system = &conservative;
    if let Some(&bad) = sorted.iter().find(|e| !(e.is_finite() && **e > 0.0)) {
        return Err(ModeError::InvalidEnergy(bad));
    }
    if sorted.windows(2).any(|w| w[1] < w[0]) {
        return Err(ModeError::ChartFit(
            "continue_family needs ascending energies".into(),
        ));
    }
    let modes = linear_modes(system)?;
    let mode = modes.get(mode_index).ok_or(ModeError::NoSuchMode {
        index: mode_index,
        dof: N,
    })?;
    let family = super::family_name(N, mode_index);
    let q_eq = system.equilibrium();
    let c = mode.eigenvector;
    let stiffness = c.dot(&(system.potential_hessian(&q_eq) * c));
    let Some(&lowest) = sorted.first() else {
        return Ok(());
    };

    // First orbit from the linear mode: V ~ 1/2 a^2 c'Kc along q_eq + a c.
    let e_start = opts.start_energy.min(lowest);
    let guess = Shot {
        q0: q_eq + c * (2.0 * e_start / stiffness).sqrt(),
        half_period: std::f64::consts::PI / mode.omega,
        iterations: 0,
    };
    let fail = |reached: f64, requested: f64, reason: String| ModeError::ContinuationFailed {
        family: family.clone(),
        reached,
        requested,
        reason,
    };
    let mut work = Work::new(opts.max_evaluations);
    let out_of_work = |reached: f64| ModeError::WorkLimit {
        family: family.clone(),
        reached,
        limit: opts.max_evaluations,
    };
    let first = match shoot::<_, N, NX>(system, e_start, guess, opts, &mut work) {
        Ok(shot) => shot,
        Err(ShotError::OutOfWork) => return Err(out_of_work(0.0)),
        Err(ShotError::Failed(r)) => {
            return Err(fail(
                0.0,
                lowest,
                format!("no orbit at the continuation's start energy {e_start} J: {r}"),
            ));
        }
    };
    // History for the secant predictor, parametrised by sqrt(E) (amplitude
    // grows like sqrt(E) near the equilibrium).
    let mut prev: Option<(f64, Shot<N>)> = None;
    let mut cur = (e_start, first);
    let mut step = opts.initial_energy_step;
    for &target in sorted {
        while cur.0 < target {
            let e_next = (cur.0 + step).min(target);
            let predicted = match prev {
                Some((e_prev, s_prev)) => {
                    let ratio = (e_next.sqrt() - cur.0.sqrt()) / (cur.0.sqrt() - e_prev.sqrt());
                    Shot {
                        q0: cur.1.q0 + (cur.1.q0 - s_prev.q0) * ratio,
                        half_period: cur.1.half_period
                            + (cur.1.half_period - s_prev.half_period) * ratio,
                        iterations: 0,
                    }
                }
                None => cur.1,
            };
            match shoot::<_, N, NX>(system, e_next, predicted, opts, &mut work) {
                Err(ShotError::OutOfWork) => return Err(out_of_work(cur.0)),
                Ok(shot) if c.dot(&(shot.q0 - q_eq)) > 0.0 => {
                    prev = Some(cur);
                    cur = (e_next, shot);
                    if shot.iterations <= 3 {
                        step = (step * 1.5).min(opts.max_energy_step);
                    }
                }
                outcome => {
                    step *= 0.5;
                    if step < opts.min_energy_step {
                        let reason = match outcome {
                            Err(ShotError::Failed(r)) => r,
                            Err(ShotError::OutOfWork) => unreachable!("handled above"),
                            Ok(_) => {
                                "the turning point crossed to the other side of the mode".into()
                            }
                        };
                        return Err(fail(cur.0, target, reason));
                    }
                }
            }
        }
        // The loop ends exactly on target (steps are clipped to it).
        let shot = cur.1;
        let mode = match verify::<_, N, NX>(system, target, &shot, opts, &mut work) {
            Ok(mode) => mode,
            Err(VerifyError::OutOfWork) => return Err(out_of_work(cur.0)),
            Err(VerifyError::Mode(e)) => return Err(e),
        };
        if !on_mode(mode) {
            break;
        }
    }
    Ok(())
}
