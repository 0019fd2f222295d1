//! A controller defined by FMU parameter names and values (what the C API's
//! `eigenmpc_create_named` takes, and what `eigenmpc modes
//! --fmu-start-values` writes): the FMU's own table gives the names, the
//! ranges and the defaults, so the C API needs no field per parameter.

use super::settings::Settings;
use super::{ControllerProduct, description, table};
use eigenmpc::mpc::Variant;
use fmi2_slave::table::named_value;

/// The settings of product `P` with the parameters `(name, value)` set over
/// its defaults, each checked as `fmi2SetReal` / `fmi2SetInteger` would
/// check it (Integer and enumeration parameters take integral values,
/// Boolean ones 0 or 1).
/// Refused, naming the variable: an unknown name, a variable that is not a
/// parameter, a value out of range or not integral where it must be.
pub fn settings_from_named<P: ControllerProduct<N>, const N: usize>(
    values: &[(&str, f64)],
) -> Result<Settings<N>, String> {
    table::table::<N>().settings_from_named(
        &description::<P, N>(),
        P::settings(Variant::Curved),
        values,
    )
}

/// Checks `name = x` as `fmi2Set*` would for product `P` (a value for a
/// tunable set later, e.g. by the C API's `eigenmpc_set_e_ref`).
pub fn check_named<P: ControllerProduct<N>, const N: usize>(
    name: &str,
    x: f64,
) -> Result<(), String> {
    named_value(&description::<P, N>(), name, x).map(|_| ())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controller::settings::ChartSource;
    use crate::products::{EigenMpc2, EigenMpc3};

    #[test]
    fn names_set_the_settings_and_bad_ones_are_refused() {
        let s = settings_from_named::<EigenMpc3, 3>(&[
            ("m[3]", 0.5),
            ("cf[2]", 0.08),
            ("chart_source", 2.0),
            ("variant", 1.0),
            ("E_ref", 3.0),
            ("adapt", 1.0),
        ])
        .unwrap();
        assert!(s.adapt);
        assert_eq!(s.model.mass, [1.0, 1.0, 0.5]);
        assert_eq!(s.model.joints[1].coulomb, 0.08);
        assert_eq!(s.chart_source, ChartSource::Parameters);
        assert_eq!(s.variant, Variant::Straight);
        assert_eq!(s.tuning.e_ref, 3.0);
        let defaults = settings_from_named::<EigenMpc2, 2>(&[]).unwrap();
        assert_eq!(defaults, EigenMpc2::settings(Variant::Curved));
        for (pairs, needle) in [
            (vec![("m[3]", 1.0)], "m[3] is not a variable of EigenMPC"),
            (vec![("q[1]", 0.1)], "q[1] is not a parameter of EigenMPC"),
            (vec![("horizon", 2.5)], "horizon = 2.5 must be an integer"),
            (
                vec![("chart_source", 3.0)],
                "chart_source = 3 is above its maximum",
            ),
            (
                vec![("m[1]", f64::NAN)],
                "m[1] = NaN is not a finite number",
            ),
            (vec![("tau_max", 0.0)], "tau_max = 0 is below its minimum"),
            (vec![("adapt", 0.5)], "adapt = 0.5 must be 0 or 1"),
        ] {
            let e = settings_from_named::<EigenMpc2, 2>(&pairs).unwrap_err();
            assert!(e.contains(needle), "{e}");
        }
    }
}
