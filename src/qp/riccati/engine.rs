//! Which core runs a solve: the compile-time-sized cores of the joint-count
//! table (`fixed.rs`) or the run-time-sized one (`ipm.rs`).

use super::*;

/// The core for the solver's dimensions: compile-time-sized for the chains
/// of the joint-count table (`nx = 2 nu`, `nu` = 1 .. 6, see
/// [`crate::joints`]), runtime-sized otherwise.
#[derive(Debug)]
pub(super) enum Engine {
    Runtime(Box<Workspace>),
    Fixed(Box<dyn FixedEngine>),
}

impl Clone for Engine {
    fn clone(&self) -> Self {
        match self {
            Engine::Runtime(ws) => Engine::Runtime(ws.clone()),
            Engine::Fixed(core) => Engine::Fixed(core.boxed_clone()),
        }
    }
}

impl Engine {
    pub(super) fn new(nx: usize, nu: usize, horizon: usize) -> Self {
        let runtime = || Engine::Runtime(Box::new(Workspace::new(nx, nu, horizon)));
        crate::with_joint_count!(
            nu,
            |N, S, NP| if nx == S {
                // Slots per stage: 2 nu input bounds, 3 nx state rows.
                Engine::Fixed(Box::new(FixedCore::<S, N, { 2 * N + 3 * S }>::new(
                    horizon,
                )))
            } else {
                runtime()
            },
            otherwise runtime()
        )
    }
}

/// A compile-time-sized core behind one interface (one virtual call per
/// solve), so that its sizes come from the joint-count table.
pub(super) trait FixedEngine: std::fmt::Debug + Send + Sync {
    fn run(
        &mut self,
        qp: &OcpQp,
        set: &RiccatiSettings,
        warm: bool,
        sol: &mut QpSolution,
    ) -> (QpStatus, RiccatiInfo);
    /// [`FixedEngine::run`] on the stage-wise form, when `qp` is a
    /// [`StageQp`] of this core's sizes (`None` otherwise: the caller
    /// converts it).
    fn run_stages(
        &mut self,
        qp: &dyn std::any::Any,
        set: &RiccatiSettings,
        warm: bool,
        sol: &mut QpSolution,
    ) -> Option<(QpStatus, RiccatiInfo)>;
    fn save_multipliers(&self, out: &mut Vec<f64>);
    fn restore_multipliers(&mut self, data: &[f64]) -> bool;
    fn boxed_clone(&self) -> Box<dyn FixedEngine>;
}

impl<const NX: usize, const NU: usize, const M: usize> FixedEngine for FixedCore<NX, NU, M> {
    fn run(
        &mut self,
        qp: &OcpQp,
        set: &RiccatiSettings,
        warm: bool,
        sol: &mut QpSolution,
    ) -> (QpStatus, RiccatiInfo) {
        let loaded = self.load(qp, set);
        run_fixed(self, loaded, set, warm, sol)
    }
    fn run_stages(
        &mut self,
        qp: &dyn std::any::Any,
        set: &RiccatiSettings,
        warm: bool,
        sol: &mut QpSolution,
    ) -> Option<(QpStatus, RiccatiInfo)> {
        let qp = qp.downcast_ref::<StageQp<NX, NU>>()?;
        let loaded = self.load_stages(qp, set);
        Some(run_fixed(self, loaded, set, warm, sol))
    }
    fn save_multipliers(&self, out: &mut Vec<f64>) {
        FixedCore::save_multipliers(self, out);
    }
    fn restore_multipliers(&mut self, data: &[f64]) -> bool {
        FixedCore::restore_multipliers(self, data)
    }
    fn boxed_clone(&self) -> Box<dyn FixedEngine> {
        Box::new(self.clone())
    }
}

/// One solve on a compile-time-sized core after its load (`loaded`: the
/// data passed the load's checks): the active-set start when it applies,
/// the interior point otherwise.
fn run_fixed<const NX: usize, const NU: usize, const M: usize>(
    core: &mut FixedCore<NX, NU, M>,
    loaded: bool,
    set: &RiccatiSettings,
    warm: bool,
    sol: &mut QpSolution,
) -> (QpStatus, RiccatiInfo) {
    if !loaded {
        return (QpStatus::InvalidInput, core.info);
    }
    core.warm = warm;
    let status = match core.solve_active_set(sol) {
        Some(status) => status,
        None => interior_point(core, set, warm, sol),
    };
    (status, core.info)
}
