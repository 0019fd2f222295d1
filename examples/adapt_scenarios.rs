//! The online adaptation against the set-ups of issue 19: noisy and
//! delayed sensors on an exact model, lighter and heavier plants, and the
//! laboratory pendulums of `robots/` given a rough model. Per row: the
//! plant's final energy error (mean over the last 5 s), the RMS torque over
//! the last 5 s and the friction torque along that orbit, with adaptation
//! off and on, and what the adaptation did.
//!
//! `cargo run --release --example adapt_scenarios [-- ROW]`

use eigenmpc::adapt::{AdaptOptions, Adaptation};
use eigenmpc::identify::RlsOptions;
use eigenmpc::mechanics::{PlanarChain, PlanarChainParams};
use eigenmpc::model_file::RobotFile;
use eigenmpc::modes::{ChartFamily, FamilyOptions};
use eigenmpc::mpc::closed_loop::{energy_tail, rms_friction_torque};
use eigenmpc::mpc::{Controller, EstimatorConfig, MpcConfig, Variant, prediction_substeps};
use eigenmpc::robustness::{Imperfections, run_imperfect};
use nalgebra::SVector;

struct Row {
    name: &'static str,
    model: PlanarChainParams<2>,
    plant: PlanarChainParams<2>,
    e_ref: f64,
    tau_max: f64,
    duration: f64,
    imperfections: Imperfections,
    ekf: bool,
    z0: [f64; 4],
}

fn paper() -> PlanarChainParams<2> {
    PlanarChainParams::default()
}

/// A rough model of a laboratory robot: masses, centres of mass and
/// inertias 10-20 % off, no friction.
fn rough(robot: &PlanarChainParams<2>) -> PlanarChainParams<2> {
    let mut p = *robot;
    let f = [[1.15, 0.88, 1.2], [0.85, 1.12, 0.9]];
    for ((link, joint), f) in p.links.iter_mut().zip(&mut p.joints).zip(f) {
        link.mass *= f[0];
        link.com *= f[1];
        link.inertia *= f[2];
        joint.viscous = 0.0;
        joint.coulomb = 0.0;
    }
    p
}

fn rows() -> Vec<Row> {
    let base = |name, plant, e_ref: f64| Row {
        name,
        model: paper(),
        plant,
        e_ref,
        tau_max: 1.0,
        duration: 60.0,
        imperfections: Imperfections::default(),
        ekf: false,
        z0: [0.05, 0.05, 0.0, 0.0],
    };
    let noise = |s| Imperfections {
        measurement_noise: s,
        ..Imperfections::default()
    };
    let mut m2_light = paper();
    m2_light.links[1].mass *= 0.8;
    let mut m1_light = paper();
    m1_light.links[0].mass *= 0.75;
    let mut l1_short = paper();
    l1_short.links[0].length *= 0.92;
    l1_short.links[0].com *= 0.92;
    let mut combined = paper();
    combined.links[1].mass *= 1.25;
    combined.links[0].length *= 0.92;
    combined.links[0].com *= 0.92;
    combined.joints[0].viscous = 0.03;
    combined.joints[1].viscous = 0.03;
    let lab = |file: &str| -> PlanarChainParams<2> {
        RobotFile::load(format!("robots/{file}"))
            .unwrap()
            .params::<2>()
            .unwrap()
    };
    let lab_row = |name, robot: PlanarChainParams<2>, noisy: bool| Row {
        name,
        model: rough(&robot),
        plant: robot,
        e_ref: 2.0,
        tau_max: 0.5,
        duration: 60.0,
        imperfections: if noisy {
            noise(0.01)
        } else {
            Imperfections::default()
        },
        ekf: noisy,
        z0: [0.05, 0.05, 0.0, 0.0],
    };
    vec![
        base("exact", paper(), 14.0),
        Row {
            imperfections: noise(0.01),
            ..base("exact, noise 0.01", paper(), 14.0)
        },
        Row {
            imperfections: noise(0.01),
            ekf: true,
            ..base("exact, noise 0.01, EKF", paper(), 14.0)
        },
        Row {
            imperfections: noise(0.03),
            ..base("exact, noise 0.03, 10 J", paper(), 10.0)
        },
        Row {
            imperfections: noise(0.03),
            ekf: true,
            ..base("exact, noise 0.03, EKF, 10 J", paper(), 10.0)
        },
        Row {
            imperfections: Imperfections {
                delay_samples: 4,
                ..Imperfections::default()
            },
            ..base("exact, delay 4", paper(), 14.0)
        },
        base("m2 -20 %", m2_light, 14.0),
        base("m1 -25 %", m1_light, 14.0),
        // The controller's own limit there: its degree-9 chart of this
        // robot's mode at 14 J.
        Row {
            model: m1_light,
            ..base("m1 -25 %, exact model", m1_light, 14.0)
        },
        base("l1 -8 %, 10 J", l1_short, 10.0),
        {
            let mut p = paper();
            p.links[0].mass *= 0.975;
            base("m1 -2.5 %", p, 14.0)
        },
        {
            let mut p = paper();
            p.links[0].mass *= 1.025;
            base("m1 +2.5 %", p, 14.0)
        },
        Row {
            duration: 90.0,
            ..base("m2 +25 %, l1 -8 %, b 0.03, 10 J", combined, 10.0)
        },
        base("E_ref 3 J", paper(), 3.0),
        lab_row(
            "lab A0, rough model",
            lab("lab-double-pendulum-A0.yml"),
            false,
        ),
        lab_row(
            "lab A0, rough, noise",
            lab("lab-double-pendulum-A0.yml"),
            true,
        ),
        lab_row(
            "lab B0, rough model",
            lab("lab-double-pendulum-B0.yml"),
            false,
        ),
        lab_row(
            "lab B0, rough, noise",
            lab("lab-double-pendulum-B0.yml"),
            true,
        ),
    ]
}

fn run(row: &Row, adapt: bool) -> String {
    let model = PlanarChain::new(row.model).unwrap();
    let plant = PlanarChain::new(row.plant).unwrap();
    let mut options = FamilyOptions::for_system(&model, &[row.e_ref]);
    options.degree = 9;
    let family = ChartFamily::compute::<_, 4>(&model, 0, &options).unwrap();
    let mut config = MpcConfig::paper(Variant::Curved);
    config.cost.e_ref = row.e_ref;
    config.tau_max = row.tau_max;
    config.substeps = prediction_substeps(&model, config.dt);
    if row.ekf {
        // The EKF told the sensors' noise.
        let noise = row.imperfections.measurement_noise.max(0.005);
        config.estimator = Some(EstimatorConfig {
            angle_noise: noise,
            speed_noise: noise,
            acceleration_noise: 1.0,
        });
    }
    // The identification is told the noise the EKF is told, as in the FMU.
    let rls = match &config.estimator {
        Some(e) => RlsOptions {
            angle_noise: e.angle_noise,
            speed_noise: e.speed_noise,
            ..RlsOptions::default()
        },
        None => RlsOptions::default(),
    };
    let mut controller = Controller::<_, 2, 4>::with_family(model, config, family).unwrap();
    let mut adaptation = Adaptation::<2, 4, 11>::new(
        &row.model,
        AdaptOptions {
            synchronous: true,
            rls,
            ..AdaptOptions::default()
        },
    )
    .unwrap();
    let z0 = SVector::<f64, 4>::from(row.z0);
    let out = run_imperfect(
        &mut controller,
        adapt.then_some(&mut adaptation),
        &plant,
        &z0,
        row.duration,
        &row.imperfections,
    )
    .unwrap();
    let (mean, _) = energy_tail(&out.samples, row.e_ref, 5.0);
    let t_end = out.samples.last().unwrap().time;
    let tail: Vec<_> = out
        .samples
        .iter()
        .filter(|s| s.time > t_end - 5.0 + 1e-9)
        .collect();
    let rms =
        |j: usize| (tail.iter().map(|s| s.tau[j].powi(2)).sum::<f64>() / tail.len() as f64).sqrt();
    let friction = rms_friction_torque(&out.samples, &plant, 5.0);
    let mut text = format!(
        "{:+7.2} %  tau {:.3} / {:.3}  friction {:.3} / {:.3}",
        100.0 * (mean - row.e_ref) / row.e_ref,
        rms(0),
        rms(1),
        friction[0],
        friction[1]
    );
    if adapt {
        text += &format!("  models {}", out.model_updates);
        let id = adaptation.identification();
        text += &format!(
            "  refused {:?} reverts {} {:?} noise {:.4?} scale sd {:.3}\n      in use {:.3?}\n      estimate {:.3?}",
            adaptation.refusals(),
            adaptation.reverts(),
            adaptation.status(),
            id.noise(),
            id.scale_uncertainty(),
            adaptation.in_use().theta.as_slice(),
            id.estimate().theta.as_slice()
        );
    }
    text
}

fn main() {
    let only: Option<String> = std::env::args().nth(1);
    let duration: Option<f64> = std::env::var("DURATION").ok().and_then(|d| d.parse().ok());
    for mut row in rows() {
        if let Some(d) = duration {
            row.duration = d;
        }
        if only.as_deref().is_some_and(|o| !row.name.contains(o)) {
            continue;
        }
        println!("{}", row.name);
        println!("  off: {}", run(&row, false));
        println!("  on:  {}", run(&row, true));
    }
}
