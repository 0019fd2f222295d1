#!/usr/bin/env bash
# Regenerates fmi2-slave's checked-in FMI 2.0 bindings (src/ffi/types.rs and
# src/ffi/loader.rs) from the standard headers with bindgen's command-line
# tool, with the options the build script used to pass. The headers are
# frozen: run it only if fmi-standard2/headers changes. Needs libclang
# (Debian libclang-dev) and `cargo install bindgen-cli` (0.72).
set -euo pipefail
cd "$(dirname "$0")/../fmi2-slave"
out=$(mktemp)
bindgen fmi-standard2/headers/fmi2Functions.h \
    --allowlist-item 'fmi2.*' \
    --wrap-unsafe-ops \
    --dynamic-loading Fmi2Binding \
    --output "$out"
split=$(grep -n '^pub struct Fmi2Binding' "$out" | cut -d: -f1)
{
    sed -n '1,5p' src/ffi/types.rs
    echo
    head -n "$((split - 1))" "$out"
} >src/ffi/types.rs.new
{
    sed -n '1,3p' src/ffi/loader.rs
    echo
    tail -n "+$split" "$out"
} >src/ffi/loader.rs.new
mv src/ffi/types.rs.new src/ffi/types.rs
mv src/ffi/loader.rs.new src/ffi/loader.rs
rm -f "$out"
echo "wrote fmi2-slave/src/ffi/types.rs and loader.rs"
