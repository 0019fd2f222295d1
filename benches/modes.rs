//! Eigenmode engine benchmark: the whole in-phase family 0.25..16 J (13
//! energies) with degree-9 charts, as `eigenmpc modes` computes it.
//! Run with `cargo bench --bench modes`; prints a table.

use eigenmpc::mechanics::{DoublePendulum, Vector};
use eigenmpc::modes::{Chart, ContinuationOptions, Family, eigenmode_family, linear_modes};
use std::hint::black_box;
use std::time::Instant;

const ENERGIES: [f64; 13] = [
    0.25, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 10.0, 12.0, 14.0, 16.0,
];

fn family_with_charts(family: Family) -> usize {
    let sys = DoublePendulum::default();
    let c = linear_modes(&sys).expect("stable")[family.index()].eigenvector;
    let modes = eigenmode_family::<_, 2, 4>(
        &sys,
        family.index(),
        &ENERGIES,
        &ContinuationOptions::default(),
    )
    .expect("family");
    modes
        .iter()
        .map(|m| {
            Chart::fit(&m.path, &c, &Vector::<2>::zeros(), 9)
                .expect("chart")
                .degree
        })
        .sum()
}

fn main() {
    println!(
        "| family (13 energies 0.25..16 J, charts deg 9) | runs | median ms | min ms | max ms |"
    );
    println!("|---|---|---|---|---|");
    for family in [Family::InPhase, Family::AntiPhase] {
        let mut times: Vec<f64> = (0..21)
            .map(|_| {
                let t = Instant::now();
                black_box(family_with_charts(family));
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        times.sort_by(f64::total_cmp);
        println!(
            "| {family} | {} | {:.1} | {:.1} | {:.1} |",
            times.len(),
            times[times.len() / 2],
            times[0],
            times[times.len() - 1]
        );
    }
}
