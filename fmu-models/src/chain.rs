//! The rigid-link chain as FMU parameters, shared by the controller's model
//! and the plant: per link `m[j]`, `l[j]`, `r[j]`, `I[j]`; per joint
//! `Ir[j]`, `gr[j]`, `b[j]`, `cf[j]`, `k[j]`, `q_rest[j]`; `g` and
//! `coulomb_sharpness` (the model of `eigenmpc::mechanics::PlanarChain`).
//!
//! A start value cannot depend on another parameter, so the centre of mass
//! and the inertia default to a sentinel: a negative `r[j]` means "at the
//! tip" (`r = l`), a negative `I[j]` means "a point mass at the centre of
//! mass" (`I = m r^2` about the joint). The defaults are the paper's point
//! masses at the link tips exactly.

use eigenmpc::mechanics::{Joint, Link, ParamsError, PlanarChain, PlanarChainParams};
use fmi2_slave::table::{Field, Row, Shape};

/// Sentinel value of `r[j]` (at the tip) and `I[j]` (point mass) (any negative value).
pub const POINT_MASS: f64 = -1.0;

/// Group tag of the chain rows (the start-value files hold them).
pub const MODEL_GROUP: &str = "model";

/// The chain as its FMU parameters hold it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChainParameters<const N: usize> {
    /// Link masses `m[j]` (kg).
    pub mass: [f64; N],
    /// Link lengths `l[j]` (m).
    pub length: [f64; N],
    /// Centre-of-mass distances from the joint `r[j]` (m); negative: at the tip.
    pub com: [f64; N],
    /// Link inertias about the joint axis `I[j]` (kg m^2); negative: `m r^2`.
    pub inertia: [f64; N],
    /// Motors, friction and springs per joint.
    pub joints: [Joint; N],
    /// Gravity `g` (m/s^2).
    pub gravity: f64,
    /// Slope of the smooth Coulomb law `cf atan(coulomb_sharpness qd)` (s/rad).
    pub coulomb_sharpness: f64,
}

impl<const N: usize> Default for ChainParameters<N> {
    /// The library's default chain (the paper's point masses) with the sentinels.
    fn default() -> Self {
        let p = PlanarChainParams::<N>::default();
        Self {
            mass: p.links.map(|l| l.mass),
            length: p.links.map(|l| l.length),
            com: [POINT_MASS; N],
            inertia: [POINT_MASS; N],
            joints: p.joints,
            gravity: p.gravity,
            coulomb_sharpness: p.coulomb_sharpness,
        }
    }
}

impl<const N: usize> ChainParameters<N> {
    /// Point masses at the link tips.
    pub fn point_masses(mass: [f64; N], length: [f64; N], gravity: f64) -> Self {
        Self {
            mass,
            length,
            gravity,
            ..Self::default()
        }
    }

    /// The parameters as FMU values. A centre of mass behind the joint
    /// (`r < 0`) cannot be expressed (negative `r[j]` is the sentinel).
    pub fn from_params(p: &PlanarChainParams<N>) -> Result<Self, String> {
        let mut out = Self {
            mass: p.links.map(|l| l.mass),
            length: p.links.map(|l| l.length),
            com: [POINT_MASS; N],
            inertia: [POINT_MASS; N],
            joints: p.joints,
            gravity: p.gravity,
            coulomb_sharpness: p.coulomb_sharpness,
        };
        for (j, link) in p.links.iter().enumerate() {
            if link.com < 0.0 {
                return Err(format!(
                    "r[{}] = {} < 0 (centre of mass behind the joint) cannot be an FMU \
                     parameter: a negative r[{}] means \"at the tip\"",
                    j + 1,
                    link.com,
                    j + 1
                ));
            }
            if link.com != link.length {
                out.com[j] = link.com;
            }
            if link.inertia != 0.0 {
                out.com[j] = link.com;
                out.inertia[j] = link.inertia_about_joint();
            }
        }
        Ok(out)
    }

    /// The library's parameters (sentinels resolved).
    pub fn params(&self) -> PlanarChainParams<N> {
        PlanarChainParams {
            links: std::array::from_fn(|j| {
                let (m, l) = (self.mass[j], self.length[j]);
                let r = if self.com[j] < 0.0 { l } else { self.com[j] };
                if self.inertia[j] < 0.0 {
                    Link {
                        mass: m,
                        length: l,
                        com: r,
                        inertia: 0.0,
                    }
                } else {
                    Link::with_inertia_about_joint(m, l, r, self.inertia[j])
                }
            }),
            joints: self.joints,
            gravity: self.gravity,
            coulomb_sharpness: self.coulomb_sharpness,
        }
    }

    /// Builds the chain; the message names the FMU parameter (`I[2]`).
    pub fn build(&self) -> Result<PlanarChain<N>, String> {
        PlanarChain::new(self.params()).map_err(|e| params_error(&e))
    }
}

/// The core's parameter name (`q_rest2`) as the FMU's (`q_rest[2]`).
pub fn fmu_name(core: &str) -> String {
    let digits = core.len() - core.trim_end_matches(|c: char| c.is_ascii_digit()).len();
    if digits == 0 || digits == core.len() {
        core.to_string()
    } else {
        let (base, j) = core.split_at(core.len() - digits);
        format!("{base}[{j}]")
    }
}

/// A [`ParamsError`] in the FMU's names.
pub fn params_error(e: &ParamsError) -> String {
    match e {
        ParamsError::Invalid {
            name,
            value,
            reason,
        } => format!(
            "model parameter {} = {value} is invalid: {reason}",
            fmu_name(name)
        ),
        other => format!("model parameters: {other}"),
    }
}

/// Settings that hold a chain.
pub trait HasChain<const N: usize> {
    /// The chain.
    fn chain(&self) -> &ChainParameters<N>;
    /// The chain, mutable.
    fn chain_mut(&mut self) -> &mut ChainParameters<N>;
}

/// The point-mass rows `m[j]`, `l[j]`, `g` (`whose`: description prefix).
pub fn point_mass_rows<S: HasChain<N>, const N: usize>(whose: &str) -> Vec<Row<S>> {
    vec![
        Row::<S>::real("m", Shape::Joints)
            .parameter(Field::real(
                |s, e| s.chain().mass[e.j],
                |s, e, v| s.chain_mut().mass[e.j] = v,
            ))
            .unit("kg")
            .range(1e-6, 1e6)
            .describe(format!("{whose}mass of link {{j}}"))
            .group(MODEL_GROUP),
        Row::<S>::real("l", Shape::Joints)
            .parameter(Field::real(
                |s, e| s.chain().length[e.j],
                |s, e, v| s.chain_mut().length[e.j] = v,
            ))
            .unit("m")
            // Shorter links swing so fast (sqrt(g / l)) that one step of
            // the plant's integrator takes seconds.
            .range(1e-3, 1e3)
            .describe(format!("{whose}length of link {{j}}, joint to joint"))
            .group(MODEL_GROUP),
        Row::<S>::real("g", Shape::Scalar)
            .parameter(Field::real(
                |s, _| s.chain().gravity,
                |s, _, v| s.chain_mut().gravity = v,
            ))
            .unit("m/s2")
            .range(0.0, 1e3)
            .describe(format!("{whose}gravitational acceleration (along -y)"))
            .group(MODEL_GROUP),
    ]
}

/// The rigid-link, motor, friction and spring rows (`whose`: description prefix).
pub fn rigid_rows<S: HasChain<N>, const N: usize>(whose: &str) -> Vec<Row<S>> {
    fn joint<S: HasChain<N>, const N: usize>(
        name: &'static str,
        unit: &'static str,
        (min, max): (f64, f64),
        get: fn(&S, fmi2_slave::table::Element) -> f64,
        set: fn(&mut S, fmi2_slave::table::Element, f64),
        what: String,
    ) -> Row<S> {
        let row = Row::<S>::real(name, Shape::Joints).parameter(Field::real(get, set));
        let row = if unit.is_empty() { row } else { row.unit(unit) };
        row.range(min, max).describe(what).group(MODEL_GROUP)
    }
    vec![
        Row::<S>::real("r", Shape::Joints)
            .parameter(Field::real(
                |s, e| s.chain().com[e.j],
                |s, e, v| s.chain_mut().com[e.j] = v,
            ))
            .unit("m")
            .range(-1.0, 1e3)
            .describe(format!(
                "{whose}distance from joint {{j}} to the centre of mass of link {{j}}; \
                 negative (default): at the tip, r[{{j}}] = l[{{j}}]"
            ))
            .summary(format!(
                "{whose}joint-to-COM distance of link j; negative (default): at the tip"
            ))
            .start_text("-1 (at the tip)")
            .group(MODEL_GROUP),
        Row::<S>::real("I", Shape::Joints)
            .parameter(Field::real(
                |s, e| s.chain().inertia[e.j],
                |s, e, v| s.chain_mut().inertia[e.j] = v,
            ))
            .unit("kg.m2")
            .range(-1.0, 1e6)
            .describe(format!(
                "{whose}inertia of link {{j}} about its joint axis (contains m r^2); \
                 negative (default): a point mass at the centre of mass, I[{{j}}] = m[{{j}}] r[{{j}}]^2"
            ))
            .summary(format!(
                "{whose}inertia of link j about its joint axis; negative (default): point mass, m r^2"
            ))
            .start_text("-1 (point mass)")
            .group(MODEL_GROUP),
        joint(
            "Ir",
            "kg.m2",
            (0.0, 1e6),
            |s, e| s.chain().joints[e.j].rotor_inertia,
            |s, e, v| s.chain_mut().joints[e.j].rotor_inertia = v,
            format!(
                "{whose}rotor inertia of motor {{j}} before its gearbox (the motor sits on the \
                 previous link)"
            ),
        ),
        joint(
            "gr",
            "",
            (1e-6, 1e6),
            |s, e| s.chain().joints[e.j].gear_ratio,
            |s, e, v| s.chain_mut().joints[e.j].gear_ratio = v,
            format!("{whose}gear ratio of motor {{j}} (motor turns per joint turn)"),
        ),
        joint(
            "b",
            "N.m.s/rad",
            (0.0, 1e6),
            |s, e| s.chain().joints[e.j].viscous,
            |s, e, v| s.chain_mut().joints[e.j].viscous = v,
            format!("{whose}viscous friction at joint {{j}}, b qd"),
        ),
        joint(
            "cf",
            "N.m",
            (0.0, 1e6),
            |s, e| s.chain().joints[e.j].coulomb,
            |s, e, v| s.chain_mut().joints[e.j].coulomb = v,
            format!("{whose}Coulomb friction at joint {{j}}, cf atan(coulomb_sharpness qd)"),
        ),
        joint(
            "k",
            "N.m/rad",
            (0.0, 1e9),
            |s, e| s.chain().joints[e.j].stiffness,
            |s, e, v| s.chain_mut().joints[e.j].stiffness = v,
            format!("{whose}spring stiffness at joint {{j}} (0: no spring)"),
        ),
        joint(
            "q_rest",
            "rad",
            (-1e3, 1e3),
            |s, e| s.chain().joints[e.j].rest_angle,
            |s, e, v| s.chain_mut().joints[e.j].rest_angle = v,
            format!("{whose}rest angle of the spring at joint {{j}}"),
        ),
        Row::<S>::real("coulomb_sharpness", Shape::Scalar)
            .parameter(Field::real(
                |s, _| s.chain().coulomb_sharpness,
                |s, _, v| s.chain_mut().coulomb_sharpness = v,
            ))
            .unit("s/rad")
            .range(1e-3, 1e6)
            .describe(format!(
                "{whose}slope k of the smooth Coulomb law cf atan(k qd)"
            ))
            .group(MODEL_GROUP),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_paper_point_masses_exactly() {
        assert_eq!(
            ChainParameters::<2>::default().params(),
            PlanarChainParams::<2>::default()
        );
        assert_eq!(
            ChainParameters::<3>::default().params(),
            PlanarChainParams::<3>::default()
        );
        let p = ChainParameters::<2>::point_masses([2.0, 0.5], [1.5, 0.8], 3.0);
        assert_eq!(
            p.params(),
            PlanarChainParams::point_masses([2.0, 0.5], [1.5, 0.8], 3.0)
        );
    }

    #[test]
    fn inertia_about_the_joint_is_converted_and_round_trips() {
        let p = ChainParameters::<2> {
            mass: [0.56, 0.6],
            length: [0.3, 0.2],
            com: [0.3, 0.2],
            inertia: [0.0529, 0.0252],
            ..Default::default()
        };
        let q = p.params();
        assert!((q.links[0].inertia - (0.0529 - 0.56 * 0.09)).abs() < 1e-15);
        assert!((q.links[1].inertia_about_joint() - 0.0252).abs() < 1e-15);
        let back = ChainParameters::from_params(&q).unwrap();
        assert!((back.inertia[0] - 0.0529).abs() < 1e-15);
        assert_eq!(back.com, [0.3, 0.2]);
        // point mass at the COM: r given, I sentinel
        let p = ChainParameters::<2> {
            com: [0.5, 0.7],
            ..Default::default()
        };
        let q = p.params();
        assert_eq!((q.links[0].com, q.links[0].inertia), (0.5, 0.0));
        assert_eq!(ChainParameters::from_params(&q).unwrap(), p);
        assert_eq!(
            ChainParameters::from_params(&PlanarChainParams::<3>::default()).unwrap(),
            ChainParameters::<3>::default()
        );
        let mut q = PlanarChainParams::<2>::default();
        q.links[1].com = -0.1;
        assert!(
            ChainParameters::from_params(&q)
                .unwrap_err()
                .contains("r[2] = -0.1 < 0")
        );
    }

    #[test]
    fn core_errors_name_the_fmu_parameter() {
        assert_eq!(fmu_name("q_rest2"), "q_rest[2]");
        assert_eq!(fmu_name("I1"), "I[1]");
        assert_eq!(fmu_name("g"), "g");
        assert_eq!(fmu_name("coulomb_sharpness"), "coulomb_sharpness");
        let mut p = ChainParameters::<2>::default();
        p.com[1] = 0.0; // point mass on the axis: no inertia about the joint
        let e = p.build().unwrap_err();
        assert!(e.starts_with("model parameter I[2] = 0 is invalid"), "{e}");
    }
}
