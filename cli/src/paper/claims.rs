//! The paper's claims about its figures, each measured on this project's
//! runs and given a verdict, and `report.md` that lists them.

use super::{
    ChartModel, Extent, FIG2_ALPHAS, Modes, RunResult, Runs, eigenvector, rms_line_distance, tail,
};
use crate::report::number;
use eigenmpc::mechanics::{DoublePendulum, MechanicalSystem, Vector};
use eigenmpc::modes::Family;
use eigenmpc::mpc::closed_loop::distance_to_path;
use std::fmt::Write as _;

/// Whether a claim reproduces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Measured as the paper says.
    Holds,
    /// True for part of what the paper says (the reason says which).
    Partly,
    /// Measured otherwise.
    Differs,
}

impl Verdict {
    fn of(ok: bool) -> Self {
        if ok { Verdict::Holds } else { Verdict::Differs }
    }

    /// The word in the report.
    pub fn word(self) -> &'static str {
        match self {
            Verdict::Holds => "holds",
            Verdict::Partly => "partly",
            Verdict::Differs => "differs",
        }
    }
}

/// One claim of the paper's text, what was measured and the verdict.
#[derive(Clone, Debug)]
pub struct Claim {
    /// Short id (`C1`, ...), stable across runs.
    pub id: &'static str,
    /// The figure the claim is about.
    pub figure: &'static str,
    /// What the paper says (quoted or closely paraphrased).
    pub paper: &'static str,
    /// What this project measured.
    pub measured: String,
    /// The verdict.
    pub verdict: Verdict,
    /// Why: the criterion, and the reason when it differs.
    pub why: String,
}

/// Distances below this are "on the mode" (rad, RMS over the last 5 s).
pub const NEAR: f64 = 0.05;
/// Final RMS torque norms below this are "near zero" (N m, 5 % of the bound).
pub const SMALL_TORQUE: f64 = 0.05;
/// The paper's worst average computation time per sample (s).
pub const PAPER_WORST_MEAN_SOLVE: f64 = 5.3e-3;

fn rms_norm(v: &Vector<2>) -> f64 {
    v.norm()
}

/// `number`, but small nonzero values in scientific notation (not `0`).
fn small(x: f64) -> String {
    if x != 0.0 && x.abs() < 1e-3 {
        format!("{x:.1e}")
    } else {
        number(x)
    }
}

/// The verdict of a yes/no criterion and its explanation either way.
fn judge(ok: bool, holds: &str, differs: &str) -> (Verdict, String) {
    (
        Verdict::of(ok),
        if ok { holds } else { differs }.to_string(),
    )
}

fn band(t: Option<f64>) -> String {
    t.map_or("never in the 5 % band for good".into(), |t| {
        format!("in the 5 % band from {} s", number(t))
    })
}

fn time(t: Option<f64>) -> String {
    t.map_or("not reached".into(), |t| format!("{} s", number(t)))
}

fn reached_near(r: &RunResult) -> bool {
    r.summary.time_to_5_percent.is_some() && r.summary.rms_distance.is_some_and(|d| d < NEAR)
}

fn distance(r: &RunResult) -> f64 {
    r.summary.rms_distance.unwrap_or(f64::NAN)
}

/// RMS over the samples of `r` with `lo <= E/E_ref < hi` of the distance to `path`.
fn band_distance(r: &RunResult, lo: f64, hi: f64, path: &[Vector<2>]) -> f64 {
    let (sum, n) = r
        .trace
        .iter()
        .filter(|s| s.energy >= lo * r.spec.e_ref && s.energy < hi * r.spec.e_ref)
        .map(|s| distance_to_path(&s.state.fixed_rows::<2>(0).into_owned(), path).powi(2))
        .fold((0.0, 0usize), |(a, n), d| (a + d, n + 1));
    if n == 0 {
        f64::NAN
    } else {
        (sum / n as f64).sqrt()
    }
}

/// RMS distance of `a`'s points to the polyline `b`.
pub fn path_distance(a: &[Vector<2>], b: &[Vector<2>]) -> f64 {
    let sum: f64 = a.iter().map(|q| distance_to_path(q, b).powi(2)).sum();
    (sum / a.len().max(1) as f64).sqrt()
}

fn final_path(r: &RunResult) -> Vec<Vector<2>> {
    tail(&r.trace, 5.0)
        .map(|s| s.state.fixed_rows::<2>(0).into_owned())
        .collect()
}

/// The verdict and explanation of a claim; the struct-update base of the
/// claims below (their other fields are set in place).
fn claim((verdict, why): (Verdict, String)) -> Claim {
    Claim {
        id: "",
        figure: "",
        paper: "",
        measured: String::new(),
        verdict,
        why,
    }
}

/// Measures every claim.
pub fn claims(runs: &Runs, modes: &Modes) -> Vec<Claim> {
    let mut out = vec![];
    let plant = DoublePendulum::default();

    // Fig. 1: the 14 J in-phase eigenmode is a brake orbit on V's level set.
    let m14 = &modes.get(ChartModel::Plant, Family::InPhase, 14.0).mode;
    let v_a = plant.potential(&m14.turning_point) - m14.energy;
    let v_b = plant.potential(&m14.other_turning_point) - m14.energy;
    out.push(Claim {
        id: "C1",
        figure: "Fig. 1",
        paper: "An eigenmode is a line-shaped oscillation between two rest poses on the potential surface (the red line).",
        measured: format!(
            "14 J in-phase mode: V(turning points) - E = {:.1e} / {:.1e} J, orbit closes to {:.1e}, half period {} s",
            v_a,
            v_b,
            m14.closing_error,
            number(m14.half_period)
        ),
        verdict: Verdict::of(
            v_a.abs() < 1e-4 && v_b.abs() < 1e-4 && m14.closing_error < 1e-6,
        ),
        why: "both ends at rest on the level set V = E, and the orbit retraces itself".into(),
    });

    // Fig. 2: alpha moves the final trajectory from the linear mode to the eigenmode.
    let e_in = eigenvector(Family::InPhase);
    let mode_line = rms_line_distance(m14.path.iter().copied(), &e_in);
    let alpha_runs = runs.fig2();
    let a0 = alpha_runs[0];
    out.push(Claim {
        id: "C2",
        figure: "Fig. 2",
        paper: "With alpha = 0 the system converges to the linear mode (dotted line).",
        measured: format!(
            "alpha = 0, 14 J: {} rad from the eigenvector line, {} rad from the true mode (the mode itself is {} rad from the line)",
            small(a0.line_distance),
            small(distance(a0)),
            small(mode_line)
        ),
        ..claim(judge(
            a0.line_distance < distance(a0),
            "closer to the line than to the true eigenmode",
            "closer to the true eigenmode than to the line",
        ))
    });
    let d: Vec<f64> = alpha_runs.iter().map(|r| distance(r)).collect();
    let falls = d.windows(2).take_while(|w| w[1] < w[0]).count();
    let verdict = if falls + 1 == d.len() {
        Verdict::Holds
    } else if falls > 0 {
        Verdict::Partly
    } else {
        Verdict::Differs
    };
    out.push(Claim {
        id: "C3",
        figure: "Fig. 2",
        paper: "For increasing alpha the final trajectory approaches the actual eigenmode (dashed line).",
        measured: format!(
            "distance to the true 14 J mode for alpha = {}: {} rad",
            FIG2_ALPHAS.map(number).join(", "),
            d.iter().map(|v| small(*v)).collect::<Vec<_>>().join(", ")
        ),
        verdict,
        why: match verdict {
            Verdict::Holds => "the distance falls with every larger alpha".into(),
            Verdict::Partly => format!(
                "it falls up to alpha = {}; at alpha = {} the loop leaves the mode ({} rad, energy {} J at the end)",
                number(FIG2_ALPHAS[falls]),
                number(FIG2_ALPHAS[falls + 1]),
                number(d[falls + 1]),
                number(alpha_runs[falls + 1].spec.e_ref + alpha_runs[falls + 1].summary.final_energy_error)
            ),
            Verdict::Differs => "the distance does not fall from alpha = 0 to the next alpha".into(),
        },
    });

    // Fig. 3: modes found by the straight variant.
    for (id, run_id, what) in [
        ("C4", "fig3-in-phase-2", "in-phase, 2 J"),
        ("C5", "fig3-in-phase-16", "in-phase, 16 J (the most curved)"),
        ("C6", "fig3-anti-phase-2", "anti-phase, 2 J"),
        ("C7", "fig3-anti-phase-12", "anti-phase, 12 J"),
    ] {
        let r = runs.get(run_id);
        out.push(Claim {
            id,
            figure: "Fig. 3",
            paper: "The straight EigenMPC finds oscillations close to the actual eigenmodes, straight and curved ones.",
            measured: format!(
                "{what}: {} rad from the true mode, {}, final torque {} N m RMS",
                small(distance(r)),
                band(r.summary.time_to_5_percent),
                number(rms_norm(&r.summary.rms_torque))
            ),
            verdict: Verdict::of(reached_near(r)),
            why: if reached_near(r) {
                format!("in the band and within {NEAR} rad of the mode")
            } else if r.summary.time_to_5_percent.is_none() {
                format!(
                    "the energy does not stay in the 5 % band (error {} J at the end)",
                    number(r.summary.final_energy_error)
                )
            } else {
                format!("in the band but farther than {NEAR} rad from the mode")
            },
        });
    }
    let r2 = runs.get("fig3-in-phase-2");
    let m2 = &modes.get(ChartModel::Plant, Family::InPhase, 2.0).mode;
    let m2_line = rms_line_distance(m2.path.iter().copied(), &e_in);
    out.push(Claim {
        id: "C8",
        figure: "Fig. 3a",
        paper: "At 2 J in-phase the path is slightly straighter than the actual eigenmode.",
        measured: format!(
            "final path {} rad from the eigenvector line, the true mode {} rad",
            small(r2.line_distance),
            small(m2_line)
        ),
        ..claim(judge(
            r2.line_distance < m2_line,
            "closer to the eigenvector line than the mode is",
            "no straighter than the mode",
        ))
    });
    let r14 = runs.get("anti-phase-14");
    let r12 = runs.get("fig3-anti-phase-12");
    out.push(Claim {
        id: "C9",
        figure: "Fig. 3d",
        paper: "12 J is the highest energy for which the straight version finds a line-shaped anti-phase mode.",
        measured: format!(
            "anti-phase 12 J: {} rad from its mode, band {}; 14 J: {} rad, band {}",
            small(distance(r12)),
            time(r12.summary.time_to_5_percent),
            small(distance(r14)),
            time(r14.summary.time_to_5_percent)
        ),
        verdict: Verdict::of(reached_near(r12) && !reached_near(r14)),
        why: if reached_near(r14) {
            "14 J is found as well".into()
        } else if !reached_near(r12) {
            "12 J is not found".into()
        } else {
            "12 J found, 14 J not".into()
        },
    });

    // Figs. 4 and 5: straight and curved at 14 J from near rest.
    let s = runs.get("fig4-straight");
    let c = runs.get("fig5-curved");
    let s_low = band_line_distance(s, 0.0, 0.25, &e_in);
    let s_final = s.line_distance;
    out.push(Claim {
        id: "C10",
        figure: "Figs. 4a, 5a",
        paper: "The straight version takes an increasingly curved path as the energy grows.",
        measured: format!(
            "straight: {} rad from the eigenvector line below 25 % of E_ref, {} rad over the last 5 s",
            small(s_low),
            small(s_final)
        ),
        ..claim(judge(
            s_final > s_low,
            "farther from the line at the end than at low energy",
            "no farther from the line at the end than at low energy",
        ))
    });
    let ds = band_distance(s, 0.25, 0.95, &m14.path);
    let dc = band_distance(c, 0.25, 0.95, &m14.path);
    out.push(Claim {
        id: "C11",
        figure: "Figs. 4a, 5a",
        paper: "The curved version takes a path whose curvature is similar to the eigenmode.",
        measured: format!(
            "distance to the 14 J mode's path while 25-95 % of E_ref: curved {} rad, straight {} rad",
            small(dc),
            small(ds)
        ),
        ..claim(judge(
            dc < ds,
            "curved follows the mode's curve more closely than straight on the way up",
            "straight is as close to the mode's curve on the way up",
        ))
    });
    let between = path_distance(&final_path(s), &final_path(c));
    out.push(Claim {
        id: "C12",
        figure: "Figs. 4a, 5a",
        paper: "Both versions reach similar final trajectories.",
        measured: format!(
            "straight's last 5 s are {} rad from curved's (curved {} rad from the true mode)",
            small(between),
            small(distance(c))
        ),
        ..claim(judge(
            between < NEAR,
            &format!("within {NEAR} rad of each other"),
            &format!(
                "more than {NEAR} rad apart: straight keeps a path near the eigenvector line ({} rad from it), the optimum of its cost at 14 J, where (1 - tanh(alpha E))^2 w_xd = 33 still pulls the velocity to the line",
                small(s.line_distance)
            ),
        ))
    });
    let (ts, tc) = (
        rms_norm(&s.summary.rms_torque),
        rms_norm(&c.summary.rms_torque),
    );
    out.push(Claim {
        id: "C13",
        figure: "Figs. 4e-f, 5e-f",
        paper: "The final control action of both controllers is near zero.",
        measured: format!(
            "RMS torque norm over the last 5 s: straight {} N m, curved {} N m",
            number(ts),
            number(tc)
        ),
        verdict: if ts < SMALL_TORQUE && tc < SMALL_TORQUE {
            Verdict::Holds
        } else if ts < SMALL_TORQUE || tc < SMALL_TORQUE {
            Verdict::Partly
        } else {
            Verdict::Differs
        },
        why: format!(
            "below {SMALL_TORQUE} N m (5 % of the bound): {}",
            match (ts < SMALL_TORQUE, tc < SMALL_TORQUE) {
                (true, true) => "both",
                (false, true) => "curved only",
                (true, false) => "straight only",
                (false, false) => "neither",
            }
        ),
    });
    out.push(Claim {
        id: "C14",
        figure: "Figs. 4e-f, 5e-f",
        paper: "The curved version reaches even lower final torques.",
        measured: format!(
            "curved {} N m against straight {} N m",
            number(tc),
            number(ts)
        ),
        ..claim(judge(
            tc < ts,
            "curved's final RMS torque is the lower",
            "straight's final RMS torque is the lower",
        ))
    });
    out.push(Claim {
        id: "C15",
        figure: "Figs. 4e-f, 5e-f",
        paper: "The straight version initially applies higher torques.",
        measured: format!(
            "RMS torque norm over the first 5 s: straight {} N m, curved {} N m",
            number(s.early_torque),
            number(c.early_torque)
        ),
        ..claim(judge(
            s.early_torque > c.early_torque,
            "straight's early torque is the higher",
            "curved's early torque is as high",
        ))
    });
    out.push(Claim {
        id: "C16",
        figure: "Figs. 4b, 5b",
        paper: "The curved version takes longer to leave the low-energy region.",
        measured: format!(
            "first time at 25 % of E_ref: straight {}, curved {}",
            time(s.time_to_quarter),
            time(c.time_to_quarter)
        ),
        ..claim(judge(
            match (s.time_to_quarter, c.time_to_quarter) {
                (Some(a), Some(b)) => b > a,
                (Some(_), None) => true,
                _ => false,
            },
            "curved reaches a quarter of E_ref later",
            "curved reaches a quarter of E_ref no later than straight",
        ))
    });
    let (bs, bc) = (s.summary.time_to_5_percent, c.summary.time_to_5_percent);
    out.push(Claim {
        id: "C17",
        figure: "Figs. 4b, 5b",
        paper: "Both controllers take about the same time to reach the desired energy.",
        measured: format!(
            "in the 5 % band for good: straight {}, curved {}",
            time(bs),
            time(bc)
        ),
        verdict: Verdict::of(match (bs, bc) {
            (Some(a), Some(b)) => (a - b).abs() <= 0.25 * a.max(b),
            _ => false,
        }),
        why: match (bs, bc) {
            (Some(_), Some(_)) => "within 25 % of each other".into(),
            (None, _) => format!(
                "straight does not stay in the band: energy error {} J at the end",
                number(s.summary.final_energy_error)
            ),
            (_, None) => "curved does not stay in the band".into(),
        },
    });

    // Fig. 6: from (-1.1, 1.1).
    let s6 = runs.get("fig6-straight");
    let c6 = runs.get("fig6-curved");
    out.push(Claim {
        id: "C18",
        figure: "Fig. 6",
        paper: "From (-1.1, 1.1) rad the curved EigenMPC recovers quicker than the straight one.",
        measured: format!(
            "in the 5 % band for good: curved {}, straight {}",
            time(c6.summary.time_to_5_percent),
            time(s6.summary.time_to_5_percent)
        ),
        ..claim(judge(
            match (c6.summary.time_to_5_percent, s6.summary.time_to_5_percent) {
                (Some(a), Some(b)) => a < b,
                (Some(_), None) => true,
                _ => false,
            },
            "curved is in the band first",
            "curved is not in the band first",
        ))
    });
    out.push(Claim {
        id: "C19",
        figure: "Fig. 6",
        paper: "The straight version takes longer, but still reaches the final mode.",
        measured: format!(
            "straight: band {}, {} rad from the true mode, energy {} J at the end",
            time(s6.summary.time_to_5_percent),
            small(distance(s6)),
            number(s6.spec.e_ref + s6.summary.final_energy_error)
        ),
        verdict: Verdict::of(reached_near(s6)),
        why: if reached_near(s6) {
            format!("in the band and within {NEAR} rad of the mode")
        } else {
            "it does not end on the mode: the cost does not wrap angles, and the elbow swinging over leaves the loop near the folded pose (0, -pi), 19.6 J, where the line terms weigh (1 - tanh(1.96))^2 = 0.0016".into()
        },
    });

    // The hybrid experiment (commented out in the paper).
    for (id, family) in [("C20", Family::InPhase), ("C21", Family::AntiPhase)] {
        let h = runs.get(&format!("hybrid-{family}"));
        let cw = runs.get(&format!("curved-wrong-{family}"));
        let true_mode = &modes.get(ChartModel::Plant, family, 14.0).mode.path;
        let chart_mode = &modes.get(ChartModel::HeavierM2, family, 14.0).mode.path;
        let offset = path_distance(chart_mode, true_mode);
        let dh = distance(h);
        out.push(Claim {
            id,
            figure: "hybrid (commented out)",
            paper: "With the chart of a pendulum with m2 +20 % and alpha = 0.01, the hybrid EigenMPC brings the system to the vicinity of the actual eigenmode despite the different one in its cost.",
            measured: format!(
                "{family}, 14 J: hybrid ends {} rad from the plant's mode, curved with the same chart {} rad; the chart's own mode is {} rad from it",
                small(dh),
                small(distance(cw)),
                small(offset)
            ),
            verdict: if dh < offset && dh <= distance(cw) {
                Verdict::Holds
            } else if dh < offset {
                Verdict::Partly
            } else {
                Verdict::Differs
            },
            why: if dh < offset && dh <= distance(cw) {
                "closer to the plant's mode than its chart and than curved with the same chart".into()
            } else {
                format!(
                    "hybrid ends {} its chart's mode ({} against {} rad){}: with alpha = 0.01 the blend explores little, and beta = 0.1 (the straight variant's; the paper gives none) lowers the torque weight to (tanh(0.14) + 0.1)^2 = 0.057 of curved's, so the wrong chart is followed harder",
                    if dh < offset { "closer to the plant's mode than" } else { "farther from the plant's mode than" },
                    small(dh),
                    small(offset),
                    if distance(cw) < dh {
                        format!(", and curved alone with the same chart ends closer ({} rad)", small(distance(cw)))
                    } else {
                        String::new()
                    }
                )
            },
        });
    }

    // Computation time.
    let worst = runs
        .0
        .iter()
        .max_by(|a, b| a.mean_solve.total_cmp(&b.mean_solve))
        .expect("at least one run");
    out.push(Claim {
        id: "C22",
        figure: "section V-A",
        paper: "Among all experiments the worst average computation time was 5.3 ms (Xeon E5-1620 v2 at 3.7 GHz, MATMPC).",
        measured: format!(
            "worst mean time per sample: {} ms ({}) on {}",
            number(worst.mean_solve * 1e3),
            worst.spec.id,
            cpu_name()
        ),
        ..claim(judge(
            worst.mean_solve <= PAPER_WORST_MEAN_SOLVE,
            "at most the paper's 5.3 ms (another machine and solver: compare orders of magnitude)",
            "above the paper's 5.3 ms (another machine and solver)",
        ))
    });
    out
}

/// RMS distance to the line along `e` over the samples of `r` with
/// `lo <= E/E_ref < hi`.
fn band_line_distance(r: &RunResult, lo: f64, hi: f64, e: &Vector<2>) -> f64 {
    rms_line_distance(
        r.trace
            .iter()
            .filter(|s| s.energy >= lo * r.spec.e_ref && s.energy < hi * r.spec.e_ref)
            .map(|s| s.state.fixed_rows::<2>(0).into_owned()),
        e,
    )
}

/// The CPU's model name (Linux `/proc/cpuinfo`), or "unknown CPU".
pub fn cpu_name() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}

/// A figure written by `eigenmpc paper`: file stem and caption.
pub struct FigureEntry {
    /// File name without extension.
    pub stem: &'static str,
    /// What it shows.
    pub caption: String,
}

/// `report.md`: the set-up, every figure, every claim with its verdict and
/// the per-run table.
pub fn markdown(
    claims: &[Claim],
    runs: &Runs,
    figures: &[FigureEntry],
    extent: Extent,
    wall_seconds: f64,
    threads: usize,
) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# The paper's section V, reproduced by `eigenmpc paper`\n"
    );
    if extent == Extent::Quick {
        let _ = writeln!(
            md,
            "**Reduced run (`--quick`): every closed loop is {} s long.** The files and lines are all here; the verdicts are about these short runs, not the paper's.\n",
            number(super::QUICK_DURATION)
        );
    }
    let counts = |v: Verdict| claims.iter().filter(|c| c.verdict == v).count();
    let _ = writeln!(
        md,
        "{} claims: **{} hold**, **{} partly**, **{} differ**. Generated in {} s on {} thread(s) of {}.\n",
        claims.len(),
        counts(Verdict::Holds),
        counts(Verdict::Partly),
        counts(Verdict::Differs),
        number((wall_seconds * 10.0).round() / 10.0),
        threads,
        cpu_name()
    );
    let _ = writeln!(
        md,
        "Set-up (the paper's): point-mass double pendulum, 1 kg and 1 m per link, g = 9.81; `|tau| <= 1 N m`; N = 80 intervals of 25 ms, one real-time iteration per sample (the first solved to convergence), w_x = 50, w_xd = 2500, w_F = 225, w_E = 25 (curved) / 5 (straight), alpha = beta = 0.1 unless a run says otherwise; start at rest. Plant: adaptive Dormand-Prince (1e-10), torque held over each sample. Distances are RMS over the last 5 s to the plant's true eigenmode at E_ref (eigenmode engine, brake orbits). \"In the band\" is `|E - E_ref| < 5 %` for good. Thresholds: on the mode below {NEAR} rad, near-zero torque below {SMALL_TORQUE} N m.\n"
    );
    let _ = writeln!(md, "## Claims\n");
    let _ = writeln!(
        md,
        "| id | figure | the paper says | measured here | verdict |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|");
    for c in claims {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | **{}**: {} |",
            c.id,
            c.figure,
            c.paper,
            c.measured,
            c.verdict.word(),
            c.why
        );
    }
    let _ = writeln!(
        md,
        "\n## Figures\n\nEach is also written as SVG (`eigenmpc paper --out DIR`).\n"
    );
    for f in figures {
        let _ = writeln!(md, "**{}**\n\n![{}]({}.png)\n", f.caption, f.stem, f.stem);
    }
    let _ = writeln!(md, "## Runs\n");
    let _ = writeln!(
        md,
        "| run | variant | family | E_ref (J) | q0 (rad) | alpha | chart of | duration (s) | in the band | final E error (J) | RMS torque last 5 s (N m) | distance to the mode (rad) | distance to the line (rad) | mean solve (ms) |"
    );
    let _ = writeln!(
        md,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for r in &runs.0 {
        let s = &r.summary;
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | ({}, {}) | {} | {} | {} | {} | {} | {} / {} | {} | {} | {} |",
            r.spec.id,
            r.spec.variant,
            r.spec.family,
            number(r.spec.e_ref),
            number(r.spec.q0[0]),
            number(r.spec.q0[1]),
            number(r.spec.alpha),
            match r.spec.chart {
                ChartModel::Plant => "plant",
                ChartModel::HeavierM2 => "m2 +20 %",
            },
            number(r.trace.last().map_or(0.0, |s| s.time)),
            time(s.time_to_5_percent),
            number(s.final_energy_error),
            number(s.rms_torque[0]),
            number(s.rms_torque[1]),
            small(distance(r)),
            small(r.line_distance),
            number(r.mean_solve * 1e3)
        );
    }
    md
}
