//! The FMUs this workspace ships as typed products of the generic models:
//! the 2-joint pair `EigenMPC` / `DoublePendulum` (the paper's) and the
//! 3-link pair `EigenMPC3` / `TriplePendulum`. The archives are exports of
//! `robots/paper-double-pendulum.yml` and `robots/three-link-point-masses.yml`
//! (fmu-build); these products carry the same names, descriptions and
//! defaults (the checked-in model descriptions' tests hold them equal) for
//! the C API's defaults, the header's constants and the tests.

use crate::controller::settings::{CHART_COEFFICIENTS, Settings};
use crate::controller::{ControllerFmu, ControllerProduct};
use crate::plant::{PlantFmu, PlantProduct};
use eigenmpc::mpc::Variant;
use fmi2_slave::table::RowDoc;

/// The paper's controller for the double pendulum.
pub struct EigenMpc2;
/// The controller for the 3-link chain.
pub struct EigenMpc3;
/// The paper's double pendulum.
pub struct DoublePendulumPlant;
/// The 3-link chain.
pub struct TriplePendulumPlant;

/// `EigenMPC.fmu`.
pub type EigenMpcFmu = ControllerFmu<EigenMpc2, 2, 4, 11, 15>;
/// `EigenMPC3.fmu`.
pub type EigenMpc3Fmu = ControllerFmu<EigenMpc3, 3, 6, 18, 24>;
/// `DoublePendulum.fmu`.
pub type DoublePendulumFmu = PlantFmu<DoublePendulumPlant, 2, 4>;
/// `TriplePendulum.fmu`.
pub type TriplePendulumFmu = PlantFmu<TriplePendulumPlant, 3, 6>;

/// Unit in-phase eigenvector of the paper's double pendulum
/// (m = l = 1, g = 9.81), as the shipped `EigenMPC.fmu` has it: the export of
/// `robots/paper-double-pendulum.yml` (fmu-build); the checked-in model
/// description's test holds the two equal.
pub const DEFAULT_EIGENVECTOR: [f64; 2] = [0.923879532511287, 0.38268343236508934];

/// Chart of the paper's 14 J in-phase eigenmode (degree 9) of the default
/// model, per joint the coefficients of `s^0..s^9`: pasted from the shipped
/// `EigenMPC.fmu` (`resources/eigenmpc-export.json`); a test recomputes it.
/// (The even powers vanish up to fitting noise: the mode is symmetric.)
pub const DEFAULT_CHART_14J: [[f64; CHART_COEFFICIENTS]; 2] = [
    [
        -1.5055939285161347e-13,
        0.5531221059476471,
        -5.490335235903476e-13,
        0.9749828065062226,
        4.2224040212916485e-12,
        -1.0166322311774436,
        -6.957196857401013e-12,
        0.9510679594842331,
        4.271479025362353e-12,
        -0.37213572933987865,
    ],
    [
        3.6356170982448274e-13,
        1.2777710399255786,
        1.3229187066417022e-12,
        -2.3538167145479116,
        -1.0189824707907194e-11,
        2.4543673204542307,
        1.6798404690258843e-11,
        -2.296081166525402,
        -1.0317003307393476e-11,
        0.8984151248159781,
    ],
];

/// Energy of the 3-link controller's default chart (J).
pub const DEFAULT_E_REF_3: f64 = 14.0;

/// Unit in-phase eigenvector of the default 3-link chain (1 kg point masses
/// at the tips of 1 m links, g = 9.81), as the shipped `EigenMPC3.fmu` has
/// it (the export of `robots/three-link-point-masses.yml`); a test recomputes
/// it.
pub const DEFAULT_EIGENVECTOR_3: [f64; 3] =
    [0.912747024085715, 0.2666250173455187, 0.30952216422765755];

/// Chart of the default 3-link chain's in-phase eigenmode at 14 J (degree
/// 9), pasted from the shipped `EigenMPC3.fmu`; a test recomputes it.
pub const DEFAULT_CHART_3_14J: [[f64; CHART_COEFFICIENTS]; 3] = [
    [
        5.0499399023789496e-14,
        0.7530956839278241,
        -7.244919883791611e-13,
        0.513632106265532,
        -1.7846538845911892e-12,
        0.5591726398590857,
        2.4006990632331076e-11,
        -1.3425680845171615,
        -3.9608025694434225e-11,
        0.6441743726407415,
    ],
    [
        -2.401268890268943e-13,
        0.2074450818804149,
        1.5748048968878694e-12,
        0.8987682977255479,
        7.702125025492527e-12,
        -2.073027942331112,
        3.9824763399512146e-11,
        -0.9656515470037194,
        -1.8742320617655582e-10,
        2.921907055676568,
    ],
    [
        5.79861968042917e-14,
        0.8312946109385055,
        7.844872580089715e-13,
        -2.2888515632061854,
        -1.4657875058276735e-12,
        0.1367848671064776,
        -1.0467854978890336e-10,
        4.79090693858663,
        2.7771059652846974e-10,
        -4.416555319818425,
    ],
];

/// `modelIdentifier` of [`Exported`]'s description without a spec
/// (documentation only: an exported robot's FMU is named by its spec).
pub const BINARY_NAME: &str = "EigenMPCRobot";

/// The product behind every exported FMU and every joint count without a
/// shipped product: the library's defaults (an exported robot's spec, or
/// the C API's named values, replace them before anything runs).
pub struct Exported;

impl<const N: usize> ControllerProduct<N> for Exported {
    const MODEL_NAME: &'static str = BINARY_NAME;
    const DESCRIPTION: &'static str = "EigenMPC controller of an exported robot";
    const E_REF: f64 = 1.0;
    const EIGENVECTOR: [f64; N] = unit_first::<N>();
    const CHART: [[f64; CHART_COEFFICIENTS]; N] = [[0.0; CHART_COEFFICIENTS]; N];
}

impl<const N: usize> PlantProduct<N> for Exported {
    const MODEL_NAME: &'static str = BINARY_NAME;
    const DESCRIPTION: &'static str = "an exported robot as a plant";
}

/// `(1, 0, ..., 0)`: a nonzero placeholder eigenvector.
const fn unit_first<const N: usize>() -> [f64; N] {
    let mut v = [0.0; N];
    if N > 0 {
        v[0] = 1.0;
    }
    v
}

impl ControllerProduct<2> for EigenMpc2 {
    const MODEL_NAME: &'static str = "EigenMPC";
    const DESCRIPTION: &'static str = "EigenMPC controller for the double pendulum: joint \
                                       angles and speeds in, joint torques out; excites the \
                                       nonlinear eigenmode at E_ref";
    const E_REF: f64 = 14.0;
    const EIGENVECTOR: [f64; 2] = DEFAULT_EIGENVECTOR;
    const CHART: [[f64; CHART_COEFFICIENTS]; 2] = DEFAULT_CHART_14J;
}

impl ControllerProduct<3> for EigenMpc3 {
    const MODEL_NAME: &'static str = "EigenMPC3";
    const DESCRIPTION: &'static str = "EigenMPC controller for a 3-link planar chain: joint \
                                       angles and speeds in, joint torques out; excites the \
                                       nonlinear eigenmode at E_ref";
    const E_REF: f64 = DEFAULT_E_REF_3;
    const EIGENVECTOR: [f64; 3] = DEFAULT_EIGENVECTOR_3;
    const CHART: [[f64; CHART_COEFFICIENTS]; 3] = DEFAULT_CHART_3_14J;
}

impl PlantProduct<2> for DoublePendulumPlant {
    const MODEL_NAME: &'static str = "DoublePendulum";
    const DESCRIPTION: &'static str = "Double pendulum of the EigenMPC paper (rigid links, \
                                       motors and friction optional): joint torques in, joint \
                                       angles, speeds and energy out; adaptive Dormand-Prince \
                                       inside doStep";
}

impl PlantProduct<3> for TriplePendulumPlant {
    const MODEL_NAME: &'static str = "TriplePendulum";
    const DESCRIPTION: &'static str = "Planar 3-link chain (point masses by default; rigid \
                                       links, motors and friction optional): joint torques in, \
                                       joint angles, speeds and energy out; adaptive \
                                       Dormand-Prince inside doStep";
}

/// The C header's value-reference and enumeration constants of the FMU
/// `model_identifier`, each prefixed with `prefix`.
pub fn c_defines(model_identifier: &str, prefix: &str) -> Result<String, String> {
    use crate::{controller, plant};
    match model_identifier {
        "EigenMPC" => controller::table::table::<2>().c_defines(prefix, model_identifier),
        "EigenMPC3" => controller::table::table::<3>().c_defines(prefix, model_identifier),
        "DoublePendulum" => plant::table::table::<2>().c_defines(prefix, model_identifier),
        "TriplePendulum" => plant::table::table::<3>().c_defines(prefix, model_identifier),
        other => Err(format!("no FMU {other}")),
    }
}

/// The controller FMUs' rows in documentation form, `(identifier, rows)`.
pub fn controller_docs() -> Vec<(&'static str, Vec<RowDoc>)> {
    use crate::controller::table::table;
    vec![
        (
            EigenMpc2::MODEL_NAME,
            table::<2>().docs(&EigenMpc2::settings(Variant::Curved)),
        ),
        (
            EigenMpc3::MODEL_NAME,
            table::<3>().docs(&EigenMpc3::settings(Variant::Curved)),
        ),
    ]
}

/// The plant FMUs' rows in documentation form, `(identifier, rows)`.
pub fn plant_docs() -> Vec<(&'static str, Vec<RowDoc>)> {
    use crate::plant::settings::PlantSettings;
    use crate::plant::table::table;
    vec![
        (
            DoublePendulumPlant::MODEL_NAME,
            table::<2>().docs(&PlantSettings::default()),
        ),
        (
            TriplePendulumPlant::MODEL_NAME,
            table::<3>().docs(&PlantSettings::default()),
        ),
    ]
}

/// The controller settings a handle of `N` joints starts from: the shipped
/// product's for 2 (`EigenMPC`) and 3 (`EigenMPC3`) joints, the library's
/// defaults otherwise (an exported robot's: chart computed from the model).
pub fn default_settings<const N: usize>(variant: Variant) -> Settings<N> {
    use std::any::Any;
    // A product exists for some counts only: the downcast is the identity
    // exactly when N is that count.
    let shipped: Option<Box<dyn Any>> = match N {
        2 => Some(Box::new(EigenMpc2::settings(variant))),
        3 => Some(Box::new(EigenMpc3::settings(variant))),
        _ => None,
    };
    shipped
        .and_then(|s| s.downcast::<Settings<N>>().ok())
        .map_or_else(
            || <Exported as ControllerProduct<N>>::settings(variant),
            |s| *s,
        )
}

/// The `N`-joint controller settings with the FMU parameters `(name, value)`
/// set over [`default_settings`], each checked as `fmi2Set*` would check it
/// (the C API's `eigenmpc_create_named` for any joint count).
pub fn settings_from_named<const N: usize>(values: &[(&str, f64)]) -> Result<Settings<N>, String> {
    let defaults = default_settings::<N>(Variant::Curved);
    let name = match N {
        2 => EigenMpc2::MODEL_NAME.to_string(),
        3 => EigenMpc3::MODEL_NAME.to_string(),
        n => format!("the {n}-joint controller"),
    };
    let d = crate::controller::description_with::<N>(&name, "", &defaults);
    crate::controller::table::table::<N>().settings_from_named(&d, defaults, values)
}

/// The `N`-joint plant settings with the FMU parameters `(name, value)` set
/// over the defaults, each checked as `fmi2Set*` would check it; messages
/// name the shipped plant (`DoublePendulum`, `TriplePendulum`) or the
/// count.
pub fn plant_settings_from_named<const N: usize>(
    values: &[(&str, f64)],
) -> Result<crate::plant::settings::PlantSettings<N>, String> {
    use crate::plant::settings::PlantSettings;
    let name = match N {
        2 => DoublePendulumPlant::MODEL_NAME.to_string(),
        3 => TriplePendulumPlant::MODEL_NAME.to_string(),
        n => format!("the {n}-joint plant"),
    };
    let defaults = PlantSettings::<N>::default();
    let d = crate::plant::description_with::<N>(&name, "", &defaults);
    crate::plant::table::table::<N>().settings_from_named(&d, defaults, values)
}

/// Checks `name = x` as `fmi2Set*` would for an `N`-joint controller (the
/// ranges do not depend on the product).
pub fn check_named<const N: usize>(name: &str, x: f64) -> Result<(), String> {
    fmi2_slave::table::named_value(&crate::controller::description::<Exported, N>(), name, x)
        .map(|_| ())
}
