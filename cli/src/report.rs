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
            Panel::Angle(j) => (format!("theta{}", j + 1), format!("theta{} (rad)", j + 1)),
            Panel::Torque(j) => (format!("tau{}", j + 1), format!("tau{} (N m)", j + 1)),
        }
    }
}

const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Draws the paper-style panels of a run (joint-space path in theta1,
/// theta2 with the true eigenmode, energy, every theta_j, every tau_j): PNG,
/// or SVG when the file name ends in `.svg`.
pub fn plot_run<const N: usize, const NX: usize>(
    path: &Path,
    trace: &[Sample<N, NX>],
    mode: &[Vector<N>],
    e_ref: f64,
) -> Result<(), PlotError> {
    const { assert!(N >= 2, "the joint-space panel needs two joints") };
    // The font ships with the binary: no system fontconfig needed.
    register_font()?;
    let size = (500 * (N as u32 + 1), 900);
    let svg = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"));
    if svg {
        draw(
            SVGBackend::new(path, size).into_drawing_area(),
            trace,
            mode,
            e_ref,
        )
    } else {
        draw(
            BitMapBackend::new(path, size).into_drawing_area(),
            trace,
            mode,
            e_ref,
        )
    }
}

fn draw<DB: DrawingBackend, const N: usize, const NX: usize>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    trace: &[Sample<N, NX>],
    mode: &[Vector<N>],
    e_ref: f64,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| PlotError(format!("{e}"));
    root.fill(&WHITE).map_err(err)?;
    let panels = root.split_evenly((2, N + 1));
    let t_end = trace.last().map_or(1.0, |s| s.time).max(1e-9);
    let range = |vals: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
        let pad = ((hi - lo) * 0.05).max(1e-3);
        (lo - pad)..(hi + pad)
    };

    // Joint-space path with the true eigenmode (both branches of the orbit).
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
            .caption("joint-space path", ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d(xs, ys)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("theta1 (rad)")
            .y_desc("theta2 (rad)")
            .draw()
            .map_err(err)?;
        chart
            .draw_series(LineSeries::new(
                trace.iter().map(|s| (s.state[0], s.state[1])),
                BLUE.mix(0.6),
            ))
            .map_err(err)?
            .label("EigenMPC")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 15, y)], BLUE));
        chart
            .draw_series(LineSeries::new(
                mode.iter().map(|q| (q[0], q[1])),
                RED.stroke_width(2),
            ))
            .map_err(err)?
            .label("eigenmode at E_ref")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 15, y)], RED));
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(err)?;
    }

    let series: Vec<Panel> = std::iter::once(Panel::Energy)
        .chain((0..N).map(Panel::Angle))
        .chain((0..N).map(Panel::Torque))
        .collect();
    for (panel, what) in panels[1..].iter().zip(series) {
        let (title, label) = what.title_and_label();
        let energy = matches!(what, Panel::Energy);
        let mut ys = range(&mut trace.iter().map(|s| what.value(s)));
        if energy {
            ys = ys.start.min(e_ref * 0.9)..ys.end.max(e_ref * 1.1);
        }
        let mut chart = ChartBuilder::on(panel)
            .caption(&title, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d(0.0..t_end, ys)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc(&label)
            .draw()
            .map_err(err)?;
        chart
            .draw_series(LineSeries::new(
                trace.iter().map(|s| (s.time, what.value(s))),
                BLUE,
            ))
            .map_err(err)?;
        if energy {
            chart
                .draw_series(LineSeries::new([(0.0, e_ref), (t_end, e_ref)], RED))
                .map_err(err)?;
        }
    }
    root.present().map_err(err)?;
    Ok(())
}
