//! The plant FMU's variable table for `N` joints (value references laid out
//! by [`fmi2_slave::table::Table::new`]; for two joints the layout of the
//! original `DoublePendulum.fmu`, pinned by a test). Add new rows at the end.

use super::settings::PlantSettings;
use crate::chain::{point_mass_rows, rigid_rows};
use fmi2_slave::table::{Deps, Field, Row, Shape, Table};

type Rw<const N: usize> = Row<PlantSettings<N>>;

/// The variable table of the `N`-joint plant.
pub fn table<const N: usize>() -> Table<PlantSettings<N>> {
    let mut rows = vec![
        Rw::<N>::real("tau", Shape::Joints)
            .input(0.0)
            .unit("N.m")
            .describe("Torque at joint {j}, held over the communication step")
            .summary("joint torques, held over a step"),
        Rw::<N>::real("q", Shape::Joints)
            .output()
            .unit("rad")
            .describe(
                "Angle of joint {j}: q[1] of link 1 from the downward vertical, q[j] of link j \
                 relative to link j-1",
            )
            .summary("link 1 from the downward vertical; link j relative to link j-1")
            .initially_depends_on(Deps::SameJoint("q0")),
        Rw::<N>::real("qd", Shape::Joints)
            .output()
            .unit("rad/s")
            .describe("Speed of joint {j}")
            .summary("joint speeds")
            .initially_depends_on(Deps::SameJoint("qd0")),
        Rw::<N>::real("energy", Shape::Scalar)
            .output()
            .unit("J")
            .describe("Total mechanical energy, zero at rest at the stable equilibrium")
            .summary("total energy, 0 at rest at the stable equilibrium (hanging down)")
            .initially_depends_on(Deps::Rows(vec![
                "m", "l", "g", "q0", "qd0", "r", "I", "Ir", "gr", "k", "q_rest",
            ])),
    ];
    rows.extend(point_mass_rows::<PlantSettings<N>, N>(""));
    rows.extend([
        Rw::<N>::real("damping", Shape::Joints)
            .parameter(Field::real(
                |s, e| s.damping[e.j],
                |s, e, v| s.damping[e.j] = v,
            ))
            .unit("N.m.s/rad")
            .range(0.0, 1e6)
            .describe(
                "Viscous friction at joint {j}: the former name of b[{j}] (set either; both \
                 nonzero and different is refused)",
            )
            .summary("viscous friction, the former name of `b[j]` (set either, not both)"),
        Rw::<N>::real("q0", Shape::Joints)
            .parameter(Field::real(|s, e| s.q0[e.j], |s, e, v| s.q0[e.j] = v))
            .unit("rad")
            .range(-1e3, 1e3)
            .describe("Initial angle q[{j}]")
            .summary("initial angles"),
        Rw::<N>::real("qd0", Shape::Joints)
            .parameter(Field::real(|s, e| s.qd0[e.j], |s, e, v| s.qd0[e.j] = v))
            .unit("rad/s")
            // Beyond any robot; keeps the energy and the work per step finite.
            .range(-1e3, 1e3)
            .describe("Initial speed qd[{j}]")
            .summary("initial speeds"),
        Rw::<N>::real("rtol", Shape::Scalar)
            .parameter(Field::real(
                |s, _| s.tolerances.rtol,
                |s, _, v| s.tolerances.rtol = v,
            ))
            .range(1e-14, 1e-2)
            .describe(
                "Relative tolerance of the adaptive integrator (at its start value, a tolerance \
                 given to fmi2SetupExperiment is used instead)",
            )
            .summary("integrator tolerances (relative)"),
        Rw::<N>::real("atol", Shape::Scalar)
            .parameter(Field::real(
                |s, _| s.tolerances.atol,
                |s, _, v| s.tolerances.atol = v,
            ))
            .range(1e-14, 1e-2)
            .describe("Absolute tolerance of the adaptive integrator")
            .summary("integrator tolerances (absolute)"),
    ]);
    rows.extend(rigid_rows::<PlantSettings<N>, N>(""));
    Table::new(N, rows)
}
