//! The eigenmanifold over energy: one mode family's charts tabulated on an
//! energy grid and interpolated, so that a chart `X(s; E)` is available for
//! any energy in the family's range without recomputing an orbit.
//!
//! The grid is uniform in `sqrt(E)` (orbit amplitudes grow like `sqrt(E)`),
//! each grid energy gets a least-squares chart of the same degree in the
//! same coordinate `s = c'(q - q_eq)`, and the coefficients are interpolated
//! by a Catmull-Rom cubic in `sqrt(E)` (C1, exact at the grid, no
//! allocation: [`ChartFamily::write_chart`]).

use super::{Chart, ContinuationOptions, ModeError, continue_family, linear_modes};
use crate::mechanics::{MechanicalSystem, Vector};

/// Highest chart degree a family is refitted to ([`ChartFamily::compute_accurate`]);
/// charts from [`ChartFamily::chart`] have room for it, so a family of
/// another degree up to this one is written into them without allocating.
pub const MAX_FAMILY_DEGREE: usize = 17;

/// Largest miss (rad) of the charts about an energy that
/// [`ChartFamily::compute_accurate`] accepts before it raises the degree.
/// Measured on the paper's pendulum at 14 J: degree 9 misses the nominal
/// robot's mode by 8e-4 rad and holds it with 0.005 / 0.011 N m; with link
/// 1 10 % lighter it misses by 2.5e-3 rad and needs 0.014 / 0.033 N m
/// (degree 13: 4.4e-4 rad); 25 % lighter, 1.4e-2 rad, and the family ends
/// below 14 J (degree 17: 0.008 / 0.019 N m).
pub const CHART_TOLERANCE: f64 = 1e-3;

/// How a [`ChartFamily`] is computed.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FamilyOptions {
    /// Lowest grid energy (J), > 0.
    pub energy_min: f64,
    /// Highest grid energy asked for (J); the family may end lower (see
    /// [`ChartFamily::energy_range`]).
    pub energy_max: f64,
    /// Grid energies, >= 2.
    pub points: usize,
    /// Chart polynomial degree.
    pub degree: usize,
    /// A grid orbit whose chart misses its path by more than this (rad), or
    /// along which `s` is not monotone, ends the family.
    pub max_chart_residual: f64,
    /// Shooting and continuation settings.
    pub continuation: ContinuationOptions,
}

impl FamilyOptions {
    /// A family from `energy_max / 100` to `energy_max` on 17 grid energies,
    /// degree-9 charts; a chart that misses its orbit by more than 0.02 rad
    /// ends the family. Shooting at `rtol = atol = 1e-10` (not the
    /// 1e-12 of `eigenmpc modes`): a third of the time, and the charts are
    /// the same to 1e-9 rad, far below their fitting residual.
    pub fn up_to(energy_max: f64) -> Self {
        Self {
            energy_min: 0.01 * energy_max,
            energy_max,
            points: 17,
            degree: 9,
            max_chart_residual: 0.02,
            continuation: ContinuationOptions {
                samples: 120,
                tolerances: crate::integrate::Tolerances {
                    rtol: 1e-10,
                    atol: 1e-10,
                },
                newton_tolerance: 1e-9,
                max_energy_step: 5.0,
                verification_tolerance: 1e-6,
                ..ContinuationOptions::default()
            },
        }
    }

    /// [`FamilyOptions::up_to`] the default top for `system` and the
    /// energies a user asks for: half the potential with every link upright
    /// (above it the in-phase charts stop following the orbits), and at
    /// least 1.25 times the largest requested energy.
    pub fn for_system<S, const N: usize>(system: &S, requested: &[f64]) -> Self
    where
        S: MechanicalSystem<N> + ?Sized,
    {
        let mut upright = system.equilibrium();
        upright[0] += std::f64::consts::PI;
        let asked = requested
            .iter()
            .copied()
            .filter(|e| e.is_finite())
            .fold(0.0, f64::max);
        Self::up_to((0.5 * system.potential(&upright)).max(1.25 * asked))
    }

    fn validate(&self) -> Result<(), ModeError> {
        if !(self.energy_min.is_finite()
            && self.energy_min > 0.0
            && self.energy_max.is_finite()
            && self.energy_max > self.energy_min)
        {
            return Err(ModeError::ChartFit(format!(
                "family energy range [{}, {}] J is invalid: need 0 < min < max, finite",
                self.energy_min, self.energy_max
            )));
        }
        if self.points < 2 || self.points > 1000 {
            return Err(ModeError::ChartFit(format!(
                "family grid of {} energies: need 2..=1000",
                self.points
            )));
        }
        if !(self.max_chart_residual.is_finite() && self.max_chart_residual > 0.0) {
            return Err(ModeError::ChartFit(
                "max_chart_residual must be finite and > 0".into(),
            ));
        }
        Ok(())
    }
}

/// Charts of one eigenmode family on an energy grid (the eigenmanifold).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChartFamily<const N: usize> {
    mode_index: usize,
    degree: usize,
    eigenvector: Vector<N>,
    equilibrium: Vector<N>,
    /// `sqrt(E)` of the first grid energy and the grid step in `sqrt(E)`.
    sqrt_start: f64,
    sqrt_step: f64,
    /// Grid energies (J), ascending.
    energies: Vec<f64>,
    /// Per grid energy, per joint, the `degree + 1` coefficients.
    coefficients: Vec<f64>,
    /// Per grid energy, the chart's largest miss of its orbit (rad).
    residuals: Vec<f64>,
    /// Per grid energy, the half period (s).
    half_periods: Vec<f64>,
    /// Why the family ended below `energy_max` (None: it reached it).
    ended: Option<String>,
}

impl<const N: usize> ChartFamily<N> {
    /// Continues the family of linear mode `mode_index` (ascending
    /// frequency; 0 is the in-phase mode of a pendulum) of the system's
    /// conservative part over the grid and charts every grid orbit. The
    /// family ends at the last grid energy whose orbit could be continued
    /// and charted; fewer than two such energies is an error.
    pub fn compute<S, const NX: usize>(
        system: &S,
        mode_index: usize,
        opts: &FamilyOptions,
    ) -> Result<Self, ModeError>
    where
        S: MechanicalSystem<N> + ?Sized,
    {
        opts.validate()?;
        let linear = linear_modes(system)?;
        let eigenvector = linear
            .get(mode_index)
            .ok_or(ModeError::NoSuchMode {
                index: mode_index,
                dof: N,
            })?
            .eigenvector;
        let equilibrium = system.equilibrium();
        let sqrt_start = opts.energy_min.sqrt();
        let sqrt_step = (opts.energy_max.sqrt() - sqrt_start) / (opts.points - 1) as f64;
        let grid: Vec<f64> = (0..opts.points)
            .map(|i| {
                if i + 1 == opts.points {
                    opts.energy_max
                } else {
                    (sqrt_start + sqrt_step * i as f64).powi(2)
                }
            })
            .collect();
        let mut family = Self {
            mode_index,
            degree: opts.degree,
            eigenvector,
            equilibrium,
            sqrt_start,
            sqrt_step,
            energies: Vec::with_capacity(opts.points),
            coefficients: Vec::with_capacity(opts.points * N * (opts.degree + 1)),
            residuals: Vec::with_capacity(opts.points),
            half_periods: Vec::with_capacity(opts.points),
            ended: None,
        };
        let mut chart_error: Option<String> = None;
        let outcome = continue_family::<S, N, NX>(
            system,
            mode_index,
            &grid,
            &opts.continuation,
            |mode| match Chart::fit(&mode.path, &eigenvector, &equilibrium, opts.degree) {
                Ok(chart) if chart.max_residual <= opts.max_chart_residual => {
                    family.energies.push(mode.energy);
                    family.residuals.push(chart.max_residual);
                    family.half_periods.push(mode.half_period);
                    for c in &chart.coefficients {
                        family.coefficients.extend_from_slice(c);
                    }
                    true
                }
                Ok(chart) => {
                    chart_error = Some(format!(
                        "at {:.4} J the degree-{} chart misses the orbit by {:.2e} rad (limit {:.0e})",
                        mode.energy, opts.degree, chart.max_residual, opts.max_chart_residual
                    ));
                    false
                }
                Err(e) => {
                    chart_error = Some(format!("at {:.4} J: {e}", mode.energy));
                    false
                }
            },
        );
        family.ended = match outcome {
            Err(ModeError::ContinuationFailed { .. })
            | Err(ModeError::VerificationFailed { .. })
            | Err(ModeError::WorkLimit { .. })
                if family.energies.len() >= 2 =>
            {
                Some(outcome.unwrap_err().to_string())
            }
            Err(e) => return Err(e),
            Ok(()) => chart_error,
        };
        if family.energies.len() < 2 {
            return Err(ModeError::ContinuationFailed {
                family: super::family_name(N, mode_index),
                reached: family.energies.last().copied().unwrap_or(0.0),
                requested: opts.energy_max,
                reason: family
                    .ended
                    .clone()
                    .unwrap_or_else(|| "fewer than two grid energies charted".into()),
            });
        }
        Ok(family)
    }

    /// [`ChartFamily::compute`] at `opts.degree`, then at degrees 4 higher
    /// (up to [`MAX_FAMILY_DEGREE`]) while the family ends below `energy`
    /// or its charts miss the orbit at `energy` by more than
    /// [`CHART_TOLERANCE`] ([`ChartFamily::miss_about`]); the most accurate
    /// family there.
    /// For a model the controller runs on at `energy` (a model identified
    /// online): a more curved mode needs a higher degree.
    pub fn compute_accurate<S, const NX: usize>(
        system: &S,
        mode_index: usize,
        opts: &FamilyOptions,
        energy: f64,
    ) -> Result<Self, ModeError>
    where
        S: MechanicalSystem<N> + ?Sized,
    {
        let mut family = Self::compute::<S, NX>(system, mode_index, opts)?;
        let mut opts = *opts;
        while family.miss_about(energy) > CHART_TOLERANCE && opts.degree + 4 <= MAX_FAMILY_DEGREE {
            opts.degree += 4;
            match Self::compute::<S, NX>(system, mode_index, &opts) {
                Ok(higher) if higher.miss_about(energy) < family.miss_about(energy) => {
                    family = higher
                }
                Ok(_) => {}
                Err(_) => break,
            }
        }
        Ok(family)
    }

    /// The charts' residual at `energy` (rad), interpolated linearly
    /// between the grid energies that bracket it; infinite when the family
    /// ends below it.
    pub fn miss_about(&self, energy: f64) -> f64 {
        let (lo, hi) = self.energy_range();
        if !(energy.is_finite() && energy <= hi) {
            return f64::INFINITY;
        }
        let energy = energy.max(lo);
        let above = self
            .energies
            .iter()
            .position(|&e| e >= energy)
            .unwrap_or(self.energies.len() - 1)
            .max(1);
        let (e0, e1) = (self.energies[above - 1], self.energies[above]);
        let (r0, r1) = (self.residuals[above - 1], self.residuals[above]);
        r0 + (r1 - r0) * ((energy - e0) / (e1 - e0)).clamp(0.0, 1.0)
    }

    /// Energies the family covers, `[lowest, highest]` grid energy (J).
    pub fn energy_range(&self) -> (f64, f64) {
        (
            self.energies[0],
            *self.energies.last().expect(">= 2 energies"),
        )
    }

    /// Why the family ended below the requested maximum (None: it did not).
    pub fn ended_early(&self) -> Option<&str> {
        self.ended.as_deref()
    }

    /// Grid energies (J).
    pub fn energies(&self) -> &[f64] {
        &self.energies
    }

    /// Per grid energy, the chart's largest miss of its orbit (rad).
    pub fn residuals(&self) -> &[f64] {
        &self.residuals
    }

    /// Per grid energy, the orbit's half period (s).
    pub fn half_periods(&self) -> &[f64] {
        &self.half_periods
    }

    /// Index of the linear mode the family grows from.
    pub fn mode_index(&self) -> usize {
        self.mode_index
    }

    /// Chart degree.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// Unit linear eigenvector `c` of the chart coordinate.
    pub fn eigenvector(&self) -> Vector<N> {
        self.eigenvector
    }

    /// `energy` clamped to [`ChartFamily::energy_range`].
    pub fn clamp(&self, energy: f64) -> f64 {
        let (lo, hi) = self.energy_range();
        if energy.is_nan() {
            lo
        } else {
            energy.clamp(lo, hi)
        }
    }

    /// The chart at `energy` (clamped to the range); allocates, for set-up.
    pub fn chart(&self, energy: f64) -> Chart<N> {
        let mut chart = Chart::from_coefficients(
            self.eigenvector,
            self.equilibrium,
            std::array::from_fn(|_| {
                // Room for a family of any degree (see `write_chart`).
                let mut c = Vec::with_capacity(MAX_FAMILY_DEGREE.max(self.degree) + 1);
                c.resize(self.degree + 1, 0.0);
                c
            }),
        )
        .expect("finite eigenvector and equilibrium");
        self.write_chart(energy, &mut chart);
        chart
    }

    /// Overwrites `chart` with the chart at `energy` (clamped to the
    /// range), its degree this family's. Allocation-free for a `chart` from
    /// [`ChartFamily::chart`] of a family of this or a higher degree, or of
    /// any degree up to [`MAX_FAMILY_DEGREE`].
    pub fn write_chart(&self, energy: f64, chart: &mut Chart<N>) {
        for c in chart.coefficients.iter_mut() {
            c.resize(self.degree + 1, 0.0);
        }
        let n = self.energies.len();
        let x = (self.clamp(energy).sqrt() - self.sqrt_start) / self.sqrt_step;
        let i = (x.floor().max(0.0) as usize).min(n - 2);
        let t = (x - i as f64).clamp(0.0, 1.0);
        // Catmull-Rom weights of the points i-1, i, i+1, i+2; at the ends the
        // missing point is the linear extrapolation 2 p_i - p_{i+1}.
        let (t2, t3) = (t * t, t * t * t);
        let w = [
            0.5 * (-t + 2.0 * t2 - t3),
            0.5 * (2.0 - 5.0 * t2 + 3.0 * t3),
            0.5 * (t + 4.0 * t2 - 3.0 * t3),
            0.5 * (-t2 + t3),
        ];
        let width = N * (self.degree + 1);
        let at =
            |g: usize, j: usize, k: usize| self.coefficients[g * width + j * (self.degree + 1) + k];
        for (j, coef) in chart.coefficients.iter_mut().enumerate() {
            for (k, value) in coef.iter_mut().enumerate() {
                let p = |g: isize| -> f64 {
                    if g < 0 {
                        2.0 * at(0, j, k) - at(1, j, k)
                    } else if g as usize >= n {
                        2.0 * at(n - 1, j, k) - at(n - 2, j, k)
                    } else {
                        at(g as usize, j, k)
                    }
                };
                let i = i as isize;
                *value = w[0] * p(i - 1) + w[1] * p(i) + w[2] * p(i + 1) + w[3] * p(i + 2);
            }
        }
        chart.degree = self.degree;
        chart.eigenvector = self.eigenvector;
        chart.equilibrium = self.equilibrium;
        chart.max_residual = self.residuals[i].max(self.residuals[i + 1]);
    }
}
