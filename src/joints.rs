//! The joint counts compiled to fixed sizes: the one place that lists them.
//!
//! Every size of an `N`-joint planar chain follows from `N`: the state has
//! `S = 2 N` entries ([`state_size`]) and the identification
//! `NP = base_parameter_count(N)` base parameters. Stable Rust cannot compute
//! `2 N` inside a const generic, so code generic over the chain takes `N`,
//! `S` and `NP` as three parameters; [`crate::with_joint_count!`] binds all three,
//! computed, for a count known only at run time (a robot file, a C config,
//! an FMU's resources).
//!
//! **Adding a joint count is one number** in [`crate::joint_count_table!`]: every
//! dispatch (the CLI, the C API, the FMUs, the demo, the robot-file limit)
//! follows from it.

/// Calls `$callback!($args ; 1 2 3 4 5 6)` with the supported joint counts:
/// the table every dispatch is generated from. Add a count here.
#[macro_export]
#[doc(hidden)]
macro_rules! joint_count_table {
    ($callback:ident ! ( $($args:tt)* )) => {
        $crate::$callback!($($args)* ; 1 2 3 4 5 6)
    };
}

/// Runs `$body` with `N`, `S = 2 N` and `NP = base_parameter_count(N)`
/// (and, named as a fourth, `NA = S + NP`) bound as constants for the
/// joint count `$n` (a `usize` known at run time), or evaluates
/// `$otherwise` when `$n` is not a supported count.
///
/// ```
/// use eigenmpc::with_joint_count;
/// fn state_len<const N: usize, const S: usize>() -> usize {
///     S
/// }
/// let n = 4;
/// let s = with_joint_count!(n, |N, S, NP| Some(state_len::<N, S>()), otherwise None);
/// assert_eq!(s, Some(8));
/// let none = with_joint_count!(9, |N, S, NP| Some(N), otherwise None);
/// assert_eq!(none, None);
/// ```
#[macro_export]
macro_rules! with_joint_count {
    ($n:expr, |$N:ident, $S:ident, $NP:ident| $body:expr, otherwise $otherwise:expr) => {
        $crate::joint_count_table!(__with_joint_count_match!(
            $n,
            $N,
            $S,
            $NP,
            __EIGENMPC_AUGMENTED,
            $body,
            $otherwise
        ))
    };
    // With `NA = S + NP` too: the size of the state and the parameters
    // estimated together ([`crate::state_parameter_ekf`]).
    ($n:expr, |$N:ident, $S:ident, $NP:ident, $NA:ident| $body:expr, otherwise $otherwise:expr) => {
        $crate::joint_count_table!(__with_joint_count_match!(
            $n, $N, $S, $NP, $NA, $body, $otherwise
        ))
    };
}

#[macro_export]
#[doc(hidden)]
macro_rules! __with_joint_count_match {
    ($n:expr, $N:ident, $S:ident, $NP:ident, $NA:ident, $body:expr, $otherwise:expr ; $($k:literal)*) => {
        match $n {
            $(
                $k => {
                    #[allow(dead_code)]
                    const $N: usize = $k;
                    #[allow(dead_code)]
                    const $S: usize = 2 * $k;
                    #[allow(dead_code)]
                    const $NP: usize = $crate::identify::base_parameter_count($k);
                    #[allow(dead_code)]
                    const $NA: usize = 2 * $k + $crate::identify::base_parameter_count($k);
                    $body
                }
            )*
            _ => $otherwise,
        }
    };
}

#[macro_export]
#[doc(hidden)]
macro_rules! __joint_count_list {
    ( ; $($k:literal)*) => {
        [$($k),*]
    };
}

/// The joint counts compiled to fixed sizes, ascending.
pub const JOINT_COUNTS: &[usize] = &joint_count_table!(__joint_count_list!());

/// The most joints a chain may have.
pub const MAX_JOINTS: usize = JOINT_COUNTS[JOINT_COUNTS.len() - 1];

/// Size of the state `(q, qd)` of an `n`-joint chain.
pub const fn state_size(n: usize) -> usize {
    2 * n
}

/// Whether `n` joints are supported.
pub fn is_supported(n: usize) -> bool {
    JOINT_COUNTS.contains(&n)
}

/// The error for a joint count outside the table, naming what is supported.
pub fn unsupported(n: usize) -> String {
    format!(
        "{n} joints are not supported: a chain has {} to {MAX_JOINTS} joints",
        JOINT_COUNTS[0]
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::base_parameter_count;

    fn sizes<const N: usize, const S: usize, const NP: usize>() -> (usize, usize, usize) {
        (N, S, NP)
    }

    #[test]
    fn every_count_binds_its_derived_sizes() {
        for &n in JOINT_COUNTS {
            let got = with_joint_count!(n, |N, S, NP| Some(sizes::<N, S, NP>()), otherwise None);
            assert_eq!(got, Some((n, state_size(n), base_parameter_count(n))));
            let augmented = with_joint_count!(n, |N, S, NP, NA| Some(NA), otherwise None);
            assert_eq!(augmented, Some(state_size(n) + base_parameter_count(n)));
        }
        assert_eq!(base_parameter_count(2), 11);
        assert_eq!(base_parameter_count(3), 18);
    }

    #[test]
    fn unknown_counts_take_the_fallback() {
        for n in [0, MAX_JOINTS + 1, 100] {
            assert!(!is_supported(n));
            assert_eq!(
                with_joint_count!(n, |N, S, NP| Ok(N), otherwise Err(unsupported(n))),
                Err(unsupported(n))
            );
        }
        assert!(unsupported(7).contains("1 to 6"));
    }
}
