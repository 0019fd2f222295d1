//! The stage dimensions ([`Dims`]: run-time sizes, or compile-time ones in
//! `fixed.rs`) and where each inequality sits in a stage ([`Slots`]).

/// Stage dimensions, either runtime values or compile-time constants (the
/// latter let the compiler unroll the small dense kernels).
pub(super) trait Dims: Copy {
    fn nx(self) -> usize;
    fn nu(self) -> usize;
    #[inline(always)]
    fn nv(self) -> usize {
        self.nx() + self.nu()
    }
    /// Inequality slots per stage.
    #[inline(always)]
    fn m(self) -> usize {
        2 * self.nu() + 3 * self.nx()
    }
}

#[derive(Clone, Copy)]
pub(super) struct Runtime {
    pub(super) nx: usize,
    pub(super) nu: usize,
}

impl Dims for Runtime {
    #[inline(always)]
    fn nx(self) -> usize {
        self.nx
    }
    #[inline(always)]
    fn nu(self) -> usize {
        self.nu
    }
}

/// Slot offsets inside a stage's inequality block.
#[derive(Clone, Copy)]
pub(super) struct Slots {
    pub(super) ul: usize,
    pub(super) uu: usize,
    pub(super) xl: usize,
    pub(super) xu: usize,
    pub(super) sl: usize,
}

impl Slots {
    #[inline(always)]
    pub(super) fn of<D: Dims>(d: D) -> Self {
        let (nx, nu) = (d.nx(), d.nu());
        Self {
            ul: 0,
            uu: nu,
            xl: 2 * nu,
            xu: 2 * nu + nx,
            sl: 2 * nu + 2 * nx,
        }
    }
}
