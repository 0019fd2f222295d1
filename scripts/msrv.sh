#!/usr/bin/env bash
# The workspace's rust-version ([workspace.package] in Cargo.toml) is tested:
# `cargo check --workspace --all-targets --locked` with exactly that toolchain
# (installed with rustup when missing). nalgebra 0.35 (rust-version 1.89) sets
# the floor; raise rust-version here and in Cargo.toml together.
# Uses its own target dir (target/msrv, or $CARGO_TARGET_DIR/msrv): the other
# toolchain's artifacts stay out of the main build. About 12 min cold on 2
# cores, seconds when warm.
# Usage: bash scripts/msrv.sh (from anywhere).
set -euo pipefail
cd "$(dirname "$0")/.."

rust_version=$(sed -n 's/^rust-version = "\(.*\)"/\1/p' Cargo.toml | head -n 1)
case "$rust_version" in
    *.*.*) toolchain=$rust_version ;;
    *.*) toolchain=$rust_version.0 ;;
    *) echo "no rust-version in Cargo.toml's [workspace.package]" >&2; exit 1 ;;
esac
if ! rustup run "$toolchain" cargo --version >/dev/null 2>&1; then
    echo "== [${SECONDS} s] rustup toolchain install $toolchain"
    rustup toolchain install "$toolchain" --profile minimal
fi
echo "== [${SECONDS} s] cargo +$toolchain check --workspace --all-targets --locked"
CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-target}/msrv" \
    rustup run "$toolchain" cargo check --workspace --all-targets --locked
echo "== [${SECONDS} s] the workspace builds with Rust $toolchain (rust-version $rust_version)"
