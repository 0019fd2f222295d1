//! Output of closed-loop runs for people: the summary text, CSV and the
//! paper-style plots (shared by `eigenmpc simulate` and the FMU demo).

use eigenmpc::mechanics::Vector;
use eigenmpc::mpc::closed_loop::{Sample, Summary};
use plotters::prelude::*;
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

/// Plotting failed (file not writable, backend error).
#[derive(Debug, thiserror::Error)]
#[error("plot failed: {0}")]
pub struct PlotError(String);

impl PlotError {
    /// A plot error with this message.
    pub fn new(message: impl Into<String>) -> Self {
        Self(message.into())
    }
}

/// Registers the embedded font as `sans-serif` (the plots need no system
/// fontconfig).
pub fn register_font() -> Result<(), PlotError> {
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
        .map_err(|_| PlotError("embedded font is invalid".into()))
}

/// A number for a tick label or table cell: at most 4 decimals, trailing
/// zeros dropped, never `-0`.
pub fn number(x: f64) -> String {
    let text = format!("{:.4}", x);
    let text = if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    };
    if text == "-0" { "0".into() } else { text }
}

/// What a summary's RMS figures cover: `last 5 s`, or `whole run (2 s)`
/// for a run shorter than the 5 s window.
pub fn window_label(window: f64) -> String {
    if window < 5.0 - 1e-9 {
        format!("whole run ({} s)", number(window))
    } else {
        format!("last {} s", number(window))
    }
}

/// The summary figures as aligned text lines (time to 5 %, final energy
/// error, RMS torque and distance over the last 5 s, solve times).
pub fn summary_text<const N: usize>(s: &Summary<N>) -> String {
    let ms = |t: f64| t * 1e3;
    let mut out = String::new();
    let _ = match s.time_to_5_percent {
        Some(t) => writeln!(out, "time to |E - E_ref| < 5 % for good: {t:.3} s"),
        None => writeln!(out, "time to |E - E_ref| < 5 % for good: not reached"),
    };
    let _ = writeln!(
        out,
        "final energy error:              {:+.4} J",
        s.final_energy_error
    );
    let torques: Vec<String> = s.rms_torque.iter().map(|t| format!("{t:.4}")).collect();
    let window = window_label(s.window);
    let _ = writeln!(
        out,
        "RMS torque, {window}:{:pad$}{} N m",
        "",
        torques.join(" / "),
        pad = 20usize.saturating_sub(window.len()).max(1)
    );
    if let Some(d) = s.rms_distance {
        let _ = writeln!(out, "RMS distance to the mode, {window}: {d:.4} rad");
    }
    let _ = writeln!(
        out,
        "solve time per sample:           median {:.3} ms, p95 {:.3} ms, p99 {:.3} ms, max {:.3} ms",
        ms(s.solve_time[0]),
        ms(s.solve_time[1]),
        ms(s.solve_time[2]),
        ms(s.solve_time[3])
    );
    if s.failures > 0 {
        let _ = writeln!(out, "samples with a failed solve:     {}", s.failures);
    }
    out
}

/// First time after which the energy stays within 5 % of `e_ref` (as
/// `summarise`'s `time_to_5_percent`).
pub fn band_entry<const N: usize, const NX: usize>(
    trace: &[Sample<N, NX>],
    e_ref: f64,
) -> Option<f64> {
    eigenmpc::mpc::closed_loop::summarise(trace, e_ref, None, 5.0).time_to_5_percent
}

/// Writes a run as CSV with the columns
/// `time,q1..qN,qd1..qdN,tau1..tauN,energy,solve_ms`.
pub fn write_csv<const N: usize, const NX: usize>(
    path: &Path,
    trace: &[Sample<N, NX>],
) -> std::io::Result<()> {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    let names = |base: &'static str| (1..=N).map(move |j| format!("{base}{j}"));
    let header: Vec<String> = std::iter::once("time".to_string())
        .chain(names("q"))
        .chain(names("qd"))
        .chain(names("tau"))
        .chain(["energy".to_string(), "solve_ms".to_string()])
        .collect();
    writeln!(f, "{}", header.join(","))?;
    for s in trace {
        write!(f, "{}", s.time)?;
        for v in s.state.iter().chain(s.tau.iter()) {
            write!(f, ",{v}")?;
        }
        writeln!(f, ",{},{}", s.energy, s.solve_time * 1e3)?;
    }
    f.flush()
}

/// One plotted quantity of a sample over time.
#[derive(Clone, Copy)]
enum Panel {
    Energy,
    Angle(usize),
    Torque(usize),
}

/// Subscript digits for the joint index in labels (theta_1, tau_2).
fn subscript(j: usize) -> String {
    (j + 1)
        .to_string()
        .chars()
        .map(|c| char::from_u32(0x2080 + c.to_digit(10).unwrap_or(0)).unwrap_or(c))
        .collect()
}

impl Panel {
    fn value<const N: usize, const NX: usize>(self, s: &Sample<N, NX>) -> f64 {
        match self {
            Panel::Energy => s.energy,
            Panel::Angle(j) => s.state[j],
            Panel::Torque(j) => s.tau[j],
        }
    }

    fn title_and_label(self) -> (String, String) {
        match self {
            Panel::Energy => ("energy".into(), "E (J)".into()),
            Panel::Angle(j) => (
                format!("joint angle \u{3b8}{}", subscript(j)),
                format!("\u{3b8}{} (rad)", subscript(j)),
            ),
            Panel::Torque(j) => (
                format!("joint torque \u{3c4}{}", subscript(j)),
                format!("\u{3c4}{} (N m)", subscript(j)),
            ),
        }
    }
}

/// What a run's plot says besides the data.
#[derive(Clone, Debug, Default)]
pub struct PlotInfo {
    /// The figure's title: variant, family, `E_ref`, start state.
    pub caption: String,
    /// The torque bound, drawn on the torque panels (N m).
    pub tau_max: Option<f64>,
}

const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Draws the paper-style panels of a run (joint-space path in theta1,
/// theta2 coloured by time over the true eigenmode, energy with the 5 %
/// band, every theta_j, every tau_j with the torque bound) under the
/// caption of `info`: PNG, or SVG when the file name ends in `.svg`.
pub fn plot_run<const N: usize, const NX: usize>(
    path: &Path,
    trace: &[Sample<N, NX>],
    mode: &[Vector<N>],
    e_ref: f64,
    info: &PlotInfo,
) -> Result<(), PlotError> {
    const { assert!(N >= 2, "the joint-space panel needs two joints") };
    // The font ships with the binary: no system fontconfig needed.
    register_font()?;
    let size = (520 * (N as u32 + 1), 960);
    let svg = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"));
    if svg {
        draw(
            SVGBackend::new(path, size).into_drawing_area(),
            trace,
            mode,
            e_ref,
            info,
        )
    } else {
        draw(
            BitMapBackend::new(path, size).into_drawing_area(),
            trace,
            mode,
            e_ref,
            info,
        )
    }
}

/// Colour of time `f` in [0, 1] along the path: light blue at the start,
/// dark blue at the end.
fn time_colour(f: f64) -> RGBColor {
    let f = f.clamp(0.0, 1.0);
    let mix = |a: f64, b: f64| (a + (b - a) * f).round() as u8;
    RGBColor(mix(180.0, 8.0), mix(205.0, 48.0), mix(235.0, 107.0))
}

fn draw<DB: DrawingBackend, const N: usize, const NX: usize>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    trace: &[Sample<N, NX>],
    mode: &[Vector<N>],
    e_ref: f64,
    info: &PlotInfo,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| PlotError(format!("{e}"));
    root.fill(&WHITE).map_err(err)?;
    let root = if info.caption.is_empty() {
        root
    } else {
        root.titled(&info.caption, ("sans-serif", 22))
            .map_err(err)?
    };
    let panels = root.split_evenly((2, N + 1));
    let t_start = trace.first().map_or(0.0, |s| s.time);
    let t_end = trace.last().map_or(1.0, |s| s.time).max(t_start + 1e-9);
    let tail_start = t_end - 5.0;
    let range = |vals: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = vals
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
        if !lo.is_finite() {
            return -1.0..1.0;
        }
        let pad = ((hi - lo) * 0.06).max(1e-3);
        (lo - pad)..(hi + pad)
    };
    let label_font = ("sans-serif", 16);
    let desc_font = ("sans-serif", 17);
    let caption_font = ("sans-serif", 19);
    let blue = RGBColor(8, 48, 107);
    let red = RGBColor(214, 39, 40);
    let grey = RGBColor(120, 120, 120);

    // Joint-space path: the true eigenmode underneath as a broad light
    // band, the closed loop on top coloured by time (the last 5 s bold), so
    // that the final orbit can be compared with the mode.
    {
        let xs = range(
            &mut trace
                .iter()
                .map(|s| s.state[0])
                .chain(mode.iter().map(|q| q[0])),
        );
        let ys = range(
            &mut trace
                .iter()
                .map(|s| s.state[1])
                .chain(mode.iter().map(|q| q[1])),
        );
        let mut chart = ChartBuilder::on(&panels[0])
            .caption("joint-space path", caption_font)
            .margin(12)
            .margin_right(28)
            .x_label_area_size(44)
            .y_label_area_size(60)
            .build_cartesian_2d(xs, ys)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(format!("\u{3b8}{} (rad)", subscript(0)))
            .y_desc(format!("\u{3b8}{} (rad)", subscript(1)))
            .x_label_formatter(&|v| number(*v))
            .y_label_formatter(&|v| number(*v))
            .label_style(label_font)
            .axis_desc_style(desc_font)
            .draw()
            .map_err(err)?;
        let band = red.mix(0.3);
        chart
            .draw_series(LineSeries::new(
                mode.iter().map(|q| (q[0], q[1])),
                band.stroke_width(7),
            ))
            .map_err(err)?
            .label("plant's eigenmode at E_ref")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], band.stroke_width(7)));
        let span = (t_end - t_start).max(1e-9);
        chart
            .draw_series(trace.windows(2).map(|w| {
                let f = (w[1].time - t_start) / span;
                let width = if w[1].time > tail_start { 2 } else { 1 };
                PathElement::new(
                    [
                        (w[0].state[0], w[0].state[1]),
                        (w[1].state[0], w[1].state[1]),
                    ],
                    time_colour(f).stroke_width(width),
                )
            }))
            .map_err(err)?
            .label("EigenMPC, light to dark over time")
            .legend(move |(x, y)| {
                PathElement::new([(x, y), (x + 18, y)], time_colour(0.3).stroke_width(2))
            });
        chart
            .draw_series(std::iter::once(PathElement::new(
                Vec::<(f64, f64)>::new(),
                blue.stroke_width(2),
            )))
            .map_err(err)?
            .label("last 5 s (bold)")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], blue.stroke_width(3)));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()
            .map_err(err)?;
    }

    let band = 0.05 * e_ref.abs();
    let reached = crate::report::band_entry(trace, e_ref);
    let series: Vec<Panel> = std::iter::once(Panel::Energy)
        .chain((0..N).map(Panel::Angle))
        .chain((0..N).map(Panel::Torque))
        .collect();
    for (panel, what) in panels[1..].iter().zip(series) {
        let (title, label) = what.title_and_label();
        let mut ys = range(&mut trace.iter().map(|s| what.value(s)));
        match what {
            Panel::Energy => {
                ys = ys.start.min(e_ref - 2.0 * band)..ys.end.max(e_ref + 2.0 * band);
            }
            Panel::Torque(_) => {
                if let Some(m) = info.tau_max {
                    ys = ys.start.min(-1.1 * m)..ys.end.max(1.1 * m);
                }
            }
            Panel::Angle(_) => {}
        }
        let mut chart = ChartBuilder::on(panel)
            .caption(&title, caption_font)
            .margin(12)
            .margin_right(28)
            .x_label_area_size(44)
            .y_label_area_size(60)
            .build_cartesian_2d(t_start..t_end, ys.clone())
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc(&label)
            .x_label_formatter(&|v| number(*v))
            .y_label_formatter(&|v| number(*v))
            .label_style(label_font)
            .axis_desc_style(desc_font)
            .draw()
            .map_err(err)?;
        match what {
            Panel::Energy => {
                // The band first, E_ref under the trace: the trace's end stays visible.
                let fill = RGBColor(44, 160, 44).mix(0.18);
                chart
                    .draw_series(std::iter::once(Rectangle::new(
                        [(t_start, e_ref - band), (t_end, e_ref + band)],
                        fill.filled(),
                    )))
                    .map_err(err)?
                    .label("5 % band")
                    .legend(move |(x, y)| {
                        Rectangle::new([(x, y - 5), (x + 18, y + 5)], fill.filled())
                    });
                chart
                    .draw_series(LineSeries::new([(t_start, e_ref), (t_end, e_ref)], red))
                    .map_err(err)?
                    .label(format!("E_ref = {} J", number(e_ref)))
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], red));
                chart
                    .draw_series(LineSeries::new(
                        trace.iter().map(|s| (s.time, s.energy)),
                        blue.stroke_width(2),
                    ))
                    .map_err(err)?
                    .label("plant energy")
                    .legend(move |(x, y)| {
                        PathElement::new([(x, y), (x + 18, y)], blue.stroke_width(2))
                    });
                if let Some(t) = reached {
                    chart
                        .draw_series(LineSeries::new(
                            [(t, ys.start), (t, ys.end)],
                            grey.stroke_width(1),
                        ))
                        .map_err(err)?
                        .label(format!("in the band for good: {} s", number(t)))
                        .legend(move |(x, y)| {
                            PathElement::new([(x + 9, y - 6), (x + 9, y + 6)], grey)
                        });
                }
                chart
                    .configure_series_labels()
                    .position(SeriesLabelPosition::LowerRight)
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .label_font(("sans-serif", 14))
                    .draw()
                    .map_err(err)?;
            }
            Panel::Torque(_) => {
                chart
                    .draw_series(LineSeries::new(
                        trace.iter().map(|s| (s.time, what.value(s))),
                        blue,
                    ))
                    .map_err(err)?
                    .label("applied torque")
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], blue));
                if let Some(m) = info.tau_max {
                    let bound = red.mix(0.7);
                    for level in [-m, m] {
                        let line = chart
                            .draw_series(LineSeries::new(
                                [(t_start, level), (t_end, level)],
                                bound.stroke_width(2),
                            ))
                            .map_err(err)?;
                        if level > 0.0 {
                            line.label(format!("\u{b1}\u{3c4}_max = \u{b1}{} N m", number(m)))
                                .legend(move |(x, y)| {
                                    PathElement::new([(x, y), (x + 18, y)], bound.stroke_width(2))
                                });
                        }
                    }
                }
                chart
                    .configure_series_labels()
                    .position(SeriesLabelPosition::LowerRight)
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .label_font(("sans-serif", 14))
                    .draw()
                    .map_err(err)?;
            }
            Panel::Angle(_) => {
                chart
                    .draw_series(LineSeries::new(
                        trace.iter().map(|s| (s.time, what.value(s))),
                        blue,
                    ))
                    .map_err(err)?;
            }
        }
    }
    root.present().map_err(err)?;
    Ok(())
}
