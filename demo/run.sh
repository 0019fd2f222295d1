#!/usr/bin/env bash
# The main job in one command on a fresh Debian machine: installs what the
# build needs (libclang for fmi-sys' bindgen, gcc, binutils), then builds
# both FMUs and runs the demo (the controller FMU drives the plant FMU).
# Arguments go to the demo: bash demo/run.sh --energy 8 --out-dir target/demo8
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-build-deps.sh
exec cargo run --release -p eigenmpc-demo -- "$@"
