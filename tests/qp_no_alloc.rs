//! The Riccati QP solver does not allocate after creation: a counting global
//! allocator (per test binary, so this file holds only this check) counts
//! the allocations made by the solving thread.

use eigenmpc::qp::synthetic::{PendulumQpOptions, SplitMix64, pendulum_rti_qp, random_ocp_qp};
use eigenmpc::qp::{QpSolution, QpSolver, QpStatus, RiccatiSettings, RiccatiSolver};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    // Only the thread under test counts (the test harness allocates on its own).
    static COUNTING: Cell<bool> = const { Cell::new(false) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.with(Cell::get) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNTING.with(Cell::get) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made by `f` on this thread.
fn allocations_in(f: impl FnOnce()) -> usize {
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    COUNTING.with(|c| c.set(true));
    f();
    COUNTING.with(|c| c.set(false));
    ALLOCATIONS.load(Ordering::Relaxed) - before
}

#[test]
fn solve_does_not_allocate() {
    // The counter works.
    assert!(allocations_in(|| drop(std::hint::black_box(vec![1.0f64; 8]))) >= 1);

    let mut rng = SplitMix64::new(21);
    let n = 80;
    let mut qps: Vec<_> = (0..6)
        .map(|i| {
            let opts = PendulumQpOptions {
                tau_max: if i % 2 == 0 { 1.0 } else { 0.2 },
                velocity_bound: if i < 3 { 6.0 } else { f64::INFINITY },
                ..Default::default()
            };
            pendulum_rti_qp(&mut rng, &opts)
        })
        .collect();
    // Unconstrained, degenerate bounds, and bad data take other code paths.
    qps.push(random_ocp_qp(&mut rng, 4, 2, n));
    let mut degenerate = qps[0].clone();
    degenerate.u_upper[3] = degenerate.u_lower[3].clone();
    qps.push(degenerate);
    let mut bad = qps[1].clone();
    bad.a[5][(0, 0)] = f64::NAN;
    qps.push(bad);

    let mut solver = RiccatiSolver::new(4, 2, n, RiccatiSettings::default());
    let mut sol = QpSolution::new(4, 2, n);
    let mut statuses = Vec::with_capacity(qps.len());
    let count = allocations_in(|| {
        for qp in &qps {
            statuses.push(solver.solve(qp, &mut sol));
        }
    });
    assert_eq!(count, 0, "solve allocated {count} times");
    assert_eq!(statuses.len(), qps.len());
    assert!(
        statuses[..qps.len() - 1]
            .iter()
            .all(|s| *s == QpStatus::Solved),
        "{statuses:?}"
    );
    assert_eq!(statuses[qps.len() - 1], QpStatus::InvalidInput);
}
