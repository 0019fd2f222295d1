//! Unit definitions of the FMUs (`<UnitDefinitions>`).

use fmi2_slave::{Unit, Variable};

/// Every unit a variable of these FMUs may use.
pub fn all() -> Vec<Unit> {
    vec![
        Unit::new("rad", 0, 0, 0, 1),
        Unit::new("rad/s", 0, 0, -1, 1),
        Unit::new("rad/s2", 0, 0, -2, 1),
        Unit::new("N.m", 1, 2, -2, 0),
        Unit::new("J", 1, 2, -2, 0),
        Unit::new("1/J", -1, -2, 2, 0),
        Unit::new("s", 0, 0, 1, 0),
        Unit::new("kg", 1, 0, 0, 0),
        Unit::new("m", 0, 1, 0, 0),
        Unit::new("m/s2", 0, 1, -2, 0),
        Unit::new("kg.m2", 1, 2, 0, 0),
        Unit::new("N.m.s/rad", 1, 2, -1, -1),
        Unit::new("N.m/rad", 1, 2, -2, -1),
        Unit::new("s/rad", 0, 0, 1, -1),
    ]
}

/// The units `variables` use, in the order of [`all`].
pub fn used_by(variables: &[Variable]) -> Vec<Unit> {
    all()
        .into_iter()
        .filter(|u| variables.iter().any(|v| v.unit.as_deref() == Some(&u.name)))
        .collect()
}
