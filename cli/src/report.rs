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

/// The summary figures as aligned text lines (time to 5 %, final energy
/// error, RMS torque and distance over the last 5 s, solve times).
pub fn summary_text(s: &Summary<2>) -> String {
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
    let _ = writeln!(
        out,
        "RMS torque, last 5 s:            {:.4} / {:.4} N m",
        s.rms_torque[0], s.rms_torque[1]
    );
    if let Some(d) = s.rms_distance {
        let _ = writeln!(out, "RMS distance to the mode, last 5 s: {d:.4} rad");
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
/// `time,q1,q2,qd1,qd2,tau1,tau2,energy,solve_ms`.
pub fn write_csv(path: &Path, trace: &[Sample<2, 4>]) -> std::io::Result<()> {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(f, "time,q1,q2,qd1,qd2,tau1,tau2,energy,solve_ms")?;
    for s in trace {
        let z = &s.state;
        writeln!(
            f,
            "{},{},{},{},{},{},{},{},{}",
            s.time,
            z[0],
            z[1],
            z[2],
            z[3],
            s.tau[0],
            s.tau[1],
            s.energy,
            s.solve_time * 1e3
        )?;
    }
    f.flush()
}

/// One plotted quantity of a sample.
type SampleValue = fn(&Sample<2, 4>) -> f64;

const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Draws the paper-style panels of a run (joint-space path with the true
/// eigenmode, energy, theta1, theta2, tau1, tau2): PNG, or SVG when the file
/// name ends in `.svg`.
pub fn plot_run(
    path: &Path,
    trace: &[Sample<2, 4>],
    mode: &[Vector<2>],
    e_ref: f64,
) -> Result<(), PlotError> {
    // The font ships with the binary: no system fontconfig needed.
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
        .map_err(|_| PlotError("embedded font is invalid".into()))?;
    let size = (1500, 900);
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

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    trace: &[Sample<2, 4>],
    mode: &[Vector<2>],
    e_ref: f64,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| PlotError(format!("{e:?}"));
    root.fill(&WHITE).map_err(err)?;
    let panels = root.split_evenly((2, 3));
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

    let series: [(&str, &str, SampleValue); 5] = [
        ("energy", "E (J)", |s| s.energy),
        ("theta1", "theta1 (rad)", |s| s.state[0]),
        ("theta2", "theta2 (rad)", |s| s.state[1]),
        ("tau1", "tau1 (N m)", |s| s.tau[0]),
        ("tau2", "tau2 (N m)", |s| s.tau[1]),
    ];
    for (panel, (title, label, f)) in panels[1..].iter().zip(series.iter()) {
        let mut ys = range(&mut trace.iter().map(f));
        if *title == "energy" {
            ys = ys.start.min(e_ref * 0.9)..ys.end.max(e_ref * 1.1);
        }
        let mut chart = ChartBuilder::on(panel)
            .caption(*title, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d(0.0..t_end, ys)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc(*label)
            .draw()
            .map_err(err)?;
        chart
            .draw_series(LineSeries::new(trace.iter().map(|s| (s.time, f(s))), BLUE))
            .map_err(err)?;
        if *title == "energy" {
            chart
                .draw_series(LineSeries::new([(0.0, e_ref), (t_end, e_ref)], RED))
                .map_err(err)?;
        }
    }
    root.present().map_err(err)?;
    Ok(())
}
