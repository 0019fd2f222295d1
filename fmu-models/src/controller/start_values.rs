//! The controller FMU's start values for a given robot and reference, from
//! the same table as the FMU (what `eigenmpc modes --fmu-start-values`
//! writes).

use super::settings::{CHART_COEFFICIENTS, ChartSource, Settings};
use super::table::{REFERENCE_GROUP, table};
use crate::chain::{ChainParameters, MODEL_GROUP};
use eigenmpc::mechanics::PlanarChainParams;
use eigenmpc::mpc::Variant;
use fmi2_slave::Value;

/// The start values (name, value) of the model parameters of `model`, in
/// table order (`m[j]`, `l[j]`, `g`, `r[j]`, `I[j]`, ...): what makes the
/// controller FMU's model (and, same names, the plant FMU) that robot.
/// Refused (the message names the variable): a model the FMU cannot
/// express, a value outside its variable's range.
pub fn model_start_values<const N: usize>(
    model: &PlanarChainParams<N>,
) -> Result<Vec<(String, Value)>, String> {
    let mut settings = Settings::<N>::paper(
        Variant::Curved,
        1.0,
        [1.0; N],
        [[0.0; CHART_COEFFICIENTS]; N],
    );
    settings.model = ChainParameters::from_params(model)?;
    settings.system()?;
    checked(&settings, |r| r.group == Some(MODEL_GROUP))
}

/// The start values of the rows `select` picks, each checked against its
/// variable's range.
fn checked<const N: usize>(
    settings: &Settings<N>,
    select: impl Fn(&fmi2_slave::table::Row<Settings<N>>) -> bool,
) -> Result<Vec<(String, Value)>, String> {
    let t = table::<N>();
    let values = t.start_values(settings, select);
    let variables = t.variables(settings);
    for (name, value) in &values {
        if let Some(v) = variables.iter().find(|v| &v.name == name) {
            v.check_value(*value)?;
        }
    }
    Ok(values)
}

/// The start values (name, value), in table order, that make the `N`-joint
/// controller FMU control `model` at `e_ref` along the chart
/// `X_j(s) = sum_k chart[j][k] s^k` in `s = c'q` with the unit eigenvector
/// `eigenvector`: `E_ref`, every model parameter (`m[j]`, `l[j]`, `g`,
/// `r[j]`, `I[j]`, `Ir[j]`, ...), `c[j]`, `chart.coef[j,k]` (zero-padded
/// to 10 powers) and `chart_source = parameters`, which makes the FMU use
/// this chart instead of computing its own.
///
/// Refused (the message names the variable): a model the FMU cannot
/// express or that is not physical, more than 10 coefficients per joint,
/// a value outside its variable's range, a chart that does not belong to
/// the eigenvector.
pub fn start_values<const N: usize>(
    model: &PlanarChainParams<N>,
    e_ref: f64,
    eigenvector: &[f64; N],
    chart: &[Vec<f64>; N],
) -> Result<Vec<(String, Value)>, String> {
    let mut settings = Settings::<N>::paper(
        Variant::Curved,
        e_ref,
        *eigenvector,
        [[0.0; CHART_COEFFICIENTS]; N],
    );
    settings.model = ChainParameters::from_params(model)?;
    settings.chart_source = ChartSource::Parameters;
    for (j, row) in chart.iter().enumerate() {
        if row.len() > CHART_COEFFICIENTS {
            return Err(format!(
                "the chart of joint {} has {} coefficients; the FMU takes at most {} (degree {})",
                j + 1,
                row.len(),
                CHART_COEFFICIENTS,
                CHART_COEFFICIENTS - 1
            ));
        }
        settings.chart[j][..row.len()].copy_from_slice(row);
    }
    let system = settings.system()?;
    settings.reference(&system)?;
    checked(&settings, |r| {
        matches!(r.group, Some(MODEL_GROUP) | Some(REFERENCE_GROUP))
    })
}
