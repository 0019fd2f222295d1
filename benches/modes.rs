//! Eigenmode engine benchmark: the whole in-phase family 0.25..16 J (13
//! energies) with degree-9 charts, as `eigenmpc modes` computes it.
//! Then the controller's creation-time work, a whole mode family with its
//! interpolation table (`ChartFamily::compute`), for 2 and 3 links.
//! Run with `cargo bench --bench modes`; prints tables.

use eigenmpc::mechanics::{DoublePendulum, MechanicalSystem, PlanarChain, Vector};
use eigenmpc::model_file::RobotFile;
use eigenmpc::modes::{
    Chart, ChartFamily, ContinuationOptions, Family, FamilyOptions, eigenmode_family, linear_modes,
};
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

fn median_ms(mut f: impl FnMut()) -> (f64, f64, f64) {
    let mut times: Vec<f64> = (0..15)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(f64::total_cmp);
    (times[times.len() / 2], times[0], times[times.len() - 1])
}

fn family_row<const N: usize, const NX: usize, S: MechanicalSystem<N>>(name: &str, sys: &S) {
    let opts = FamilyOptions::for_system(sys, &[]);
    let family = ChartFamily::<N>::compute::<S, NX>(sys, 0, &opts).expect("family");
    let (lo, hi) = family.energy_range();
    let worst = family.residuals().iter().copied().fold(0.0, f64::max);
    let (med, min, max) = median_ms(|| {
        black_box(ChartFamily::<N>::compute::<S, NX>(sys, 0, &opts).expect("family"));
    });
    println!(
        "| {name} | {N} | {lo:.3} .. {hi:.2} J | {} | {worst:.1e} | {med:.1} | {min:.1} | {max:.1} |",
        family.energies().len()
    );
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
    println!();
    println!(
        "| mode family (in-phase, degree-9 charts) | links | energy range | grid energies | worst chart residual (rad) | median ms | min ms | max ms |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    family_row::<2, 4, _>("paper double pendulum", &DoublePendulum::default());
    let robot = RobotFile::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/robots/lab-double-pendulum-A0.yml"
    ))
    .and_then(|f| f.chain::<2>())
    .expect("robot file");
    family_row::<2, 4, _>("lab pendulum A0 (rigid links, motors)", &robot);
    family_row::<3, 6, _>(
        "3-link point-mass chain (1 kg, 1 m)",
        &PlanarChain::<3>::default(),
    );
}
