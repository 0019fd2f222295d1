//! Output of a closed loop with online adaptation for people: the
//! base-parameter columns of the CSV (named as the controller FMU's
//! `estimate.*` outputs, so that a CSV and an FMU run read alike), the
//! summary of the final estimate against the plant's true values, and the
//! figure of the estimate over time (`eigenmpc simulate --adapt`).

use crate::report::{
    BLUE_DARK, ORANGE, PlotError, RED, draw_legend, number, padded_range, quiet_corner,
    with_backend, with_midpoints,
};
use eigenmpc::adapt::{AdaptationStatus, Refusal};
use eigenmpc::identify::BaseParameters;
use eigenmpc_fmu_models::controller::table::{ESTIMATE_ROWS, table};
use eigenmpc_fmu_models::enums::ADAPTATION_STATUS;
use nalgebra::SVector;
use plotters::prelude::*;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What the adaptation reported right after one sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptationSample<const NP: usize> {
    /// The identification's estimate (unconstrained, as the FMU's
    /// `estimate.*` outputs).
    pub estimate: SVector<f64, NP>,
    /// Base parameters of the model the controller uses from the next
    /// sample on.
    pub in_use: SVector<f64, NP>,
    /// What the adaptation is doing.
    pub status: AdaptationStatus,
    /// Models taken so far (reverts not subtracted).
    pub model_updates: usize,
    /// Candidate models refused so far, per reason (in the order of
    /// [`Refusal::ALL`]).
    pub refusals: [usize; 3],
    /// Models the supervisor took back so far.
    pub reverts: usize,
}

impl<const NP: usize> AdaptationSample<NP> {
    /// Candidates refused so far, all reasons (the FMU's `adapt_refused`).
    pub fn refused(&self) -> usize {
        self.refusals.iter().sum()
    }
}

/// One base parameter as the controller FMU names it.
#[derive(Clone, Debug, PartialEq)]
pub struct BaseParameterName {
    /// Symbol with its joints: `A[1,2]`, `G[1]`.
    pub symbol: String,
    /// Unit as the FMU declares it (`kg.m2`, `N.m`).
    pub unit: &'static str,
    /// What it is, for a panel title (`gravity amplitude`).
    pub meaning: &'static str,
}

impl BaseParameterName {
    /// The FMU's output name, `estimate.A[1,2]`.
    pub fn estimate_column(&self) -> String {
        format!("estimate.{}", self.symbol)
    }

    /// The column of the model in use, `in_use.A[1,2]`.
    pub fn in_use_column(&self) -> String {
        format!("in_use.{}", self.symbol)
    }

    /// The unit for people: `kg m²`, `N m s/rad`.
    pub fn unit_text(&self) -> String {
        self.unit.replace("m2", "m\u{b2}").replace('.', " ")
    }
}

/// The base parameters of an `N`-joint chain in the order of
/// [`eigenmpc::identify::BaseParameters`]'s vector, named and with units
/// from the controller FMU's variable table (`estimate.A[j,l]`,
/// `estimate.G[j]`, ...): one list, so that names and units cannot drift.
pub fn base_parameter_names<const N: usize>() -> Vec<BaseParameterName> {
    let t = table::<N>();
    let mut out = vec![];
    for name in ESTIMATE_ROWS {
        // Every name of ESTIMATE_ROWS is a row of the table (the FMU's
        // start-up depends on it, and its tests check it).
        let Some(row) = t.row(name) else { continue };
        let symbol = name.trim_start_matches("estimate.");
        let meaning = match symbol {
            "A" => "link inertia amplitude",
            "G" => "gravity amplitude",
            "Ir" => "rotor inertia",
            "b" => "viscous friction",
            "cf" => "Coulomb friction",
            _ => "",
        };
        for e in row.shape.elements(N) {
            out.push(BaseParameterName {
                symbol: row
                    .element_name(e)
                    .trim_start_matches("estimate.")
                    .to_string(),
                unit: row.unit.unwrap_or(""),
                meaning,
            });
        }
    }
    out
}

/// The name of `status` as the FMU's `adaptation_status` enumeration has
/// it (`learning`).
pub fn status_name(status: AdaptationStatus) -> &'static str {
    ADAPTATION_STATUS
        .items
        .iter()
        .find(|i| i.value == status)
        .map_or("?", |i| i.name)
}

/// The CSV header cells the adaptation adds: the estimate, the model in
/// use, then `model_updates`, `adapt_refused`, `adapt_reverts`,
/// `adaptation_status` (the FMU's outputs).
pub fn csv_columns(names: &[BaseParameterName]) -> Vec<String> {
    names
        .iter()
        .map(BaseParameterName::estimate_column)
        .chain(names.iter().map(BaseParameterName::in_use_column))
        .chain(
            [
                "model_updates",
                "adapt_refused",
                "adapt_reverts",
                "adaptation_status",
            ]
            .map(String::from),
        )
        .collect()
}

/// The CSV cells of one sample, in the order of [`csv_columns`].
pub fn csv_cells<const NP: usize>(a: &AdaptationSample<NP>) -> Vec<String> {
    a.estimate
        .iter()
        .chain(a.in_use.iter())
        .map(|v| v.to_string())
        .chain([
            a.model_updates.to_string(),
            a.refused().to_string(),
            a.reverts.to_string(),
            status_name(a.status).to_string(),
        ])
        .collect()
}

/// The error of `value` against the true `truth`: relative (%) when the
/// truth is not zero, else absolute in the parameter's unit.
pub fn error_text(value: f64, truth: f64, unit: &str) -> String {
    let diff = value - truth;
    if truth != 0.0 {
        let percent = 100.0 * diff / truth.abs();
        // Below 1e-9 % it is the round-off of the parameter file's numbers.
        if percent.abs() >= 0.01 || percent.abs() < 1e-9 {
            format!("{percent:+.2} %")
        } else {
            // "+0.00 %" would hide how close it is.
            format!("{percent:+.1e} %")
        }
    } else if diff == 0.0 {
        "0".into()
    } else if unit.is_empty() {
        format!("{diff:+.1e}")
    } else {
        format!("{diff:+.1e} {unit}")
    }
}

/// `A[1,1] + gr_1^2 Ir[1]`: the first motor turns with the first link, so
/// the kinetic energy has these two only in this sum (their energy
/// features are the same `qd_1^2 / 2`, scaled by `gr_1^2`), and the
/// identification can tell the sum only.
pub fn first_joint_inertia<const N: usize, const NP: usize>(
    theta: &SVector<f64, NP>,
    gear_ratio_1: f64,
) -> f64 {
    let b = BaseParameters::<N, NP> { theta: *theta };
    b.inertia_amplitude(0, 0) + gear_ratio_1 * gear_ratio_1 * b.rotor_inertia(0)
}

/// The adaptation's part of the printed summary: the counts and, per base
/// parameter, the plant's true value (when known: a plant with joint
/// springs has none), the model at the start, the final estimate and the
/// final model in use with their errors; then the one combination of
/// `A[1,1]` and `Ir[1]` that is identifiable ([`first_joint_inertia`],
/// `gear_ratio_1` the model's).
pub fn summary_text<const N: usize, const NP: usize>(
    names: &[BaseParameterName],
    samples: &[AdaptationSample<NP>],
    start: &SVector<f64, NP>,
    truth: Option<&SVector<f64, NP>>,
    gear_ratio_1: f64,
) -> String {
    let mut out = String::new();
    let Some(last) = samples.last() else {
        return out;
    };
    let reasons: Vec<String> = Refusal::ALL
        .iter()
        .zip(last.refusals)
        .map(|(r, n)| {
            let reason = match r {
                Refusal::NotPhysical => "not physical",
                Refusal::NotBetter => "not better",
                Refusal::ModelFailed => "model failed",
            };
            format!("{reason} {n}")
        })
        .collect();
    let _ = writeln!(
        out,
        "adaptation:                      models taken {}, refused {} ({}), taken back {}; status {}",
        last.model_updates,
        last.refused(),
        reasons.join(", "),
        last.reverts,
        status_name(last.status)
    );
    let _ = writeln!(
        out,
        "  {:<18} {:>11} {:>11} {:>11} {:>14} {:>11} {:>14}",
        "base parameter", "plant", "model start", "estimate", "error", "model used", "error"
    );
    for (i, name) in names.iter().enumerate().take(NP) {
        let label = format!("{} ({})", name.symbol, name.unit_text());
        let (plant, err_est, err_use) = match truth {
            Some(t) => (
                format!("{:.5}", t[i]),
                error_text(last.estimate[i], t[i], ""),
                error_text(last.in_use[i], t[i], ""),
            ),
            None => ("?".into(), String::new(), String::new()),
        };
        let _ = writeln!(
            out,
            "  {label:<18} {plant:>11} {:>11.5} {:>11.5} {err_est:>14} {:>11.5} {err_use:>14}",
            start[i], last.estimate[i], last.in_use[i]
        );
    }
    let sum = |theta: &SVector<f64, NP>| first_joint_inertia::<N, NP>(theta, gear_ratio_1);
    let (plant, err_est, err_use) = match truth {
        Some(t) => (
            format!("{:.5}", sum(t)),
            error_text(sum(&last.estimate), sum(t), ""),
            error_text(sum(&last.in_use), sum(t), ""),
        ),
        None => ("?".into(), String::new(), String::new()),
    };
    let _ = writeln!(
        out,
        "  {:<18} {plant:>11} {:>11.5} {:>11.5} {err_est:>14} {:>11.5} {err_use:>14}",
        format!("A[1,1]+{}\u{b2}Ir[1]", number(gear_ratio_1)),
        sum(start),
        sum(&last.estimate),
        sum(&last.in_use)
    );
    let _ = writeln!(
        out,
        "  (the first motor turns with link 1: the energy has A[1,1] and Ir[1] in this sum only)"
    );
    out
}

/// The adaptation figure's file next to the run's plot: `out.png` ->
/// `out_adaptation.png` (same folder and format).
pub fn figure_path(plot: &Path) -> PathBuf {
    let stem = plot
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = match plot.extension() {
        Some(ext) => format!("{stem}_adaptation.{}", ext.to_string_lossy()),
        None => format!("{stem}_adaptation"),
    };
    plot.with_file_name(name)
}

/// Green of the moments a model was taken.
const GREEN: RGBColor = RGBColor(44, 160, 44);

/// Tick labels with as many decimals as the axis `span` needs (the base
/// parameters range from 1e-5 kg m² rotor inertias to 20 N m), never `-0`.
fn tick(v: f64, span: f64) -> String {
    let decimals =
        (2.0 - eigenmpc::math::log10(span.abs().max(1e-12)).floor()).clamp(0.0, 9.0) as usize;
    let text = format!("{v:.decimals$}");
    let text = if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    };
    if text
        .trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        "0".into()
    } else {
        text
    }
}

/// Draws one panel per base parameter: the identification's estimate over
/// time (line), the model in use (step line), the plant's true value
/// (dashed, when known) and vertical markers where a model was taken
/// (green) or taken back (red); a last panel shows the adaptation's status
/// over time. `times[i]` is the time of `samples[i]`. PNG, or SVG when the
/// name ends in `.svg`.
pub fn plot_adaptation<const NP: usize>(
    path: &Path,
    caption: &str,
    names: &[BaseParameterName],
    times: &[f64],
    samples: &[AdaptationSample<NP>],
    truth: Option<&SVector<f64, NP>>,
) -> Result<(), PlotError> {
    let panels = NP + 1;
    let columns = 4usize;
    let rows = panels.div_ceil(columns);
    let size = (470 * columns as u32, 360 * rows as u32 + 50);
    let figure = Figure {
        caption,
        names,
        times,
        samples,
        truth,
        grid: (rows, columns),
    };
    with_backend(
        path,
        size,
        |root| figure.draw(root),
        |root| figure.draw(root),
    )
}

/// What [`plot_adaptation`] draws.
struct Figure<'a, const NP: usize> {
    caption: &'a str,
    names: &'a [BaseParameterName],
    times: &'a [f64],
    samples: &'a [AdaptationSample<NP>],
    truth: Option<&'a SVector<f64, NP>>,
    grid: (usize, usize),
}

impl<const NP: usize> Figure<'_, NP> {
    /// Times at which `count` of the samples went up (a model taken, a
    /// model taken back).
    fn events(&self, count: impl Fn(&AdaptationSample<NP>) -> usize) -> Vec<f64> {
        let mut before = 0;
        let mut out = vec![];
        for (t, s) in self.times.iter().zip(self.samples) {
            if count(s) > before {
                out.push(*t);
            }
            before = count(s);
        }
        out
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
    ) -> Result<(), PlotError>
    where
        DB::ErrorType: 'static,
    {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| PlotError::new(format!("{e}"));
        root.fill(&WHITE).map_err(err)?;
        let root = root.titled(self.caption, ("sans-serif", 22)).map_err(err)?;
        let areas = root.split_evenly(self.grid);
        let t_start = self.times.first().copied().unwrap_or(0.0);
        let t_end = self
            .times
            .last()
            .copied()
            .unwrap_or(1.0)
            .max(t_start + 1e-9);
        let taken = self.events(|s| s.model_updates);
        let reverted = self.events(|s| s.reverts);
        for (i, area) in areas.iter().enumerate().take(NP) {
            self.draw_parameter(area, i, t_start..t_end, &taken, &reverted)?;
        }
        if let Some(area) = areas.get(NP) {
            self.draw_status(area, t_start..t_end, &taken, &reverted)?;
        }
        root.present().map_err(err)?;
        Ok(())
    }

    /// The panel of base parameter `i`.
    fn draw_parameter<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, plotters::coord::Shift>,
        i: usize,
        ts: std::ops::Range<f64>,
        taken: &[f64],
        reverted: &[f64],
    ) -> Result<(), PlotError>
    where
        DB::ErrorType: 'static,
    {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| PlotError::new(format!("{e}"));
        let name = &self.names[i];
        let unit = name.unit_text();
        let truth = self.truth.map(|t| t[i]);
        let estimate: Vec<(f64, f64)> = self
            .times
            .iter()
            .zip(self.samples)
            .map(|(t, s)| (*t, s.estimate[i]))
            .collect();
        // The model in use changes between samples: drawn as steps.
        let mut in_use: Vec<(f64, f64)> = vec![];
        for (t, s) in self.times.iter().zip(self.samples) {
            let v = s.in_use[i];
            if let Some(&(_, last)) = in_use.last()
                && last != v
            {
                in_use.push((*t, last));
            }
            in_use.push((*t, v));
        }
        let ys = padded_range(estimate.iter().chain(&in_use).map(|p| p.1).chain(truth));
        let final_error = match (truth, self.samples.last()) {
            (Some(t), Some(s)) => format!(": estimate {}", error_text(s.estimate[i], t, &unit)),
            _ => String::new(),
        };
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!("{} {}{final_error}", name.symbol, name.meaning),
                ("sans-serif", 18),
            )
            .margin(10)
            .margin_right(24)
            .x_label_area_size(42)
            .y_label_area_size(74)
            .build_cartesian_2d(ts.clone(), ys.clone())
            .map_err(err)?;
        let span = ys.end - ys.start;
        let t_span = ts.end - ts.start;
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc(format!("{} ({unit})", name.symbol))
            .x_labels(7)
            .y_labels(6)
            .x_label_formatter(&|v| tick(*v, t_span))
            .y_label_formatter(&|v| tick(*v, span))
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 15))
            .draw()
            .map_err(err)?;
        draw_markers(&mut chart, &ys, taken, reverted, i == 0)?;
        let mut drawn = with_midpoints(&estimate);
        let used = ORANGE.stroke_width(2);
        chart
            .draw_series(LineSeries::new(in_use.iter().copied(), used))
            .map_err(err)?
            .label("model in use")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], used));
        drawn.extend(with_midpoints(&in_use));
        let line = BLUE_DARK.stroke_width(2);
        chart
            .draw_series(LineSeries::new(estimate.iter().copied(), line))
            .map_err(err)?
            .label("estimate")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], line));
        if let Some(t) = truth {
            let style = BLACK.stroke_width(2);
            chart
                .draw_series(DashedLineSeries::new(
                    [(ts.start, t), (ts.end, t)],
                    10,
                    6,
                    style,
                ))
                .map_err(err)?
                .label("plant (true)")
                .legend(move |(x, y)| {
                    plotters::element::DashedPathElement::new([(x, y), (x + 20, y)], 6, 3, style)
                });
            drawn.extend((0..=8).map(|k| (ts.start + k as f64 * t_span / 8.0, t)));
        }
        if i == 0 {
            // One legend for the figure: every panel draws the same series.
            draw_legend(&mut chart, quiet_corner(&drawn, &ts, &ys))?;
        }
        Ok(())
    }

    /// The status panel: the adaptation's status over time on a scale of
    /// its five states, with the same markers.
    fn draw_status<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, plotters::coord::Shift>,
        ts: std::ops::Range<f64>,
        taken: &[f64],
        reverted: &[f64],
    ) -> Result<(), PlotError>
    where
        DB::ErrorType: 'static,
    {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| PlotError::new(format!("{e}"));
        let items = ADAPTATION_STATUS.items;
        let level = |s: AdaptationStatus| {
            items
                .iter()
                .position(|i| i.value == s)
                .map_or(0.0, |k| k as f64)
        };
        let ys = -0.5..(items.len() as f64 - 0.5);
        let last = self.samples.last();
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!(
                    "adaptation status: {} taken, {} refused, {} taken back",
                    last.map_or(0, |s| s.model_updates),
                    last.map_or(0, |s| s.refused()),
                    last.map_or(0, |s| s.reverts)
                ),
                ("sans-serif", 18),
            )
            .margin(10)
            .margin_right(24)
            .x_label_area_size(42)
            .y_label_area_size(90)
            .build_cartesian_2d(ts.clone(), ys.clone())
            .map_err(err)?;
        let t_span = ts.end - ts.start;
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .x_labels(7)
            .y_labels(items.len())
            .x_label_formatter(&|v| tick(*v, t_span))
            .y_label_formatter(&|v| {
                let k = v.round();
                if (v - k).abs() < 1e-6 && k >= 0.0 {
                    items
                        .get(k as usize)
                        .map_or(String::new(), |i| i.name.into())
                } else {
                    String::new()
                }
            })
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 15))
            .draw()
            .map_err(err)?;
        draw_markers(&mut chart, &ys, taken, reverted, false)?;
        let mut steps: Vec<(f64, f64)> = vec![];
        for (t, s) in self.times.iter().zip(self.samples) {
            let v = level(s.status);
            if let Some(&(_, before)) = steps.last()
                && before != v
            {
                steps.push((*t, before));
            }
            steps.push((*t, v));
        }
        chart
            .draw_series(LineSeries::new(steps, BLUE_DARK.stroke_width(2)))
            .map_err(err)?;
        Ok(())
    }
}

/// Vertical lines at the times a model was taken (green) and taken back
/// (red), labelled for the legend when `label`.
fn draw_markers<DB: DrawingBackend>(
    chart: &mut crate::report::Panel2d<'_, DB>,
    ys: &std::ops::Range<f64>,
    taken: &[f64],
    reverted: &[f64],
    label: bool,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| PlotError::new(format!("{e}"));
    for (times, colour, text) in [
        (taken, GREEN, "model taken"),
        (reverted, RED, "model taken back"),
    ] {
        if times.is_empty() {
            continue;
        }
        let style = colour.mix(0.8).stroke_width(2);
        let series = chart
            .draw_series(
                times
                    .iter()
                    .map(|&t| PathElement::new([(t, ys.start), (t, ys.end)], style)),
            )
            .map_err(err)?;
        if label {
            series
                .label(text)
                .legend(move |(x, y)| PathElement::new([(x + 10, y - 6), (x + 10, y + 6)], style));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use eigenmpc::identify::base_parameter_count;
    use eigenmpc::mechanics::PlanarChainParams;

    /// The names follow the order of `BaseParameters`' vector: each
    /// accessor's value sits under its name.
    #[test]
    fn names_follow_the_base_parameter_vector() {
        let names = base_parameter_names::<2>();
        assert_eq!(names.len(), base_parameter_count(2));
        let symbols: Vec<&str> = names.iter().map(|n| n.symbol.as_str()).collect();
        assert_eq!(
            symbols,
            [
                "A[1,1]", "A[1,2]", "A[2,2]", "G[1]", "G[2]", "Ir[1]", "Ir[2]", "b[1]", "b[2]",
                "cf[1]", "cf[2]"
            ]
        );
        let mut params = PlanarChainParams::<2>::point_masses([1.0, 0.8], [1.0, 0.5], 9.81);
        params.joints[1].viscous = 0.03;
        params.joints[0].coulomb = 0.07;
        let b = BaseParameters::<2, 11>::of(&params).unwrap();
        let at = |symbol: &str| b.theta[symbols.iter().position(|s| *s == symbol).unwrap()];
        assert_eq!(at("A[1,2]"), b.inertia_amplitude(0, 1));
        assert_eq!(at("G[2]"), b.gravity_amplitude(1));
        assert_eq!(at("b[2]"), 0.03);
        assert_eq!(at("cf[1]"), 0.07);
        assert_eq!(names[0].estimate_column(), "estimate.A[1,1]");
        assert_eq!(names[6].in_use_column(), "in_use.Ir[2]");
        assert_eq!(names[0].unit_text(), "kg m\u{b2}");
        assert_eq!(names[7].unit_text(), "N m s/rad");
    }

    #[test]
    fn figure_path_errors_and_ticks() {
        assert_eq!(
            figure_path(Path::new("out/run.svg")),
            Path::new("out/run_adaptation.svg")
        );
        assert_eq!(error_text(7.9, 7.848, ""), "+0.66 %");
        assert_eq!(error_text(7.848001, 7.848, ""), "+1.3e-5 %");
        assert_eq!(error_text(-0.0005, 0.0, "kg m\u{b2}"), "-5.0e-4 kg m\u{b2}");
        assert_eq!(error_text(0.0, 0.0, ""), "0");
        assert_eq!(tick(-0.00001, 0.01), "0");
        assert_eq!(tick(0.0005, 0.002), "0.0005");
        assert_eq!(tick(20.0, 60.0), "20");
    }
}
