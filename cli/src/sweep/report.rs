//! The outputs of a sweep: one CSV row and one JSON object per run
//! (parameters, then metrics), and a plot of one metric over the swept
//! parameters (a line for one, a heat map for two).

use super::Metrics;
use crate::report::{PlotError, number, register_font, viridis};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use serde_json::json;
use std::fmt::Write as _;
use std::path::Path;

/// One finished run: its swept values and what it gave (or why it failed).
#[derive(Clone, Debug)]
pub struct Row {
    /// The swept names and values.
    pub values: Vec<(String, f64)>,
    /// The metrics, or the run's error.
    pub outcome: Result<Metrics, String>,
}

/// The metric columns before the torques, with their units.
const HEAD: [(&str, &str); 4] = [
    ("time_to_band", "s"),
    ("success", "1/0"),
    ("final_energy_error", "J"),
    ("mean_energy_error", "relative"),
];

/// The metric columns after the torques, with their units.
const TAIL: [(&str, &str); 5] = [
    ("distance_to_mode", "rad"),
    ("failed_solves", "samples"),
    ("model_updates", ""),
    ("solve_time_median", "s"),
    ("solve_time_p99", "s"),
];

/// The metric columns of a robot of `joints` joints, in CSV order, with
/// their units: one `rms_torque_<j>` per joint.
pub fn metric_columns(joints: usize) -> Vec<(String, &'static str)> {
    let torques = (1..=joints).map(|j| (format!("rms_torque_{j}"), "N m"));
    HEAD.iter()
        .map(|(n, u)| (n.to_string(), *u))
        .chain(torques)
        .chain(TAIL.iter().map(|(n, u)| (n.to_string(), *u)))
        .collect()
}

/// The value of metric `name` (NaN when the run has none: never reached
/// the band, no mode there, a failed run).
pub fn metric(m: &Metrics, name: &str) -> Option<f64> {
    let opt = |v: Option<f64>| v.unwrap_or(f64::NAN);
    if let Some(j) = name.strip_prefix("rms_torque_") {
        let j: usize = j.parse().ok()?;
        return m.rms_torque.get(j.checked_sub(1)?).copied();
    }
    Some(match name {
        "time_to_band" => opt(m.time_to_band),
        "success" => f64::from(u8::from(m.success)),
        "final_energy_error" => m.final_energy_error,
        "mean_energy_error" => m.mean_energy_error,
        "distance_to_mode" => opt(m.distance_to_mode),
        "failed_solves" => m.failed_solves as f64,
        "model_updates" => m.model_updates as f64,
        "solve_time_median" => m.solve_time[0],
        "solve_time_p99" => m.solve_time[1],
        _ => return None,
    })
}

/// Checks that `name` is a metric column for `joints` joints.
pub fn check_metric(name: &str, joints: usize) -> Result<(), String> {
    let columns = metric_columns(joints);
    if columns.iter().any(|(m, _)| m == name) {
        Ok(())
    } else {
        let names: Vec<&str> = columns.iter().map(|(m, _)| m.as_str()).collect();
        Err(format!(
            "unknown metric `{name}` (known: {})",
            names.join(", ")
        ))
    }
}

/// A CSV cell: whole numbers without a fraction, others as the shortest
/// text that reads back to the same double.
fn cell(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{}", v as i64)
    } else {
        format!("{v:?}")
    }
}

/// The CSV of a robot of `joints` joints: `run`, the swept names, the
/// metrics, `error`.
pub fn csv(swept: &[String], rows: &[Row], joints: usize) -> String {
    let columns = metric_columns(joints);
    let mut out = String::from("run");
    for n in swept {
        write!(out, ",{n}").unwrap();
    }
    for (m, _) in &columns {
        write!(out, ",{m}").unwrap();
    }
    out.push_str(",error\n");
    for (i, row) in rows.iter().enumerate() {
        write!(out, "{i}").unwrap();
        for (_, v) in &row.values {
            write!(out, ",{}", cell(*v)).unwrap();
        }
        match &row.outcome {
            Ok(m) => {
                for (name, _) in &columns {
                    let v = metric(m, name).unwrap_or(f64::NAN);
                    if v.is_nan() {
                        out.push(',');
                    } else {
                        write!(out, ",{}", cell(v)).unwrap();
                    }
                }
                out.push_str(",\n");
            }
            Err(e) => {
                out.push_str(&",".repeat(columns.len()));
                // One field: quotes doubled.
                writeln!(out, ",\"{}\"", e.replace('"', "\"\"")).unwrap();
            }
        }
    }
    out
}

/// The JSON: `{"runs": [{"run", "parameters", "metrics" | "error"}]}`.
pub fn json(rows: &[Row]) -> serde_json::Value {
    let runs: Vec<serde_json::Value> = rows
        .iter()
        .enumerate()
        .map(|(i, row)| {
            let parameters: serde_json::Map<String, serde_json::Value> = row
                .values
                .iter()
                .map(|(n, v)| (n.clone(), json!(v)))
                .collect();
            match &row.outcome {
                Ok(m) => json!({"run": i, "parameters": parameters, "metrics": m}),
                Err(e) => json!({"run": i, "parameters": parameters, "error": e}),
            }
        })
        .collect();
    json!({ "runs": runs })
}

/// Plots `metric` over the swept parameters: a line (and points) over one
/// parameter, a heat map over two (the first on x), points over the first
/// parameter otherwise. PNG or SVG by extension.
pub fn plot(
    path: &Path,
    title: &str,
    swept: &[String],
    rows: &[Row],
    metric_name: &str,
) -> Result<(), PlotError> {
    register_font()?;
    let svg = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"));
    let size = (960, 660);
    if svg {
        draw(
            SVGBackend::new(path, size).into_drawing_area(),
            title,
            swept,
            rows,
            metric_name,
        )
    } else {
        draw(
            BitMapBackend::new(path, size).into_drawing_area(),
            title,
            swept,
            rows,
            metric_name,
        )
    }
}

fn unit_of(metric_name: &str) -> &'static str {
    if metric_name.starts_with("rms_torque_") {
        return "N m";
    }
    HEAD.iter()
        .chain(TAIL.iter())
        .find(|(m, _)| *m == metric_name)
        .map_or("", |(_, u)| u)
}

fn span(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.06).max(1e-6 * hi.abs().max(1.0));
    (lo - pad, hi + pad)
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    swept: &[String],
    rows: &[Row],
    metric_name: &str,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| PlotError::new(format!("{e}"));
    root.fill(&WHITE).map_err(err)?;
    let root = root.titled(title, ("sans-serif", 24)).map_err(err)?;
    let unit = unit_of(metric_name);
    let metric_label = if unit.is_empty() {
        metric_name.to_string()
    } else {
        format!("{metric_name} ({unit})")
    };
    let value = |r: &Row| {
        r.outcome
            .as_ref()
            .ok()
            .and_then(|m| super::report::metric(m, metric_name))
            .unwrap_or(f64::NAN)
    };
    let x_name = swept.first().map_or("run", |s| s.as_str());
    let x = |i: usize, r: &Row| r.values.first().map_or(i as f64, |v| v.1);
    if swept.len() == 2 && rows.iter().all(|r| r.values.len() == 2) {
        // Heat map: cells centred on the grid values.
        let mut xs: Vec<f64> = rows.iter().map(|r| r.values[0].1).collect();
        let mut ys: Vec<f64> = rows.iter().map(|r| r.values[1].1).collect();
        for v in [&mut xs, &mut ys] {
            v.sort_by(f64::total_cmp);
            v.dedup();
        }
        let half = |v: &[f64]| {
            if v.len() > 1 {
                (v[v.len() - 1] - v[0]) / (v.len() - 1) as f64 / 2.0
            } else {
                0.5 * v[0].abs().max(1.0)
            }
        };
        let (hx, hy) = (half(&xs), half(&ys));
        let (vlo, vhi) = span(rows.iter().map(value));
        let (main, bar) = root.split_horizontally(800);
        // A strip under the map for the note on missing values.
        let height = main.dim_in_pixel().1;
        let (main, note) = main.split_vertically(height.saturating_sub(26));
        let mut chart = ChartBuilder::on(&main)
            .margin(16)
            .x_label_area_size(52)
            .y_label_area_size(72)
            .build_cartesian_2d(
                (xs[0] - hx)..(xs[xs.len() - 1] + hx),
                (ys[0] - hy)..(ys[ys.len() - 1] + hy),
            )
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(&swept[0])
            .y_desc(&swept[1])
            .x_label_formatter(&|v| number(*v))
            .y_label_formatter(&|v| number(*v))
            .label_style(("sans-serif", 17))
            .axis_desc_style(("sans-serif", 19))
            .draw()
            .map_err(err)?;
        chart
            .draw_series(rows.iter().map(|r| {
                let (cx, cy, v) = (r.values[0].1, r.values[1].1, value(r));
                let fill = if v.is_finite() {
                    viridis((v - vlo) / (vhi - vlo)).filled()
                } else {
                    RGBColor(200, 200, 200).filled()
                };
                Rectangle::new([(cx - hx, cy - hy), (cx + hx, cy + hy)], fill)
            }))
            .map_err(err)?;
        chart
            .draw_series(rows.iter().map(|r| {
                let v = value(r);
                let text = if v.is_finite() { number(v) } else { "-".into() };
                // Light text on the dark half of the scale.
                let dark = v.is_finite() && (v - vlo) / (vhi - vlo) < 0.45;
                let style = ("sans-serif", 15)
                    .into_font()
                    .color(if dark { &WHITE } else { &BLACK })
                    .pos(Pos::new(HPos::Center, VPos::Center));
                Text::new(text, (r.values[0].1, r.values[1].1), style)
            }))
            .map_err(err)?;
        if rows.iter().any(|r| !value(r).is_finite()) {
            note.draw(&Text::new(
                "grey, -: no value (never in the band, no mode there, or a failed run)",
                (90, 4),
                ("sans-serif", 14).into_font().color(&RGBColor(90, 90, 90)),
            ))
            .map_err(err)?;
        }
        // Colour bar with the metric's range.
        let mut scale = ChartBuilder::on(&bar)
            .margin_top(16)
            .margin_bottom(68)
            .margin_left(12)
            .margin_right(8)
            .y_label_area_size(0)
            .right_y_label_area_size(96)
            .build_cartesian_2d(0.0..1.0, vlo..vhi)
            .map_err(err)?;
        scale
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_desc(&metric_label)
            .y_label_formatter(&|v| number(*v))
            .label_style(("sans-serif", 15))
            .draw()
            .map_err(err)?;
        let steps = 64;
        scale
            .draw_series((0..steps).map(|k| {
                let a = vlo + (vhi - vlo) * k as f64 / steps as f64;
                let b = vlo + (vhi - vlo) * (k + 1) as f64 / steps as f64;
                Rectangle::new(
                    [(0.0, a), (1.0, b)],
                    viridis(k as f64 / (steps - 1) as f64).filled(),
                )
            }))
            .map_err(err)?;
    } else {
        let points: Vec<(f64, f64)> = rows
            .iter()
            .enumerate()
            .map(|(i, r)| (x(i, r), value(r)))
            .collect();
        let (xlo, xhi) = span(points.iter().map(|p| p.0));
        let (ylo, yhi) = span(points.iter().map(|p| p.1));
        let mut chart = ChartBuilder::on(&root)
            .margin(16)
            .margin_right(36)
            .x_label_area_size(52)
            .y_label_area_size(80)
            .build_cartesian_2d(xlo..xhi, ylo..yhi)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(x_name)
            .y_desc(&metric_label)
            .x_label_formatter(&|v| number(*v))
            .y_label_formatter(&|v| number(*v))
            .label_style(("sans-serif", 17))
            .axis_desc_style(("sans-serif", 19))
            .draw()
            .map_err(err)?;
        let blue = RGBColor(31, 119, 180);
        let finite: Vec<(f64, f64)> = points.iter().copied().filter(|p| p.1.is_finite()).collect();
        if swept.len() == 1 {
            let mut line = finite.clone();
            line.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(line, blue.stroke_width(2)))
                .map_err(err)?
                .label(metric_name)
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], blue.stroke_width(2))
                });
        }
        chart
            .draw_series(finite.iter().map(|&p| Circle::new(p, 5, blue.filled())))
            .map_err(err)?;
        // Runs without a value (never in the band, no mode, failed): a
        // cross on the bottom edge, so that they are not silently missing.
        let red = RGBColor(214, 39, 40);
        let missing: Vec<f64> = points
            .iter()
            .filter(|p| !p.1.is_finite())
            .map(|p| p.0)
            .collect();
        if !missing.is_empty() {
            chart
                .draw_series(
                    missing
                        .iter()
                        .map(|&x| Cross::new((x, ylo), 7, red.stroke_width(3))),
                )
                .map_err(err)?
                .label(format!("{} run(s) without a value", missing.len()))
                .legend(move |(x, y)| Cross::new((x + 10, y), 6, red.stroke_width(3)));
        }
        if swept.len() == 1 || !missing.is_empty() {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 16))
                .draw()
                .map_err(err)?;
        }
    }
    root.present().map_err(err)?;
    Ok(())
}
