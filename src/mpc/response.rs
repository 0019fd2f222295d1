//! The motor's response per sample, `u += a (tau - u)`
//! ([`MpcConfig::torque_response`](super::MpcConfig::torque_response)): the
//! torque `u_k` applied over sample `k` is `(1 - a) u_k-1 + a tau_k`.
//!
//! The plan's controls are the *applied* torques. A command `tau` within
//! `|tau| <= tau_max` reaches, `k + 1` samples after the last applied
//! torque `p`, the applied torques `c^(k+1) p +- a tau_max sum_i<=k |c|^i`
//! (`c = 1 - a`), within `|u| <= tau_max`: that interval bounds stage `k`
//! of the plan (exact for stage 0, a necessary condition for the later
//! ones, whose reachable sets couple). The command sent is the one that
//! makes the motor apply the plan's first control, `tau = (u_0 - c p) /
//! a`, inside its bound by construction of stage 0's.
//!
//! For `a >= 1` every stage's interval is the whole `[-tau_max, tau_max]`
//! (the motor reaches any torque in one sample), so the plan is the one
//! without the response and the command cancels the overshoot; for `a < 1`
//! the first stages' intervals open up from `p` at the rate the motor can
//! follow. Without a response (`a = 1`) the bounds and the command are
//! exactly those of a controller that knows nothing of it.
//!
//! The controller keeps the applied torques, not its commands, in its
//! history ([`super::delay`]): the estimator's propagation, the delay's
//! prediction and the identification all see what acted on the robot.

use crate::mechanics::Vector;

/// The intervals the plan's stages may apply, stage 0 first: `a` the
/// response, `previous` the torque applied over the last sample. Each item
/// is `(lower, upper)` per joint, with `lower <= upper`.
pub(super) struct StageBounds<const N: usize> {
    a: f64,
    tau_max: f64,
    previous: Vector<N>,
    /// `c^(k+1)` of the coming stage `k`.
    power: f64,
    /// `a sum_i<=k |c|^i` of the coming stage.
    reach: f64,
    /// `|c|^(k+1)`.
    magnitude: f64,
}

impl<const N: usize> StageBounds<N> {
    /// The intervals from stage 0 on.
    pub(super) fn new(a: f64, tau_max: f64, previous: &Vector<N>) -> Self {
        let c = 1.0 - a;
        Self {
            a,
            tau_max,
            previous: *previous,
            power: c,
            reach: a,
            magnitude: c.abs(),
        }
    }
}

impl<const N: usize> Iterator for StageBounds<N> {
    type Item = (Vector<N>, Vector<N>);

    fn next(&mut self) -> Option<Self::Item> {
        let (a, tau_max) = (self.a, self.tau_max);
        let bound = Vector::<N>::repeat(tau_max);
        if a == 1.0 {
            return Some((-bound, bound));
        }
        let mut lower = -bound;
        let mut upper = bound;
        let half = self.reach * tau_max;
        for j in 0..N {
            let centre = self.power * self.previous[j];
            let (lo, hi) = ((centre - half).max(-tau_max), (centre + half).min(tau_max));
            // An applied torque beyond the bound (a restored state, a lowered
            // tau_max) may leave no overlap: the nearest reachable torque.
            let (lo, hi) = if lo <= hi {
                (lo, hi)
            } else {
                let nearest = centre.clamp(-tau_max, tau_max);
                (nearest, nearest)
            };
            lower[j] = lo;
            upper[j] = hi;
        }
        let c = 1.0 - a;
        self.reach += a * self.magnitude;
        self.power *= c;
        self.magnitude *= c.abs();
        Some((lower, upper))
    }
}

/// The command that makes the motor apply `wanted` after `previous`, and
/// the torque it then applies: `wanted` itself unless the command had to be
/// clipped to `|tau| <= tau_max` (a non-finite `wanted` asks for zero).
pub(super) fn command<const N: usize>(
    a: f64,
    tau_max: f64,
    previous: &Vector<N>,
    wanted: &Vector<N>,
) -> (Vector<N>, Vector<N>) {
    if a == 1.0 {
        return (*wanted, *wanted);
    }
    let mut tau = Vector::<N>::zeros();
    let mut applied = Vector::<N>::zeros();
    for j in 0..N {
        let want = if wanted[j].is_finite() {
            wanted[j]
        } else {
            0.0
        };
        let t = ((want - (1.0 - a) * previous[j]) / a).clamp(-tau_max, tau_max);
        tau[j] = t;
        applied[j] = previous[j] + a * (t - previous[j]);
    }
    (tau, applied)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Stage k's interval is what k + 1 commands within the bound reach,
    /// within the bound: its ends are those of the extreme command
    /// sequences (all at one bound for a <= 1, alternating for a > 1).
    #[test]
    fn stage_bounds_are_the_reachable_torques() {
        let tau_max = 0.5;
        for a in [0.1, 0.25, 0.5, 1.0, 1.5, 1.9, 2.0] {
            for p in [-0.5, -0.2, 0.0, 0.3, 0.5] {
                let previous = Vector::<1>::new(p);
                let mut bounds = StageBounds::new(a, tau_max, &previous);
                for k in 0..30usize {
                    let (lo, hi) = bounds.next().unwrap();
                    // Extremes: the command that pushes u_k up most is
                    // +tau_max where the coefficient a c^(k-i) is positive.
                    let c = 1.0 - a;
                    let (mut up, mut down) = (p, p);
                    for i in 0..=k {
                        let sign = if c.powi((k - i) as i32) >= 0.0 {
                            1.0
                        } else {
                            -1.0
                        };
                        up = c * up + a * sign * tau_max;
                        down = c * down - a * sign * tau_max;
                    }
                    let want_hi = up.min(tau_max);
                    let want_lo = down.max(-tau_max);
                    assert!(
                        (hi[0] - want_hi).abs() < 1e-12,
                        "a {a} p {p} k {k}: {hi} vs {want_hi}"
                    );
                    assert!(
                        (lo[0] - want_lo).abs() < 1e-12,
                        "a {a} p {p} k {k}: {lo} vs {want_lo}"
                    );
                }
            }
        }
        // Immediate response: the plain bound, bit for bit.
        let (lo, hi) = StageBounds::new(1.0, 0.5, &Vector::<2>::new(0.4, -0.1))
            .next()
            .unwrap();
        assert_eq!(
            (lo, hi),
            (Vector::<2>::repeat(-0.5), Vector::<2>::repeat(0.5))
        );
    }

    /// The command makes the motor apply the wanted torque whenever stage
    /// 0's interval holds it, and stays within its bound.
    #[test]
    fn the_command_makes_the_motor_apply_the_plan() {
        let tau_max = 0.5;
        for a in [0.1, 0.5, 1.0, 1.5, 2.0] {
            for p in [-0.5, -0.1, 0.2, 0.5] {
                let previous = Vector::<1>::new(p);
                let (lo, hi) = StageBounds::new(a, tau_max, &previous).next().unwrap();
                for s in 0..=10 {
                    let wanted = Vector::<1>::new(lo[0] + (hi[0] - lo[0]) * s as f64 / 10.0);
                    let (tau, applied) = command(a, tau_max, &previous, &wanted);
                    assert!(tau[0].abs() <= tau_max, "a {a}: command {tau}");
                    let motor = p + a * (tau[0] - p);
                    assert!(
                        (motor - wanted[0]).abs() < 1e-14,
                        "a {a} p {p}: {motor} vs {wanted}"
                    );
                    assert!((applied[0] - motor).abs() < 1e-15);
                }
                // Beyond reach: the command is clipped, the motor falls short.
                let (tau, applied) = command(a, tau_max, &previous, &Vector::<1>::new(hi[0] + 1.0));
                assert!((applied[0] - (p + a * (tau[0] - p))).abs() < 1e-15);
            }
        }
    }
}
