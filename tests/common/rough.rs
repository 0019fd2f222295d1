//! A rough model of a robot, shared by the adaptation tests.

use eigenmpc::math;
use eigenmpc::mechanics::{PlanarChainParams, Vector};

/// A rough model of a laboratory robot, as a user's CAD model is: masses
/// +15 / -15 %, centres of mass -12 / +12 %, inertias +20 / -10 % (links
/// 1 / 2), no friction (as `examples/adapt_scenarios.rs`).
pub fn rough(robot: &PlanarChainParams<2>) -> PlanarChainParams<2> {
    let mut p = *robot;
    let f = [[1.15, 0.88, 1.2], [0.85, 1.12, 0.9]];
    for ((link, joint), f) in p.links.iter_mut().zip(&mut p.joints).zip(f) {
        link.mass *= f[0];
        link.com *= f[1];
        link.inertia *= f[2];
        joint.viscous = 0.0;
        joint.coulomb = 0.0;
    }
    p
}

/// The torque held over the sample from `t` (s) that excites a 2-joint lab
/// robot in open loop: a sum of sines (N m).
#[allow(dead_code)] // not every test that shares this file drives in open loop
pub fn probing_torque(t: f64) -> Vector<2> {
    Vector::<2>::new(
        0.3 * math::sin(2.3 * t) + 0.1 * math::cos(7.1 * t),
        0.2 * math::sin(3.7 * t),
    )
}
