#!/usr/bin/env bash
# The crates.io packaging check of the publishable library crates (issue 36):
# - refuses a cargo older than the workspace's rust-version (the toolchain that
#   runs this and tests/run.sh is the tested one; scripts/msrv.sh checks the
#   rust-version itself with that toolchain);
# - checks that the publishable crates are exactly those listed here (a new
#   member is either added here or marked `publish = false`);
# - `cargo package` of all of them in one invocation WITH verification: each
#   .crate is unpacked and built on its own, the crates depending on each
#   other through cargo's local overlay registry (cargo >= 1.90).
# Uses the normal target dir (or CARGO_TARGET_DIR), so it reuses the build;
# --allow-dirty: it checks the packaging, not the git state.
# Usage: bash scripts/package.sh (from anywhere).
set -euo pipefail
cd "$(dirname "$0")/.."

# The library crates for users; cli, demo, fmu-build, controller-fmu (the C
# library) and robot-fmu (the exported FMUs' binary) are `publish = false`.
crates=(eigenmpc fmu-core fmi2-slave fmi3-slave eigenmpc-fmu-models)

version_key() { awk -F. '{ printf "%04d%04d%04d\n", $1, $2, ($3 == "" ? 0 : $3) }'; }
rust_version=$(sed -n 's/^rust-version = "\(.*\)"/\1/p' Cargo.toml | head -n 1)
cargo_version=$(cargo --version | awk '{print $2}' | sed 's/-.*//')
if [ -z "$rust_version" ]; then
    echo "no rust-version in Cargo.toml's [workspace.package]" >&2
    exit 1
fi
if [ "$(echo "$cargo_version" | version_key)" \< "$(echo "$rust_version" | version_key)" ]; then
    echo "cargo $cargo_version is older than the workspace's rust-version $rust_version" >&2
    exit 1
fi
# The overlay registry that packages interdependent crates together.
if [ "$(echo "$cargo_version" | version_key)" \< "$(echo 1.90 | version_key)" ]; then
    echo "cargo $cargo_version: packaging the workspace's crates together needs cargo >= 1.90" >&2
    exit 1
fi
echo "== [${SECONDS} s] cargo $cargo_version (rust-version $rust_version)"

publishable=$(cargo metadata --no-deps --format-version 1 | python3 -c '
import json, sys
m = json.load(sys.stdin)
print(" ".join(sorted(p["name"] for p in m["packages"] if p["publish"] != [])))')
expected=$(printf '%s\n' "${crates[@]}" | sort | tr '\n' ' ' | sed 's/ $//')
if [ "$publishable" != "$expected" ]; then
    echo "publishable crates: $publishable; scripts/package.sh packages: $expected" >&2
    echo "(add the crate here or give it publish = false)" >&2
    exit 1
fi

# Cargo unpacks the overlay registry's crates into
# $CARGO_HOME/registry/src/<hash of the registry's path>/<crate>-<version> and
# never again while that directory exists: a second run from the same
# checkout path verified against the first run's sources (measured: a field
# added to eigenmpc was missing when eigenmpc-fmu-models was verified). Drop
# those copies of the workspace's own crates first.
version=$(sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -n 1)
for c in "${crates[@]}"; do
    rm -rf "${CARGO_HOME:-$HOME/.cargo}"/registry/src/*/"$c-$version"
done

echo "== [${SECONDS} s] cargo package ${crates[*]} (each verified from its .crate)"
args=()
for c in "${crates[@]}"; do args+=(-p "$c"); done
cargo package --allow-dirty "${args[@]}"
echo "== [${SECONDS} s] packaged: ${CARGO_TARGET_DIR:-target}/package/*.crate"
