//! The robustness report's outputs: scores and per-run tables (Markdown),
//! one CSV row per run, and one plot panel per category (energy error
//! against the varied quantity, success marked).

use super::{
    CATEGORIES, Case, ENERGY_TOLERANCE, NOISY_TORQUE_ALLOWANCE, Outcome, TORQUE_ALLOWANCE,
};
use crate::report::{PlotError, register_font};
use plotters::prelude::*;
use std::fmt::Write as _;
use std::path::Path;

/// One case with its outcome without and with adaptation.
#[derive(Clone, Debug)]
pub struct RunPair {
    /// The case.
    pub case: Case,
    /// Without adaptation.
    pub off: Outcome,
    /// With adaptation.
    pub on: Outcome,
}

/// Share of successful runs of `category` (off, on) and the number of runs.
pub fn score(rows: &[RunPair], category: &str) -> (f64, f64, usize) {
    let runs: Vec<&RunPair> = rows
        .iter()
        .filter(|r| r.case.category == category)
        .collect();
    let n = runs.len();
    let share = |f: fn(&RunPair) -> bool| {
        if n == 0 {
            f64::NAN
        } else {
            runs.iter().filter(|r| f(r)).count() as f64 / n as f64
        }
    };
    (share(|r| r.off.success), share(|r| r.on.success), n)
}

fn outcome_cells(o: &Outcome) -> String {
    let joints = |v: &[f64], add: f64| {
        v.iter()
            .map(|x| format!("{:.3}", x + add))
            .collect::<Vec<_>>()
            .join(" / ")
    };
    format!(
        "{} | {:+.2} | {} | {} |",
        if o.success { "yes" } else { "**no**" },
        100.0 * o.energy_error,
        joints(&o.rms_torque, 0.0),
        joints(&o.friction_torque, o.allowance),
    )
}

/// The Markdown report: `title` (the configuration), the score table, and
/// one table per category.
pub fn markdown(title: &str, rows: &[RunPair]) -> String {
    let mut s = format!(
        "{title}\n\n## Scores (share of runs within {} % of E_ref with RMS torque at most friction + {} N m, + {} N m under noise)\n\n",
        100.0 * ENERGY_TOLERANCE,
        TORQUE_ALLOWANCE,
        NOISY_TORQUE_ALLOWANCE
    );
    s.push_str("| category | runs | without adaptation | with adaptation |\n|---|---|---|---|\n");
    let (mut all_off, mut all_on, mut all_n) = (0.0, 0.0, 0usize);
    for category in CATEGORIES {
        let (off, on, n) = score(rows, category);
        if n == 0 {
            continue;
        }
        writeln!(s, "| {category} | {n} | {:.2} | {:.2} |", off, on).unwrap();
        all_off += off * n as f64;
        all_on += on * n as f64;
        all_n += n;
    }
    if all_n > 0 {
        writeln!(
            s,
            "| **all** | {all_n} | {:.2} | {:.2} |",
            all_off / all_n as f64,
            all_on / all_n as f64
        )
        .unwrap();
    }
    s.push_str(
        "\nPer run: success, energy error of the mean over the last 5 s (%), RMS motor torque \
         over the last 5 s per joint (N m), the torque allowed (the plant's RMS friction torque \
         along the last 5 s + the allowance), without | with adaptation, and the models the \
         adaptation swapped in.\n",
    );
    for category in CATEGORIES {
        let runs: Vec<&RunPair> = rows
            .iter()
            .filter(|r| r.case.category == category)
            .collect();
        let Some(first) = runs.first() else { continue };
        writeln!(s, "\n### {category}\n").unwrap();
        let unit = if first.case.unit.is_empty() {
            String::new()
        } else {
            format!(" ({})", first.case.unit)
        };
        writeln!(
            s,
            "| parameter | value{unit} | ok | E error (%) | tau RMS (N m) | allowed (N m) | ok (adapt) | E error (%) | tau RMS (N m) | allowed (N m) | models |"
        )
        .unwrap();
        s.push_str("|---|---|---|---|---|---|---|---|---|---|---|\n");
        for r in runs {
            writeln!(
                s,
                "| {} | {} | {} {} {} |",
                r.case.parameter,
                crate::report::number(r.case.value),
                outcome_cells(&r.off),
                outcome_cells(&r.on),
                r.on.model_updates
            )
            .unwrap();
        }
    }
    s
}

/// One CSV row per run and adaptation setting: `rms_tau<j>_Nm` and
/// `rms_friction<j>_Nm` per joint.
pub fn csv(rows: &[RunPair]) -> String {
    let joints = rows.first().map_or(2, |r| r.off.rms_torque.len());
    let mut s = String::from(
        "category,parameter,value,unit,adapt,ekf,success,time_to_5pct_band_s,energy_error",
    );
    for j in 1..=joints {
        write!(s, ",rms_tau{j}_Nm").unwrap();
    }
    for j in 1..=joints {
        write!(s, ",rms_friction{j}_Nm").unwrap();
    }
    s.push_str(",failed_solves,model_updates\n");
    for r in rows {
        for (adapt, o) in [(false, &r.off), (true, &r.on)] {
            write!(
                s,
                "{},{},{},{},{},{},{},{},{}",
                r.case.category,
                r.case.parameter,
                r.case.value,
                r.case.unit,
                adapt,
                o.ekf,
                o.success,
                o.time_to_band.map_or(String::new(), |t| t.to_string()),
                o.energy_error,
            )
            .unwrap();
            for v in o.rms_torque.iter().chain(&o.friction_torque) {
                write!(s, ",{v}").unwrap();
            }
            writeln!(s, ",{},{}", o.failed_solves, o.model_updates).unwrap();
        }
    }
    s
}

/// The x axis label of a parameter in its unit, in symbols.
fn axis_label(parameter: &str, unit: &str) -> String {
    let parameter = match parameter {
        "sigma" => "noise \u{3c3}",
        "a" => "torque response a (u += a (\u{3c4} - u) per sample)",
        "delay" => "measurement delay",
        "profile" => "random pulse profile",
        "model" => "rough model",
        p => p,
    };
    match unit {
        "x nominal" => "factor of the nominal value".to_string(),
        "profile" => "pulse profile number".to_string(),
        "model" => "rough model number".to_string(),
        "" => parameter.to_string(),
        "kg m^2" => format!("{parameter} (kg m\u{b2})"),
        unit => format!("{parameter} ({unit})"),
    }
}

/// Plots one panel per category: the energy error (%) of the mean over
/// the last 5 s against the varied quantity, without (blue) and with
/// (orange) adaptation, one line per parameter; a filled circle is a
/// success (energy and torque), a cross a failure; the 1 % band is shaded. PNG, or SVG when
/// the name ends in `.svg`.
pub fn plot(path: &Path, title: &str, rows: &[RunPair]) -> Result<(), PlotError> {
    register_font()?;
    let categories: Vec<&str> = CATEGORIES
        .into_iter()
        .filter(|c| rows.iter().any(|r| r.case.category == *c))
        .collect();
    let columns = categories.len().clamp(1, 4);
    let lines = categories.len().div_ceil(columns).max(1);
    let size = (380 * columns as u32, 340 * lines as u32 + 60);
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"))
    {
        draw(
            SVGBackend::new(path, size).into_drawing_area(),
            title,
            rows,
            &categories,
            (lines, columns),
        )
    } else {
        draw(
            BitMapBackend::new(path, size).into_drawing_area(),
            title,
            rows,
            &categories,
            (lines, columns),
        )
    }
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    rows: &[RunPair],
    categories: &[&str],
    grid: (usize, usize),
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| PlotError::new(format!("{e}"));
    root.fill(&WHITE).map_err(err)?;
    // A caption wider than a few panels gets a smaller font, not clipped
    // (about half the font size per character).
    let width = root.dim_in_pixel().0 as f64;
    let font = (width / (0.52 * title.chars().count().max(1) as f64)).clamp(11.0, 18.0);
    let root = root.titled(title, ("sans-serif", font)).map_err(err)?;
    let panels = root.split_evenly(grid);
    let off_colour = RGBColor(31, 119, 180);
    let on_colour = RGBColor(255, 127, 14);
    for (panel, category) in panels.iter().zip(categories) {
        let runs: Vec<&RunPair> = rows
            .iter()
            .filter(|r| r.case.category == *category)
            .collect();
        let (off, on, n) = score(rows, category);
        let values = runs.iter().map(|r| r.case.value);
        let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
        let pad = ((hi - lo) * 0.08).max(1e-3 * hi.abs().max(1e-3));
        // Errors beyond +-20 % are drawn at the edge (the table has them).
        let clip = |e: f64| (100.0 * e).clamp(-20.0, 20.0);
        let errors = runs
            .iter()
            .flat_map(|r| [clip(r.off.energy_error), clip(r.on.energy_error)]);
        let (elo, ehi) = errors.fold((-2.0f64, 2.0f64), |(a, b), v| (a.min(v), b.max(v)));
        let xs = (lo - pad)..(hi + pad);
        let ys = (elo * 1.1)..(ehi * 1.1);
        let mut drawn: Vec<(f64, f64)> = vec![];
        let unit = runs.first().map_or("", |r| r.case.unit);
        let parameter = runs.first().map_or("", |r| r.case.parameter.as_str());
        let x_desc = axis_label(parameter, unit);
        let mut chart = ChartBuilder::on(panel)
            .caption(
                format!(
                    "{category}: {:.0} % / {:.0} % of {n} succeed",
                    100.0 * off,
                    100.0 * on
                ),
                ("sans-serif", 17),
            )
            .margin(12)
            .margin_right(24)
            .x_label_area_size(42)
            .y_label_area_size(52)
            .build_cartesian_2d(xs.clone(), ys.clone())
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc("energy error (%)")
            .x_labels(6)
            .x_label_formatter(&|v| crate::report::number(*v))
            .y_label_formatter(&|v| crate::report::number(*v))
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(err)?;
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [
                    (lo - pad, -100.0 * ENERGY_TOLERANCE),
                    (hi + pad, 100.0 * ENERGY_TOLERANCE),
                ],
                RGBColor(0, 160, 0).mix(0.12).filled(),
            )))
            .map_err(err)?
            .label(format!("{} % band", 100.0 * ENERGY_TOLERANCE))
            .legend(|(x, y)| {
                Rectangle::new(
                    [(x, y - 5), (x + 14, y + 5)],
                    RGBColor(0, 160, 0).mix(0.3).filled(),
                )
            });
        let mut parameters: Vec<&str> = runs.iter().map(|r| r.case.parameter.as_str()).collect();
        parameters.dedup();
        for (k, parameter) in parameters.iter().enumerate() {
            let of: Vec<&&RunPair> = runs
                .iter()
                .filter(|r| r.case.parameter == *parameter)
                .collect();
            for (adapt, colour) in [(false, off_colour), (true, on_colour)] {
                let pick = |r: &RunPair| if adapt { r.on.clone() } else { r.off.clone() };
                let style = if k == 0 {
                    colour.stroke_width(2)
                } else {
                    colour.mix(0.55).stroke_width(2)
                };
                let points: Vec<(f64, f64, bool)> = of
                    .iter()
                    .map(|r| {
                        let o = pick(r);
                        (r.case.value, clip(o.energy_error), o.success)
                    })
                    .collect();
                let label = format!(
                    "{}{}",
                    if parameters.len() > 1 {
                        format!("{parameter} ")
                    } else {
                        String::new()
                    },
                    if adapt { "adapt" } else { "no adapt" }
                );
                let line: Vec<(f64, f64)> = points.iter().map(|p| (p.0, p.1)).collect();
                drawn.extend(crate::report::with_midpoints(&line));
                chart
                    .draw_series(LineSeries::new(line, style))
                    .map_err(err)?
                    .label(label)
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + 14, y)], style));
                chart
                    .draw_series(points.iter().map(|&(x, y, ok)| {
                        let marker: DynElement<DB, (f64, f64)> = if ok {
                            Circle::new((x, y), 4, colour.filled()).into_dyn()
                        } else {
                            Cross::new((x, y), 5, colour.stroke_width(2)).into_dyn()
                        };
                        marker
                    }))
                    .map_err(err)?;
            }
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.3))
            .label_font(("sans-serif", 12))
            .position(crate::report::quiet_corner(&drawn, &xs, &ys))
            .draw()
            .map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}
