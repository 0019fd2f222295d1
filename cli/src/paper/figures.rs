//! The paper's figures, drawn from the runs of [`super::RUNS`]: PNG and SVG
//! each, with units, legends and captions.

use super::claims::{FigureEntry, path_distance};
use super::{ChartModel, FIG2_ALPHAS, Modes, RunResult, Runs, eigenvector, tail};
use crate::report::{
    BLUE_MODE, GREY, ORANGE, PlotError, PlotInfo, RED, draw_legend, draw_mesh, draw_path_panel,
    legend_line, number, padded_range, panel_chart, plot_run, viridis, with_backend,
};
use eigenmpc::mechanics::{DoublePendulum, MechanicalSystem, Vector};
use eigenmpc::modes::Family;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::ops::Range;
use std::path::Path;

type Area<DB> = DrawingArea<DB, Shift>;

fn err<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> PlotError {
    PlotError::new(format!("{e}"))
}

const GREEN: RGBColor = RGBColor(44, 160, 44);

/// Fig. 2 draws the final paths of runs closer than this to the mode (rad).
const OFF_MODE: f64 = 0.5;

/// Writes every figure as `<stem>.png` and `<stem>.svg` into `dir`.
pub fn write_all(dir: &Path, runs: &Runs, modes: &Modes) -> Result<Vec<FigureEntry>, PlotError> {
    let mut out = vec![];
    let both = |stem: &'static str,
                caption: String,
                size: (u32, u32),
                png: &dyn Fn(Area<BitMapBackend<'_>>) -> Result<(), PlotError>,
                svg: &dyn Fn(Area<SVGBackend<'_>>) -> Result<(), PlotError>|
     -> Result<FigureEntry, PlotError> {
        for ext in ["png", "svg"] {
            let path = dir.join(format!("{stem}.{ext}"));
            with_backend(&path, size, png, svg)
                .map_err(|e| PlotError::new(format!("{}: {e}", path.display())))?;
        }
        Ok(FigureEntry { stem, caption })
    };
    // One drawing function, called with the PNG and with the SVG backend.
    macro_rules! figure {
        ($stem:expr, $title:expr, $size:expr, $draw:ident($($arg:expr),*)) => {
            out.push(both(
                $stem,
                $title.into(),
                $size,
                &|r| $draw(r, $title, $($arg),*),
                &|r| $draw(r, $title, $($arg),*),
            )?)
        };
    }

    let title1 = "Fig. 1: the 14 J in-phase eigenmode on the potential energy V(\u{3b8}\u{2081}, \u{3b8}\u{2082})";
    figure!("fig1-surface", title1, (1000, 820), fig1(modes));

    let title2 = "Fig. 2: final trajectories of the straight EigenMPC for several \u{3b1} (in-phase, E_ref = 14 J)";
    figure!("fig2-alpha", title2, (1500, 700), fig2(runs, modes));

    let title3 = "Fig. 3: oscillations found by the straight EigenMPC (orange) vs. the true eigenmodes (blue)";
    figure!("fig3-modes", title3, (1200, 1060), fig3(runs, modes));

    for (stem, id, title) in [
        (
            "fig4-straight",
            "fig4-straight",
            "Fig. 4: straight EigenMPC, in-phase, E_ref = 14 J, |\u{3c4}| \u{2264} 1 N m, from q = (0.05, 0.05)",
        ),
        (
            "fig5-curved",
            "fig5-curved",
            "Fig. 5: curved EigenMPC, in-phase, E_ref = 14 J, |\u{3c4}| \u{2264} 1 N m, from q = (0.05, 0.05)",
        ),
    ] {
        let r = runs.get(id);
        let mode = &modes.plant(&r.spec).mode.path;
        let info = PlotInfo {
            caption: title.into(),
            tau_max: Some(1.0),
        };
        for ext in ["png", "svg"] {
            let path = dir.join(format!("{stem}.{ext}"));
            plot_run(&path, &r.trace, mode, r.spec.e_ref, &info)
                .map_err(|e| PlotError::new(format!("{}: {e}", path.display())))?;
        }
        out.push(FigureEntry {
            stem,
            caption: title.into(),
        });
    }

    let title6 = "Fig. 6: convergence from large initial conditions, q = (-1.1, 1.1) rad, in-phase, E_ref = 14 J";
    figure!("fig6-large-ic", title6, (1560, 560), fig6(runs, modes));

    let title7 = "Hybrid EigenMPC (commented out in the paper): chart of a pendulum with m\u{2082} +20 %, \u{3b1} = 0.01, E_ref = 14 J";
    figure!("fig7-hybrid", title7, (1200, 600), fig7(runs, modes));
    Ok(out)
}

fn titled<DB: DrawingBackend>(root: Area<DB>, title: &str) -> Result<Area<DB>, PlotError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    root.titled(title, ("sans-serif", 22)).map_err(err)
}

fn q(s: &eigenmpc::mpc::closed_loop::Sample<2, 4>) -> (f64, f64) {
    (s.state[0], s.state[1])
}

fn points(path: &[Vector<2>]) -> impl Iterator<Item = (f64, f64)> + Clone + '_ {
    path.iter().map(|q| (q[0], q[1]))
}

/// The part of the line through the origin along `e` inside the box.
fn clipped_line(e: &Vector<2>, xs: &Range<f64>, ys: &Range<f64>) -> [(f64, f64); 2] {
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for (c, r) in [(e[0], xs), (e[1], ys)] {
        if c.abs() > 1e-12 {
            let (a, b) = (r.start / c, r.end / c);
            lo = lo.max(a.min(b));
            hi = hi.min(a.max(b));
        }
    }
    if !(lo.is_finite() && hi.is_finite()) || lo > hi {
        return [(0.0, 0.0), (0.0, 0.0)];
    }
    [(e[0] * lo, e[1] * lo), (e[0] * hi, e[1] * hi)]
}

/// Marching squares: the segments of the level set `v = level` of a grid
/// `v[i][j]` at `(x[i], y[j])`.
fn contour(x: &[f64], y: &[f64], v: &[Vec<f64>], level: f64) -> Vec<[(f64, f64); 2]> {
    let mut segments = vec![];
    let cross = |p: (f64, f64), vp: f64, r: (f64, f64), vr: f64| {
        let t = (level - vp) / (vr - vp);
        (p.0 + t * (r.0 - p.0), p.1 + t * (r.1 - p.1))
    };
    for i in 0..x.len() - 1 {
        for j in 0..y.len() - 1 {
            let corners = [
                ((x[i], y[j]), v[i][j]),
                ((x[i + 1], y[j]), v[i + 1][j]),
                ((x[i + 1], y[j + 1]), v[i + 1][j + 1]),
                ((x[i], y[j + 1]), v[i][j + 1]),
            ];
            let mut hits = vec![];
            for k in 0..4 {
                let (p, vp) = corners[k];
                let (r, vr) = corners[(k + 1) % 4];
                if (vp < level) != (vr < level) {
                    hits.push(cross(p, vp, r, vr));
                }
            }
            for pair in hits.chunks_exact(2) {
                segments.push([pair[0], pair[1]]);
            }
        }
    }
    segments
}

fn fig1<DB: DrawingBackend>(root: Area<DB>, title: &str, modes: &Modes) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let root = titled(root, title)?;
    let plant = DoublePendulum::default();
    let pi = std::f64::consts::PI;
    let n = 121;
    let grid: Vec<f64> = (0..n)
        .map(|k| -pi + 2.0 * pi * k as f64 / (n - 1) as f64)
        .collect();
    let v: Vec<Vec<f64>> = grid
        .iter()
        .map(|&a| {
            grid.iter()
                .map(|&b| plant.potential(&Vector::<2>::new(a, b)))
                .collect()
        })
        .collect();
    let v_max = v.iter().flatten().copied().fold(0.0, f64::max);
    let (main, bar) = root.split_horizontally(860);
    let mut chart = panel_chart(&main, "", -pi..pi, -pi..pi)?;
    draw_mesh(&mut chart, "\u{3b8}\u{2081} (rad)", "\u{3b8}\u{2082} (rad)")?;
    let h = pi / (n - 1) as f64;
    chart
        .draw_series(grid.iter().enumerate().flat_map(|(i, &a)| {
            let v = &v;
            grid.iter().enumerate().map(move |(j, &b)| {
                Rectangle::new(
                    [(a - h, b - h), (a + h, b + h)],
                    viridis(v[i][j] / v_max).mix(0.75).filled(),
                )
            })
        }))
        .map_err(err)?;
    let mut levels = vec![];
    let mut level = 5.0;
    while level < v_max {
        levels.push(level);
        level += 5.0;
    }
    let line = RGBColor(40, 40, 40).mix(0.6);
    for (k, &l) in levels.iter().enumerate() {
        let series = chart
            .draw_series(
                contour(&grid, &grid, &v, l)
                    .into_iter()
                    .map(|s| PathElement::new(s.to_vec(), line.stroke_width(1))),
            )
            .map_err(err)?;
        if k == 0 {
            series
                .label("level sets of V, every 5 J")
                .legend(legend_line(line.stroke_width(1)));
        }
    }
    let white = WHITE.stroke_width(2);
    chart
        .draw_series(
            contour(&grid, &grid, &v, 14.0)
                .into_iter()
                .map(|s| PathElement::new(s.to_vec(), white)),
        )
        .map_err(err)?
        .label("V = 14 J")
        .legend(legend_line(RGBColor(200, 200, 200).stroke_width(2)));
    let mode = &modes.get(ChartModel::Plant, Family::InPhase, 14.0).mode;
    chart
        .draw_series(LineSeries::new(points(&mode.path), RED.stroke_width(4)))
        .map_err(err)?
        .label("eigenmode, in-phase, 14 J")
        .legend(legend_line(RED.stroke_width(4)));
    chart
        .draw_series(
            [mode.turning_point, mode.other_turning_point]
                .into_iter()
                .map(|p| Circle::new((p[0], p[1]), 6, RED.filled())),
        )
        .map_err(err)?
        .label("turning points (at rest, V = E)")
        .legend(|(x, y)| Circle::new((x + 9, y), 5, RED.filled()));
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
    // Colour bar of V.
    let mut cb = ChartBuilder::on(&bar)
        .margin_top(40)
        .margin_bottom(60)
        .margin_right(20)
        .y_label_area_size(56)
        .build_cartesian_2d(0.0..1.0, 0.0..v_max)
        .map_err(err)?;
    cb.configure_mesh()
        .disable_x_mesh()
        .disable_x_axis()
        .y_desc("V (J)")
        .y_label_formatter(&|v| number(*v))
        .label_style(("sans-serif", 16))
        .axis_desc_style(("sans-serif", 17))
        .draw()
        .map_err(err)?;
    let steps = 64;
    cb.draw_series((0..steps).map(|k| {
        let lo = v_max * k as f64 / steps as f64;
        let hi = v_max * (k + 1) as f64 / steps as f64;
        Rectangle::new(
            [(0.0, lo), (1.0, hi)],
            viridis((k as f64 + 0.5) / steps as f64).mix(0.75).filled(),
        )
    }))
    .map_err(err)?;
    root.present().map_err(err)
}

fn fig2<DB: DrawingBackend>(
    root: Area<DB>,
    title: &str,
    runs: &Runs,
    modes: &Modes,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let root = titled(root, title)?;
    let (left, right) = root.split_horizontally(820);
    let alpha_runs = runs.fig2();
    let mode = &modes
        .get(ChartModel::Plant, Family::InPhase, 14.0)
        .mode
        .path;
    let e = eigenvector(Family::InPhase);
    // Runs that left the mode (far off, chaotic-looking) would set the
    // scale: they are listed in the legend and shown on the right only.
    let (shown, left_out): (Vec<&RunResult>, Vec<&RunResult>) = alpha_runs
        .iter()
        .partition(|r| r.summary.rms_distance.is_some_and(|d| d < OFF_MODE));
    let xs = padded_range(
        shown
            .iter()
            .flat_map(|r| tail(&r.trace, 5.0).map(|s| s.state[0]))
            .chain(mode.iter().map(|q| q[0])),
    );
    let ys = padded_range(
        shown
            .iter()
            .flat_map(|r| tail(&r.trace, 5.0).map(|s| s.state[1]))
            .chain(mode.iter().map(|q| q[1])),
    );
    let mut chart = panel_chart(
        &left,
        "final trajectories (last 5 s)",
        xs.clone(),
        ys.clone(),
    )?;
    draw_mesh(&mut chart, "\u{3b8}\u{2081} (rad)", "\u{3b8}\u{2082} (rad)")?;
    let black = BLACK.stroke_width(2);
    chart
        .draw_series(DottedLineSeries::new(
            clipped_line(&e, &xs, &ys),
            0,
            8,
            |c| Circle::new(c, 2, GREY.filled()),
        ))
        .map_err(err)?
        .label("linear mode (eigenvector)")
        .legend(|(x, y)| Circle::new((x + 9, y), 2, GREY.filled()));
    chart
        .draw_series(DashedLineSeries::new(points(mode), 10, 6, black))
        .map_err(err)?
        .label("true eigenmode, 14 J")
        .legend(legend_line(black));
    let colour_of = |r: &RunResult| {
        let k = alpha_runs
            .iter()
            .position(|a| a.spec.id == r.spec.id)
            .unwrap_or(0);
        viridis(k as f64 / (alpha_runs.len() - 1).max(1) as f64 * 0.85)
    };
    for r in &shown {
        let colour = colour_of(r);
        chart
            .draw_series(LineSeries::new(
                tail(&r.trace, 5.0).map(q),
                colour.stroke_width(2),
            ))
            .map_err(err)?
            .label(format!("\u{3b1} = {}", number(r.spec.alpha)))
            .legend(legend_line(colour.stroke_width(2)));
    }
    for r in &left_out {
        let colour = colour_of(r);
        chart
            .draw_series(std::iter::empty::<PathElement<(f64, f64)>>())
            .map_err(err)?
            .label(format!(
                "\u{3b1} = {}: leaves the mode ({} rad off, right)",
                number(r.spec.alpha),
                number(r.summary.rms_distance.unwrap_or(f64::NAN))
            ))
            .legend(move |(x, y)| Cross::new((x + 9, y), 5, colour.stroke_width(2)));
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)?;

    let d_mode: Vec<(f64, f64)> = alpha_runs
        .iter()
        .map(|r| (r.spec.alpha, r.summary.rms_distance.unwrap_or(f64::NAN)))
        .collect();
    let d_line: Vec<(f64, f64)> = alpha_runs
        .iter()
        .map(|r| (r.spec.alpha, r.line_distance))
        .collect();
    let a_max = FIG2_ALPHAS[FIG2_ALPHAS.len() - 1];
    let ys = padded_range(d_mode.iter().chain(&d_line).map(|p| p.1).chain([0.0]));
    let mut chart = panel_chart(
        &right,
        "RMS distance of the last 5 s",
        -0.02 * a_max..1.04 * a_max,
        ys,
    )?;
    draw_mesh(&mut chart, "\u{3b1}", "distance (rad)")?;
    let finite = |v: &[(f64, f64)]| -> Vec<(f64, f64)> {
        v.iter().copied().filter(|p| p.1.is_finite()).collect()
    };
    for (data, colour, label) in [
        (finite(&d_mode), BLUE_MODE, "to the true eigenmode"),
        (finite(&d_line), GREY, "to the linear mode (line)"),
    ] {
        chart
            .draw_series(LineSeries::new(data.clone(), colour.stroke_width(2)))
            .map_err(err)?
            .label(label)
            .legend(legend_line(colour.stroke_width(2)));
        chart
            .draw_series(data.iter().map(|&p| Circle::new(p, 5, colour.filled())))
            .map_err(err)?;
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
    root.present().map_err(err)
}

/// A joint-space panel comparing final orbits with reference paths.
struct Compare<'a> {
    caption: String,
    /// Reference paths drawn first: points, colour, width, dashed, label.
    references: Vec<(&'a [Vector<2>], RGBColor, u32, bool, String)>,
    /// Final orbits drawn on top: run, colour, label.
    orbits: Vec<(&'a RunResult, RGBColor, String)>,
    /// The linear eigenvector drawn dotted, if given.
    line: Option<Vector<2>>,
}

fn compare_panel<DB: DrawingBackend>(area: &Area<DB>, c: &Compare<'_>) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let xs = padded_range(
        c.references
            .iter()
            .flat_map(|r| r.0.iter().map(|q| q[0]))
            .chain(
                c.orbits
                    .iter()
                    .flat_map(|o| tail(&o.0.trace, 5.0).map(|s| s.state[0])),
            ),
    );
    let ys = padded_range(
        c.references
            .iter()
            .flat_map(|r| r.0.iter().map(|q| q[1]))
            .chain(
                c.orbits
                    .iter()
                    .flat_map(|o| tail(&o.0.trace, 5.0).map(|s| s.state[1])),
            ),
    );
    let mut chart = panel_chart(area, &c.caption, xs.clone(), ys.clone())?;
    draw_mesh(&mut chart, "\u{3b8}\u{2081} (rad)", "\u{3b8}\u{2082} (rad)")?;
    if let Some(e) = c.line {
        chart
            .draw_series(DottedLineSeries::new(
                clipped_line(&e, &xs, &ys),
                0,
                8,
                |p| Circle::new(p, 2, GREY.filled()),
            ))
            .map_err(err)?
            .label("linear mode")
            .legend(|(x, y)| Circle::new((x + 9, y), 2, GREY.filled()));
    }
    // Solid references under the orbits, dashed ones on top (thin, visible).
    for (path, colour, width, _, label) in c.references.iter().filter(|r| !r.3) {
        let style = colour.stroke_width(*width);
        chart
            .draw_series(LineSeries::new(points(path), style))
            .map_err(err)?
            .label(label.as_str())
            .legend(legend_line(style));
    }
    for (run, colour, label) in &c.orbits {
        let style = colour.stroke_width(2);
        chart
            .draw_series(LineSeries::new(tail(&run.trace, 5.0).map(q), style))
            .map_err(err)?
            .label(label.as_str())
            .legend(legend_line(style));
    }
    for (path, colour, width, _, label) in c.references.iter().filter(|r| r.3) {
        let style = colour.stroke_width(*width);
        chart
            .draw_series(DashedLineSeries::new(points(path), 10, 6, style))
            .map_err(err)?
            .label(label.as_str())
            .legend(legend_line(style));
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)
}

fn fig3<DB: DrawingBackend>(
    root: Area<DB>,
    title: &str,
    runs: &Runs,
    modes: &Modes,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let root = titled(root, title)?;
    let panels = root.split_evenly((2, 2));
    for (panel, (id, label)) in panels.iter().zip([
        ("fig3-in-phase-2", "(a) in-phase, E_ref = 2 J"),
        ("fig3-in-phase-16", "(b) in-phase, E_ref = 16 J"),
        ("fig3-anti-phase-2", "(c) anti-phase, E_ref = 2 J"),
        ("fig3-anti-phase-12", "(d) anti-phase, E_ref = 12 J"),
    ]) {
        let r = runs.get(id);
        let mode = &modes.plant(&r.spec).mode.path;
        compare_panel(
            panel,
            &Compare {
                caption: format!(
                    "{label}: {} rad apart",
                    number(r.summary.rms_distance.unwrap_or(f64::NAN))
                ),
                references: vec![(mode, BLUE_MODE, 2, false, "true eigenmode".into())],
                orbits: vec![(r, ORANGE, "straight EigenMPC, last 5 s".into())],
                line: Some(eigenvector(r.spec.family)),
            },
        )?;
    }
    root.present().map_err(err)
}

fn fig6<DB: DrawingBackend>(
    root: Area<DB>,
    title: &str,
    runs: &Runs,
    modes: &Modes,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let root = titled(root, title)?;
    let panels = root.split_evenly((1, 3));
    let s = runs.get("fig6-straight");
    let c = runs.get("fig6-curved");
    let mode = &modes.plant(&s.spec).mode.path;
    draw_path_panel(&panels[0], &s.trace, mode, "(a) straight EigenMPC")?;
    draw_path_panel(&panels[1], &c.trace, mode, "(b) curved EigenMPC")?;
    let e_ref = s.spec.e_ref;
    let t_end = s.trace.last().map_or(1.0, |x| x.time).max(1e-9);
    let ys = padded_range(
        s.trace
            .iter()
            .chain(&c.trace)
            .map(|x| x.energy)
            .chain([0.0, 1.1 * e_ref]),
    );
    let mut chart = panel_chart(&panels[2], "energy", 0.0..t_end, ys)?;
    draw_mesh(&mut chart, "time (s)", "E (J)")?;
    let band = GREEN.mix(0.18);
    chart
        .draw_series(std::iter::once(Rectangle::new(
            [(0.0, 0.95 * e_ref), (t_end, 1.05 * e_ref)],
            band.filled(),
        )))
        .map_err(err)?
        .label("5 % band")
        .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 18, y + 5)], band.filled()));
    chart
        .draw_series(LineSeries::new([(0.0, e_ref), (t_end, e_ref)], RED))
        .map_err(err)?
        .label(format!("E_ref = {} J", number(e_ref)))
        .legend(legend_line(RED.into()));
    for (r, colour, label) in [(s, ORANGE, "straight"), (c, BLUE_MODE, "curved")] {
        chart
            .draw_series(LineSeries::new(
                r.trace.iter().map(|x| (x.time, x.energy)),
                colour.stroke_width(2),
            ))
            .map_err(err)?
            .label(label)
            .legend(legend_line(colour.stroke_width(2)));
    }
    draw_legend(&mut chart, SeriesLabelPosition::LowerRight)?;
    root.present().map_err(err)
}

fn fig7<DB: DrawingBackend>(
    root: Area<DB>,
    title: &str,
    runs: &Runs,
    modes: &Modes,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let root = titled(root, title)?;
    let panels = root.split_evenly((1, 2));
    for (panel, family) in panels.iter().zip([Family::InPhase, Family::AntiPhase]) {
        let h = runs.get(&format!("hybrid-{family}"));
        let cw = runs.get(&format!("curved-wrong-{family}"));
        let true_mode = &modes.get(ChartModel::Plant, family, 14.0).mode.path;
        let chart_mode = &modes.get(ChartModel::HeavierM2, family, 14.0).mode.path;
        let offset = path_distance(chart_mode, true_mode);
        compare_panel(
            panel,
            &Compare {
                caption: format!("{family} mode"),
                references: vec![
                    (
                        true_mode,
                        BLUE_MODE,
                        3,
                        false,
                        "plant's true eigenmode".into(),
                    ),
                    (
                        chart_mode,
                        BLACK,
                        1,
                        true,
                        format!(
                            "the cost's chart (m\u{2082} +20 %), {} rad off",
                            number(offset)
                        ),
                    ),
                ],
                orbits: vec![
                    (
                        h,
                        ORANGE,
                        format!(
                            "hybrid, last 5 s: {} rad off",
                            number(h.summary.rms_distance.unwrap_or(f64::NAN))
                        ),
                    ),
                    (
                        cw,
                        GREEN,
                        format!(
                            "curved, same chart: {} rad off",
                            number(cw.summary.rms_distance.unwrap_or(f64::NAN))
                        ),
                    ),
                ],
                line: None,
            },
        )?;
    }
    root.present().map_err(err)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contour_of_a_cone_is_a_circle() {
        let g: Vec<f64> = (0..41).map(|k| -2.0 + 0.1 * k as f64).collect();
        let v: Vec<Vec<f64>> = g
            .iter()
            .map(|&a| g.iter().map(|&b| (a * a + b * b).sqrt()).collect())
            .collect();
        let segments = contour(&g, &g, &v, 1.0);
        assert!(segments.len() > 40);
        for s in segments {
            for p in s {
                // Linear interpolation of a cone: within a cell's sag of the circle.
                assert!(((p.0 * p.0 + p.1 * p.1).sqrt() - 1.0).abs() < 5e-3, "{p:?}");
            }
        }
    }

    #[test]
    fn clipped_line_stays_in_the_box() {
        let e = Vector::<2>::new(0.6, 0.8);
        let [a, b] = clipped_line(&e, &(-1.0..2.0), &(-0.5..1.0));
        for p in [a, b] {
            assert!(p.0 >= -1.0 - 1e-12 && p.0 <= 2.0 + 1e-12);
            assert!(p.1 >= -0.5 - 1e-12 && p.1 <= 1.0 + 1e-12);
        }
        assert!((b.1 - 1.0).abs() < 1e-12 && (a.1 + 0.5).abs() < 1e-12);
    }
}
