//! Output of closed-loop runs for people: the summary text, CSV and the
//! paper-style plots (shared by `eigenmpc simulate` and the FMU demo).

use eigenmpc::mechanics::Vector;
use eigenmpc::mpc::closed_loop::{Sample, Summary};
use plotters::coord::types::RangedCoordf64;
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
    if s.released > 0 {
        let _ = writeln!(
            out,
            "stall supervisor:                {} stall(s), torque released for {} samples",
            s.stalls, s.released
        );
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
    write_csv_with(path, trace, &[], |_| vec![])
}

/// [`write_csv`] with `extra` columns after its own: `extra_cells(i)`
/// gives those of sample `i`. A header cell with a comma or a quote (the
/// FMU's `estimate.A[1,2]`) is quoted as RFC 4180 says.
pub fn write_csv_with<const N: usize, const NX: usize>(
    path: &Path,
    trace: &[Sample<N, NX>],
    extra: &[String],
    mut extra_cells: impl FnMut(usize) -> Vec<String>,
) -> std::io::Result<()> {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    let names = |base: &'static str| (1..=N).map(move |j| format!("{base}{j}"));
    let quote = |cell: &String| {
        if cell.contains([',', '"']) {
            format!("\"{}\"", cell.replace('"', "\"\""))
        } else {
            cell.clone()
        }
    };
    let header: Vec<String> = std::iter::once("time".to_string())
        .chain(names("q"))
        .chain(names("qd"))
        .chain(names("tau"))
        .chain(["energy".to_string(), "solve_ms".to_string()])
        .chain(extra.iter().map(quote))
        .collect();
    writeln!(f, "{}", header.join(","))?;
    for (i, s) in trace.iter().enumerate() {
        write!(f, "{}", s.time)?;
        for v in s.state.iter().chain(s.tau.iter()) {
            write!(f, ",{v}")?;
        }
        write!(f, ",{},{}", s.energy, s.solve_time * 1e3)?;
        for cell in extra_cells(i) {
            write!(f, ",{}", quote(&cell))?;
        }
        writeln!(f)?;
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
    // The font ships with the binary: no system fontconfig needed.
    register_font()?;
    let (rows, cols) = panel_grid(N);
    let size = (520 * cols as u32, 480 * rows as u32);
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

/// Rows and columns of a run's panels (path, energy, every angle, every
/// torque): two rows of `N + 1` up to 3 joints, then rows of 4 (small
/// multiples that stay readable for 6 joints).
fn panel_grid(joints: usize) -> (usize, usize) {
    let panels = 2 * joints + 2;
    let cols = (joints + 1).min(4);
    (panels.div_ceil(cols), cols)
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
    let panels = root.split_evenly(panel_grid(N));
    let t_start = trace.first().map_or(0.0, |s| s.time);
    let t_end = trace.last().map_or(1.0, |s| s.time).max(t_start + 1e-9);
    let (blue, red, grey) = (BLUE_DARK, RED, GREY);
    let path_title = if N >= 2 {
        "joint-space path"
    } else {
        "phase plane"
    };
    draw_path_panel(&panels[0], trace, mode, path_title)?;

    let band = 0.05 * e_ref.abs();
    let reached = crate::report::band_entry(trace, e_ref);
    let series: Vec<Panel> = std::iter::once(Panel::Energy)
        .chain((0..N).map(Panel::Angle))
        .chain((0..N).map(Panel::Torque))
        .collect();
    for (panel, what) in panels[1..].iter().zip(series) {
        let (title, label) = what.title_and_label();
        let mut ys = padded_range(trace.iter().map(|s| what.value(s)));
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
        let mut chart = panel_chart(panel, &title, t_start..t_end, ys.clone())?;
        draw_mesh(&mut chart, "time (s)", &label)?;
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
                draw_legend(&mut chart, SeriesLabelPosition::LowerRight)?;
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
                draw_legend(&mut chart, SeriesLabelPosition::LowerRight)?;
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

/// Dark blue of the closed-loop traces.
pub const BLUE_DARK: RGBColor = RGBColor(8, 48, 107);
/// Red of references (E_ref, the eigenmode band, the torque bound).
pub const RED: RGBColor = RGBColor(214, 39, 40);
/// Grey of markers and secondary references.
pub const GREY: RGBColor = RGBColor(120, 120, 120);
/// Orange of a final orbit compared with a reference (the paper's Fig. 3).
pub const ORANGE: RGBColor = RGBColor(255, 127, 14);
/// Blue of a true eigenmode (the paper's Fig. 3).
pub const BLUE_MODE: RGBColor = RGBColor(31, 119, 180);

/// The chart type of every panel: f64 on both axes.
pub type Panel2d<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The range of the finite `values`, padded by 6 % (-1..1 when there is none).
pub fn padded_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return -1.0..1.0;
    }
    let pad = ((hi - lo) * 0.06).max(1e-3);
    (lo - pad)..(hi + pad)
}

fn plot_error<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> PlotError {
    PlotError(format!("{e}"))
}

/// A panel with a caption, margins that keep the last tick label inside
/// the image, and room for the axis labels.
pub fn panel_chart<'a, DB: DrawingBackend + 'a>(
    area: &'a DrawingArea<DB, plotters::coord::Shift>,
    caption: &str,
    xs: std::ops::Range<f64>,
    ys: std::ops::Range<f64>,
) -> Result<Panel2d<'a, DB>, PlotError>
where
    DB::ErrorType: 'static,
{
    ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 19))
        .margin(12)
        .margin_right(28)
        .x_label_area_size(44)
        .y_label_area_size(60)
        .build_cartesian_2d(xs, ys)
        .map_err(plot_error)
}

/// Grid, axis descriptions and `number()` tick labels (no `-0`).
pub fn draw_mesh<'a, DB: DrawingBackend + 'a>(
    chart: &mut Panel2d<'a, DB>,
    x_desc: &str,
    y_desc: &str,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_label_formatter(&|v| number(*v))
        .y_label_formatter(&|v| number(*v))
        .label_style(("sans-serif", 16))
        .axis_desc_style(("sans-serif", 17))
        .draw()
        .map_err(plot_error)
}

/// The legend of the labelled series in a framed, slightly transparent box.
pub fn draw_legend<'a, DB: DrawingBackend + 'a>(
    chart: &mut Panel2d<'a, DB>,
    position: SeriesLabelPosition,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(plot_error)
}

/// A legend entry: a short line in `style`.
pub fn legend_line(style: ShapeStyle) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    move |(x, y)| PathElement::new([(x, y), (x + 18, y)], style)
}

/// Joint-space panel of a run: the true eigenmode `mode` underneath as a
/// broad light band, the closed loop on top coloured by time (the last 5 s
/// bold), so that the final orbit can be compared with the mode. The axes
/// are the first two angles; a single joint is shown in its phase plane
/// (angle, speed), the mode as its swing on the angle axis.
pub fn draw_path_panel<DB: DrawingBackend, const N: usize, const NX: usize>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    trace: &[Sample<N, NX>],
    mode: &[Vector<N>],
    caption: &str,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let t_start = trace.first().map_or(0.0, |s| s.time);
    let t_end = trace.last().map_or(1.0, |s| s.time).max(t_start + 1e-9);
    let tail_start = t_end - 5.0;
    // The vertical axis: angle 2, or joint 1's speed (state N = 1).
    let y_index = if N >= 2 { 1 } else { N };
    let mode_y = |q: &Vector<N>| if N >= 2 { q[1] } else { 0.0 };
    let xs = padded_range(
        trace
            .iter()
            .map(|s| s.state[0])
            .chain(mode.iter().map(|q| q[0])),
    );
    let ys = padded_range(
        trace
            .iter()
            .map(|s| s.state[y_index])
            .chain(mode.iter().map(mode_y)),
    );
    let mut chart = panel_chart(area, caption, xs, ys)?;
    let y_label = if N >= 2 {
        format!("\u{3b8}{} (rad)", subscript(1))
    } else {
        format!("d\u{3b8}{}/dt (rad/s)", subscript(0))
    };
    draw_mesh(
        &mut chart,
        &format!("\u{3b8}{} (rad)", subscript(0)),
        &y_label,
    )?;
    let band = RED.mix(0.3).stroke_width(7);
    chart
        .draw_series(LineSeries::new(
            mode.iter().map(|q| (q[0], mode_y(q))),
            band,
        ))
        .map_err(plot_error)?
        .label("plant's eigenmode at E_ref")
        .legend(legend_line(band));
    let span = (t_end - t_start).max(1e-9);
    chart
        .draw_series(trace.windows(2).map(|w| {
            let f = (w[1].time - t_start) / span;
            let width = if w[1].time > tail_start { 2 } else { 1 };
            PathElement::new(
                [
                    (w[0].state[0], w[0].state[y_index]),
                    (w[1].state[0], w[1].state[y_index]),
                ],
                time_colour(f).stroke_width(width),
            )
        }))
        .map_err(plot_error)?
        .label("EigenMPC, light to dark over time")
        .legend(legend_line(time_colour(0.3).stroke_width(2)));
    chart
        .draw_series(std::iter::once(PathElement::new(
            Vec::<(f64, f64)>::new(),
            BLUE_DARK.stroke_width(2),
        )))
        .map_err(plot_error)?
        .label("last 5 s (bold)")
        .legend(legend_line(BLUE_DARK.stroke_width(3)));
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)
}

/// Viridis-like colour of `t` in [0, 1] (dark violet to yellow).
pub fn viridis(t: f64) -> RGBColor {
    const STOPS: [(f64, [u8; 3]); 5] = [
        (0.0, [68, 1, 84]),
        (0.25, [59, 82, 139]),
        (0.5, [33, 145, 140]),
        (0.75, [94, 201, 98]),
        (1.0, [253, 231, 37]),
    ];
    let t = t.clamp(0.0, 1.0);
    let i = STOPS.iter().rposition(|(s, _)| *s <= t).unwrap_or(0).min(3);
    let (s0, c0) = STOPS[i];
    let (s1, c1) = STOPS[i + 1];
    let f = (t - s0) / (s1 - s0);
    let mix = |a: u8, b: u8| (a as f64 + (b as f64 - a as f64) * f).round() as u8;
    RGBColor(mix(c0[0], c1[0]), mix(c0[1], c1[1]), mix(c0[2], c1[2]))
}

/// Draws `draw(root)` into a PNG, or an SVG when `path` ends in `.svg`,
/// on a white background with the embedded font.
pub fn with_backend(
    path: &Path,
    size: (u32, u32),
    draw_png: impl FnOnce(
        DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    ) -> Result<(), PlotError>,
    draw_svg: impl FnOnce(DrawingArea<SVGBackend<'_>, plotters::coord::Shift>) -> Result<(), PlotError>,
) -> Result<(), PlotError> {
    register_font()?;
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"))
    {
        draw_svg(SVGBackend::new(path, size).into_drawing_area())
    } else {
        draw_png(BitMapBackend::new(path, size).into_drawing_area())
    }
}

/// The corner of the plot box `xs` x `ys` with the fewest of `points` in
/// its quarter-size box: where a legend hides the least data. Ties go to
/// upper right, upper left, lower right, lower left, in that order.
pub fn quiet_corner(
    points: &[(f64, f64)],
    xs: &std::ops::Range<f64>,
    ys: &std::ops::Range<f64>,
) -> SeriesLabelPosition {
    let (w, h) = (0.5 * (xs.end - xs.start), 0.5 * (ys.end - ys.start));
    let corners = [
        (SeriesLabelPosition::UpperRight, xs.end - w, ys.end - h),
        (SeriesLabelPosition::UpperLeft, xs.start, ys.end - h),
        (SeriesLabelPosition::LowerRight, xs.end - w, ys.start),
        (SeriesLabelPosition::LowerLeft, xs.start, ys.start),
    ];
    let mut best = (usize::MAX, SeriesLabelPosition::UpperRight);
    for (position, x0, y0) in corners {
        let inside = points
            .iter()
            .filter(|p| p.0 >= x0 && p.0 <= x0 + w && p.1 >= y0 && p.1 <= y0 + h)
            .count();
        if inside < best.0 {
            best = (inside, position);
        }
    }
    best.1
}

/// The points of a polyline and the midpoints of its segments (what
/// [`quiet_corner`] counts for a line).
pub fn with_midpoints(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut out = points.to_vec();
    out.extend(
        points
            .windows(2)
            .map(|w| (0.5 * (w[0].0 + w[1].0), 0.5 * (w[0].1 + w[1].1))),
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_legend_goes_where_the_data_is_not() {
        let xs = 0.0..1.0;
        let ys = 0.0..1.0;
        // Data along the rising diagonal: the upper left and lower right are free.
        let diagonal: Vec<(f64, f64)> = (0..=10)
            .map(|k| (k as f64 / 10.0, k as f64 / 10.0))
            .collect();
        assert!(matches!(
            quiet_corner(&diagonal, &xs, &ys),
            SeriesLabelPosition::UpperLeft
        ));
        // Data everywhere but the lower left.
        let mut busy = diagonal.clone();
        busy.extend([(0.1, 0.9), (0.2, 0.8), (0.9, 0.1), (0.8, 0.3)]);
        busy.retain(|p| !(p.0 < 0.5 && p.1 < 0.5));
        assert!(matches!(
            quiet_corner(&busy, &xs, &ys),
            SeriesLabelPosition::LowerLeft
        ));
        assert_eq!(with_midpoints(&[(0.0, 0.0), (1.0, 2.0)]).len(), 3);
    }

    #[test]
    fn numbers_never_show_minus_zero() {
        assert_eq!(number(-0.00001), "0");
        assert_eq!(number(2.50), "2.5");
        assert_eq!(number(-1.23456), "-1.2346");
    }
}
