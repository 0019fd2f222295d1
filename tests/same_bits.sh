#!/usr/bin/env bash
# The shipped FMUs' model descriptions (their defaults, hence their GUIDs)
# and the controllers' precomputed mode families have the same bits on
# every machine (issue 36): `fmu-build --descriptions` computes them
#   - natively,
#   - on baseline x86-64 (qemu-x86_64 -cpu qemu64: SSE2 only, so glibc's
#     libm and every run-time SIMD dispatch take their baseline paths),
#   - on x86-64 with AVX2 and FMA but no AVX-512 (qemu -cpu Haswell),
#   - on aarch64 (cross-built with Debian's Rust, run under qemu-aarch64),
# and every result must be byte-equal to the checked-in descriptions.
# Before the elementary functions went through `eigenmpc::math`, glibc's
# FMA variants of sin/cos/exp/pow moved the charts' last bits between
# machines. Needs target/release/fmu-build (tests/run.sh builds it) and
# the cross tools (scripts/ensure-cross-deps.sh).
set -euo pipefail
cd "$(dirname "$0")/.."

out=target/same-bits
rm -rf "$out"
native=target/release/fmu-build
test -x "$native" || { echo "$native missing: cargo build --release -p fmu-build" >&2; exit 1; }

echo "-- native ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs))"
"$native" --descriptions "$out/native" >/dev/null
for cpu in qemu64 Haswell-noTSX; do
    echo "-- x86-64 under qemu-x86_64 -cpu $cpu"
    # (qemu names the CPU model's features its emulator lacks: noise here.)
    qemu-x86_64 -cpu "$cpu" "$native" --descriptions "$out/x86-64-$cpu" >/dev/null \
        2> >(grep -v "TCG doesn't support requested feature" >&2)
done

echo "-- aarch64: cross build (Debian's rustc-web, -Zbuild-std) and qemu-aarch64"
# The same toolchain and flags as fmu-build's cross builds of the FMU binary
# (fmu-build/src/main.rs, cross_build), into the same target folder.
env -u RUSTUP_TOOLCHAIN -u CARGO_TARGET_DIR \
    RUSTC=/usr/bin/rustc RUSTC_BOOTSTRAP=1 \
    CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc \
    CARGO_PROFILE_RELEASE_DEBUG=0 \
    /usr/bin/cargo build --quiet --release -p fmu-build --bin fmu-build \
    -Zbuild-std=std,panic_abort --target aarch64-unknown-linux-gnu --target-dir target/cross
qemu-aarch64 -L /usr/aarch64-linux-gnu \
    target/cross/aarch64-unknown-linux-gnu/release/fmu-build --descriptions "$out/aarch64" >/dev/null

status=0
for run in x86-64-qemu64 x86-64-Haswell-noTSX aarch64; do
    if diff -r "$out/native" "$out/$run" >"$out/$run.diff"; then
        echo "$run: byte-equal to native ($(find "$out/native" -type f | wc -l) files)"
    else
        echo "$run: differs from native:" >&2
        head -20 "$out/$run.diff" >&2
        status=1
    fi
done
# The checked-in descriptions are these (a user's fmu-build checks it too).
for f in "$out"/native/*.xml "$out"/native/fmi3/*.xml; do
    rel=${f#"$out"/native/}
    if ! cmp -s "$f" "modelDescription/$rel"; then
        echo "modelDescription/$rel differs from the computed description:" \
            "run cargo run --release -p fmu-build -- --update-checked-in" >&2
        status=1
    fi
done
[ "$status" = 0 ] && echo "same bits: native, baseline x86-64, AVX2 x86-64 and aarch64 agree with modelDescription/"
exit "$status"
