//! A sweep split over machines: each worker runs a contiguous part of the
//! spec's runs (`eigenmpc sweep --only FROM..TO --rows-out FILE`) and
//! writes one [`Record`] per run; the records of all parts are then merged
//! (`eigenmpc sweep --from-rows FILE ...`) into the outputs one local sweep
//! writes, from the same code. The Python/Dask runner works this way, so the
//! spec, its random sample, the closed loop and the metrics exist once, here.

use super::Metrics;
use super::report::Row;
use serde::{Deserialize, Deserializer, Serialize};
use std::ops::Range;

/// One finished run as a worker writes it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Record {
    /// Index of the run in the spec's order.
    pub run: usize,
    /// Its swept names and values (checked against the spec when merged).
    pub parameters: Vec<(String, f64)>,
    /// The metrics, or ...
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub metrics: Option<Metrics>,
    /// ... why the run failed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

impl Record {
    /// The record of run `run` with `values` and its outcome.
    pub fn new(run: usize, values: &[(String, f64)], outcome: &Result<Metrics, String>) -> Self {
        Self {
            run,
            parameters: values.to_vec(),
            metrics: outcome.as_ref().ok().cloned(),
            error: outcome.as_ref().err().cloned(),
        }
    }
}

/// Parses `FROM..TO` (runs FROM to TO-1, as the spec orders them).
pub fn parse_range(text: &str, runs: usize) -> Result<Range<usize>, String> {
    let (from, to) = text
        .split_once("..")
        .ok_or_else(|| format!("--only {text}: expected FROM..TO (run indices, TO excluded)"))?;
    let number = |t: &str| {
        t.trim()
            .parse::<usize>()
            .map_err(|_| format!("--only {text}: '{}' is not a run index", t.trim()))
    };
    let (from, to) = (number(from)?, number(to)?);
    if from >= to || to > runs {
        return Err(format!(
            "--only {text}: needs FROM < TO <= {runs} (the spec has {runs} runs)"
        ));
    }
    Ok(from..to)
}

/// The sweep's rows from the records of its parts: every run of `runs`
/// exactly once, with the spec's values (a record of another spec is
/// refused, naming the run).
pub fn merge(runs: &[Vec<(String, f64)>], records: Vec<Record>) -> Result<Vec<Row>, String> {
    let mut slots: Vec<Option<Row>> = vec![None; runs.len()];
    for r in records {
        let slot = slots.get_mut(r.run).ok_or_else(|| {
            format!(
                "record of run {}: the spec has {} runs (another spec?)",
                r.run,
                runs.len()
            )
        })?;
        if r.parameters != runs[r.run] {
            return Err(format!(
                "record of run {}: its values {:?} are not the spec's {:?} (another spec?)",
                r.run, r.parameters, runs[r.run]
            ));
        }
        if slot.is_some() {
            return Err(format!("run {} has two records", r.run));
        }
        let outcome = match (r.metrics, r.error) {
            (Some(m), None) => Ok(m),
            (None, Some(e)) => Err(e),
            _ => {
                return Err(format!(
                    "record of run {}: needs metrics or an error",
                    r.run
                ));
            }
        };
        *slot = Some(Row {
            values: r.parameters,
            outcome,
        });
    }
    let missing: Vec<String> = slots
        .iter()
        .enumerate()
        .filter(|(_, s)| s.is_none())
        .map(|(i, _)| i.to_string())
        .collect();
    if !missing.is_empty() {
        return Err(format!("no record of run(s) {}", missing.join(", ")));
    }
    Ok(slots.into_iter().flatten().collect())
}

/// A number JSON wrote as `null` (serde_json writes NaN and the infinities
/// so) reads back as NaN.
pub(super) fn number<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// [`number`] for each element.
pub(super) fn numbers<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
    Ok(Vec::<Option<f64>>::deserialize(d)?
        .into_iter()
        .map(|v| v.unwrap_or(f64::NAN))
        .collect())
}

/// [`number`] for a pair.
pub(super) fn pair<'de, D: Deserializer<'de>>(d: D) -> Result<[f64; 2], D::Error> {
    let [a, b] = <[Option<f64>; 2]>::deserialize(d)?;
    Ok([a.unwrap_or(f64::NAN), b.unwrap_or(f64::NAN)])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn metrics(t: f64) -> Metrics {
        Metrics {
            time_to_band: Some(t),
            success: true,
            final_energy_error: 0.1 + 0.2,
            mean_energy_error: f64::NAN,
            rms_torque: vec![1.0 / 3.0, f64::NAN, 2e-17],
            distance_to_mode: None,
            failed_solves: 0,
            model_updates: 2,
            solve_time: [1.2345678901234567e-4, f64::NAN],
        }
    }

    #[test]
    fn records_round_trip_bit_for_bit_and_merge_in_the_spec_order() {
        let runs = vec![vec![("controller.E_ref".to_string(), 0.1 + 0.7)]; 3];
        let records = vec![
            Record::new(2, &runs[2], &Err("diverged".into())),
            Record::new(0, &runs[0], &Ok(metrics(3.7))),
            Record::new(1, &runs[1], &Ok(metrics(1.0 / 7.0))),
        ];
        let text = serde_json::to_string(&records).unwrap();
        let back: Vec<Record> = serde_json::from_str(&text).unwrap();
        let rows = merge(&runs, back).unwrap();
        let m = rows[1].outcome.as_ref().unwrap();
        assert_eq!(m.time_to_band, Some(1.0 / 7.0));
        assert_eq!(m.final_energy_error.to_bits(), (0.1f64 + 0.2).to_bits());
        assert_eq!(m.rms_torque[0].to_bits(), (1.0f64 / 3.0).to_bits());
        assert!(m.rms_torque[1].is_nan() && m.mean_energy_error.is_nan());
        assert_eq!(m.solve_time[0], 1.2345678901234567e-4);
        assert_eq!(rows[2].outcome, Err("diverged".into()));
        assert_eq!(rows[0].values, runs[0]);
    }

    #[test]
    fn a_missing_twice_given_or_foreign_run_is_refused() {
        let runs = vec![
            vec![("model.m[2]".to_string(), 1.0)],
            vec![("model.m[2]".to_string(), 2.0)],
        ];
        let ok = |i: usize| Record::new(i, &runs[i], &Ok(metrics(1.0)));
        assert_eq!(
            merge(&runs, vec![ok(1)]).unwrap_err(),
            "no record of run(s) 0"
        );
        assert_eq!(
            merge(&runs, vec![ok(0), ok(1), ok(1)]).unwrap_err(),
            "run 1 has two records"
        );
        let mut foreign = ok(0);
        foreign.parameters[0].1 = 1.5;
        assert!(
            merge(&runs, vec![foreign, ok(1)])
                .unwrap_err()
                .contains("not the spec's")
        );
        assert!(
            merge(
                &runs,
                vec![ok(0), Record::new(5, &runs[0], &Ok(metrics(1.0)))]
            )
            .unwrap_err()
            .contains("the spec has 2 runs")
        );
        assert_eq!(parse_range("0..2", 2), Ok(0..2));
        assert!(
            parse_range("1..3", 2)
                .unwrap_err()
                .contains("FROM < TO <= 2")
        );
        assert!(
            parse_range("1-2", 2)
                .unwrap_err()
                .contains("expected FROM..TO")
        );
    }
}
