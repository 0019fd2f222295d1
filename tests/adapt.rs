//! Online adaptation (src/adapt.rs) on the robustness issue's plant: m2
//! +20 %, l1 +10 %, damping 0.05 N m s on both joints, none of it in the
//! controller's model. With adaptation the plant's energy settles at 14 J,
//! the torque is what the damping takes and the orbit is the plant's mode;
//! without it the energy ends far off. The sample path allocates nothing.

use eigenmpc::adapt::{AdaptOptions, Adaptation};
use eigenmpc::mechanics::{PlanarChain, PlanarChainParams, Vector};
use eigenmpc::modes::{ChartFamily, FamilyOptions};
use eigenmpc::mpc::closed_loop::{Sample, distance_to_path, mode_and_chart};
use eigenmpc::mpc::{Controller, MpcConfig, Variant};
use eigenmpc::robustness::{Imperfections, run_imperfect};
use nalgebra::SVector;

struct Outcome {
    mean_energy: f64,
    rms_torque: [f64; 2],
    rms_damping: [f64; 2],
    rms_distance: f64,
    model_updates: usize,
}

fn plant_params() -> PlanarChainParams<2> {
    let mut p = PlanarChainParams::<2>::point_masses([1.0, 1.2], [1.1, 1.0], 9.81);
    p.joints[0].viscous = 0.05;
    p.joints[1].viscous = 0.05;
    p
}

/// The paper's pendulum as the model, curved on its family at 14 J, and
/// its adaptation.
fn controller_and_adaptation(
    horizon: usize,
    options: AdaptOptions,
) -> (Controller<PlanarChain<2>, 2, 4>, Adaptation<2, 4, 11>) {
    let prior = PlanarChainParams::<2>::default();
    let model = PlanarChain::new(prior).unwrap();
    let family =
        ChartFamily::compute::<_, 4>(&model, 0, &FamilyOptions::for_system(&model, &[14.0]))
            .unwrap();
    let mut config = MpcConfig::paper(Variant::Curved);
    config.horizon = horizon;
    let ctrl = Controller::<_, 2, 4>::with_family(model, config, family).unwrap();
    (ctrl, Adaptation::new(&prior, options).unwrap())
}

fn closed_loop(adapt: bool, seconds: f64) -> Outcome {
    let plant = PlanarChain::new(plant_params()).unwrap();
    let (mut ctrl, mut adaptation) = controller_and_adaptation(
        80,
        AdaptOptions {
            synchronous: true,
            ..AdaptOptions::default()
        },
    );
    let run = run_imperfect(
        &mut ctrl,
        adapt.then_some(&mut adaptation),
        &plant,
        &SVector::<f64, 4>::new(0.05, 0.05, 0.0, 0.0),
        seconds,
        &Imperfections::default(),
    )
    .unwrap();
    let tail = &run.samples[run.samples.len() - 200..];
    let (mode, _) = mode_and_chart::<_, 2, 4>(&plant, 0, 14.0, 9).unwrap();
    let n = tail.len() as f64;
    let rms = |f: &dyn Fn(&Sample<2, 4>) -> f64| {
        (tail.iter().map(|s| f(s).powi(2)).sum::<f64>() / n).sqrt()
    };
    let q = |s: &Sample<2, 4>| Vector::<2>::new(s.state[0], s.state[1]);
    Outcome {
        mean_energy: tail.iter().map(|s| s.energy).sum::<f64>() / n,
        rms_torque: [rms(&|s| s.tau[0]), rms(&|s| s.tau[1])],
        rms_damping: [rms(&|s| 0.05 * s.state[2]), rms(&|s| 0.05 * s.state[3])],
        rms_distance: rms(&|s| distance_to_path(&q(s), &mode.path)),
        model_updates: run.model_updates,
    }
}

#[test]
fn adaptation_finds_the_plants_mode_and_energy() {
    let on = closed_loop(true, 90.0);
    eprintln!(
        "adapt on: E {:.4} J, tau {:?}, damping {:?}, distance {:.4}, {} models",
        on.mean_energy, on.rms_torque, on.rms_damping, on.rms_distance, on.model_updates
    );
    assert!((on.mean_energy - 14.0).abs() < 0.01 * 14.0);
    for j in 0..2 {
        assert!(on.rms_torque[j] <= on.rms_damping[j] + 0.02, "joint {j}");
    }
    assert!(on.rms_distance < 0.01);
    assert!(on.model_updates > 0);
    let off = closed_loop(false, 90.0);
    eprintln!(
        "adapt off: E {:.4} J, distance {:.4}",
        off.mean_energy, off.rms_distance
    );
    assert!(
        (off.mean_energy - 14.0).abs() > 0.1 * 14.0,
        "the test can fail"
    );
}

mod counting {
    use std::alloc::{GlobalAlloc, Layout, System};
    use std::cell::Cell;

    thread_local! {
        /// Allocations of this thread while counting is on (the worker
        /// thread's own allocations are not the sample path's).
        pub static COUNT: Cell<Option<usize>> = const { Cell::new(None) };
    }

    pub struct Counting;

    fn count() {
        let _ = COUNT.try_with(|c| {
            if let Some(n) = c.get() {
                c.set(Some(n + 1));
            }
        });
    }

    unsafe impl GlobalAlloc for Counting {
        unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
            count();
            unsafe { System.alloc(layout) }
        }
        unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
            unsafe { System.dealloc(ptr, layout) }
        }
        unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
            count();
            unsafe { System.realloc(ptr, layout, new_size) }
        }
    }
}

#[global_allocator]
static ALLOCATOR: counting::Counting = counting::Counting;

/// The sample path (identification, posting a request, swapping a model in,
/// the controller's step) allocates nothing on the sample thread; the
/// worker computes the families.
#[test]
fn the_sample_path_does_not_allocate() {
    let plant = PlanarChain::new(plant_params()).unwrap();
    let (mut ctrl, mut adaptation) = controller_and_adaptation(
        40,
        AdaptOptions {
            period: 10,
            ..AdaptOptions::default()
        },
    );
    let dt = ctrl.config().dt;
    let mut z = SVector::<f64, 4>::new(0.3, 0.2, 0.0, 0.0);
    let mut tau = ctrl.step(&z).tau;
    counting::COUNT.with(|c| c.set(Some(0)));
    for _ in 0..2000 {
        let (q, qd) = (Vector::<2>::new(z[0], z[1]), Vector::<2>::new(z[2], z[3]));
        adaptation.sample(&mut ctrl, &q, &qd, &tau, dt);
        tau = ctrl.step(&z).tau;
        z = eigenmpc::integrate::rk4_step::<_, 2, 4>(&plant, &z, &tau, dt);
        // the worker gets time to compute (as it would in real time)
        std::thread::sleep(std::time::Duration::from_micros(100));
    }
    let allocations = counting::COUNT.with(|c| c.replace(None)).unwrap();
    assert!(adaptation.model_updates() > 0, "a model was swapped in");
    assert_eq!(allocations, 0);
}
