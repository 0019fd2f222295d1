#!/usr/bin/env bash
# The project's test command (README "Run the tests"): formatting, lints,
# Rust tests. Installs what a fresh Debian machine lacks.
set -euo pipefail
cd "$(dirname "$0")/.."

echo "== cargo fmt --check"
cargo fmt --all -- --check
echo "== cargo clippy"
cargo clippy --workspace --all-targets -- -D warnings
echo "== cargo test"
cargo test --workspace
