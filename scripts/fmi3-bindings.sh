#!/usr/bin/env bash
# Regenerates fmi3-slave's checked-in FMI 3.0 bindings (src/ffi/types.rs)
# from the standard headers with bindgen's command-line tool: the C types,
# constants and function typedefs (`fmi3DoStepTYPE`, ...), no function
# declarations (the FMU defines those, with export_fmi3!). The headers are
# frozen: run it only if fmi-standard3/headers changes. Needs libclang
# (Debian libclang-dev) and `cargo install bindgen-cli` (0.72).
set -euo pipefail
cd "$(dirname "$0")/../fmi3-slave"
out=$(mktemp)
bindgen fmi-standard3/headers/fmi3Functions.h \
    --allowlist-type 'fmi3.*' \
    --allowlist-var 'fmi3.*' \
    --wrap-unsafe-ops \
    --output "$out"
{
    cat <<'HEADER'
// FMI 3.0 C types, constants and function typedefs: bindgen 0.72 output of
// fmi-standard3/headers/fmi3Functions.h (2-clause BSD, Modelica Association),
// checked in so that building an FMU needs neither bindgen nor libclang (and
// cross builds see the same types). The headers are frozen; regenerate with
// scripts/fmi3-bindings.sh if they ever change.
HEADER
    echo
    cat "$out"
} >src/ffi/types.rs.new
mv src/ffi/types.rs.new src/ffi/types.rs
rm -f "$out"
echo "wrote fmi3-slave/src/ffi/types.rs"
