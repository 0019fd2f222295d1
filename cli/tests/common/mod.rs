//! Helpers shared by the CLI's integration tests.

use std::process::{Command, Output};

/// Runs the `eigenmpc` binary with `args`.
pub fn eigenmpc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_eigenmpc"))
        .args(args)
        .output()
        .expect("run eigenmpc")
}

/// Runs `eigenmpc` with `args`, requires success and returns its stdout.
#[allow(dead_code)] // not every test binary uses it
pub fn eigenmpc_ok(args: &[&str]) -> String {
    let out = eigenmpc(args);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "eigenmpc {args:?}: {stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}
