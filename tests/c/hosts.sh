#!/usr/bin/env bash
# The C host tests, on every platform the FMUs carry a binary for: linux64
# natively (gcc), win64 under wine (mingw), aarch64-linux under qemu-user
# (the aarch64 GNU toolchain). On each:
# - plant_loop (linux64, win64): the unpacked DoublePendulum.fmu's binary
#   linked, through the FMI functions of the generated header;
# - controller_loop: the C library's plain C API in a closed loop;
# - fmu_master: a generic FMI 2.0 / 3.0 master that loads a controller FMU
#   and a plant FMU from their unpacked folders and runs the paper's
#   scenario, for the shipped 2- and 3-joint pairs and an exported 4-link
#   robot: FMI 2.0 archives on linux64 and win64, FMI 3.0 archives on every
#   platform (aarch64-linux is in FMI 3.0 only). Every run's figures must be
#   the linux64 FMI 2.0 run's: the same band time, the final energy within
#   1e-6 J.
# Usage: bash tests/c/hosts.sh (from tests/run.sh, after fmu-build).
set -euo pipefail
cd "$(dirname "$0")/../.."
target_dir=$(cd "${CARGO_TARGET_DIR:-target}" && pwd)
fmu_dir="$target_dir/fmu"
work="$target_dir/c-host"
rm -rf "$work" && mkdir -p "$work"
cflags=(-std=c11 -O2 -Wall -Wextra -Werror -Iinclude -Ifmi3-slave/fmi-standard3/headers)

# FMI 2.0 archives unpack to $work/<id>, FMI 3.0 ones to $work/fmi3/<id>.
for f in EigenMPC DoublePendulum EigenMPC3 TriplePendulum; do
    python3 -m zipfile -e "$fmu_dir/$f.fmu" "$work/$f"
    python3 -m zipfile -e "$fmu_dir/fmi3/$f.fmu" "$work/fmi3/$f"
done
guid=$(grep -o 'guid="[^"]*"' "$work/DoublePendulum/modelDescription.xml" | cut -d'"' -f2)

# The pairs fmu_master runs: shipped 2 and 3 joints, and an exported 4-link robot.
"$target_dir/release/eigenmpc" export --model robots/examples/four-link-rigid.yml --energy 1 \
    --fmi 2,3 --out "$work/export" >/dev/null
for f in FourLinkRigidEigenMPC FourLinkRigidPlant; do
    python3 -m zipfile -e "$work/export/$f.fmu" "$work/$f"
    python3 -m zipfile -e "$work/export/fmi3/$f.fmu" "$work/fmi3/$f"
done
pairs=("EigenMPC DoublePendulum 30" "EigenMPC3 TriplePendulum 60" "FourLinkRigidEigenMPC FourLinkRigidPlant 15")

# same_figures REFERENCE OTHER LABEL: the run in OTHER reproduces REFERENCE's
# figures (fmu_master's output lines).
same_figures() {
    python3 - "$@" <<'PY'
import sys
ref, other = (dict(zip(*[iter(open(f).read().split())] * 2)) for f in sys.argv[1:3])
assert ref["joints"] == other["joints"] and ref["band"] == other["band"], (ref, other)
de = abs(float(ref["final_energy"]) - float(other["final_energy"]))
assert de <= 1e-6, f"final energy differs by {de} J: {ref} {other}"
print(f"   {sys.argv[3]} = linux64 FMI 2.0: band {other['band']} s, final energy within {de:.1e} J")
PY
}
# run_pairs LABEL FMI_FOLDER OUT_DIR COMMAND...: fmu_master on every pair;
# FMI_FOLDER is "" (FMI 2.0 archives) or "fmi3/"; PATH_PREFIX (wine's Z:)
# goes before each folder. Compares with the linux64 FMI 2.0 run when
# there is one.
run_pairs() {
    local label=$1 folder=$2 out=$3
    shift 3
    mkdir -p "$out"
    for pair in "${pairs[@]}"; do
        read -r c p t <<<"$pair"
        "$@" "${PATH_PREFIX:-}$work/$folder$c" "${PATH_PREFIX:-}$work/$folder$p" "$t" \
            | tr -d '\r' | tee "$out/$c.txt"
        if [ -e "$linux/$c.txt" ] && [ "$out/$c.txt" != "$linux/$c.txt" ]; then
            same_figures "$linux/$c.txt" "$out/$c.txt" "$label"
        fi
    done
}

echo "-- linux64 (gcc)"
linux="$work/linux64" && mkdir -p "$linux"
plant_bin="$work/DoublePendulum/binaries/linux64"
gcc "${cflags[@]}" tests/c/plant_loop.c -L"$plant_bin" -l:DoublePendulum.so \
    -Wl,-rpath,"$plant_bin" -lm -o "$linux/plant_loop"
"$linux/plant_loop" "$guid" "file://$work/DoublePendulum/resources"
c_lib="$fmu_dir/c/linux64"
gcc "${cflags[@]}" tests/c/controller_loop.c -L"$c_lib" -leigenmpc_fmu -Wl,-rpath,"$c_lib" \
    -lm -o "$linux/controller_loop"
"$linux/controller_loop"
gcc "${cflags[@]}" tests/c/fmu_master.c -ldl -lm -o "$linux/fmu_master"
run_pairs "linux64 FMI 2.0" "" "$linux" "$linux/fmu_master" linux64
run_pairs "linux64 FMI 3.0" fmi3/ "$linux/fmi3" "$linux/fmu_master" x86_64-linux

win64_hosts() {
    if [ ! -d "$work/DoublePendulum/binaries/win64" ]; then
        echo "-- win64: the FMUs carry no win64 binary (FMU_PLATFORMS=${FMU_PLATFORMS:-}); skipped"
        return
    fi
    echo "-- win64 (mingw, under wine)"
    local win="$work/win64" && mkdir -p "$win"
    export WINEPREFIX="$target_dir/wine" WINEDEBUG=-all
    # Debian's wine 8.0 lacks bcryptprimitives.dll (ProcessPrng, imported by
    # Rust's standard library): a test shim beside the test programs.
    x86_64-w64-mingw32-gcc -shared -O2 -Wall -Wextra -Werror -o "$win/bcryptprimitives.dll" \
        tests/c/wine/process_prng.c -ladvapi32
    # The FMU's DLL keeps the name it was built with (eigenmpc_robot.dll) in
    # its export directory, which is the name a program linked to it imports.
    cp "$work/DoublePendulum/binaries/win64/DoublePendulum.dll" "$win/eigenmpc_robot.dll"
    x86_64-w64-mingw32-gcc "${cflags[@]}" tests/c/plant_loop.c \
        -L"$work/DoublePendulum/binaries/win64" -l:DoublePendulum.dll -lm -o "$win/plant_loop.exe"
    wine "$win/plant_loop.exe" "$guid" "file:///Z:$work/DoublePendulum/resources"
    cp "$fmu_dir/c/win64/eigenmpc_fmu.dll" "$win/"
    x86_64-w64-mingw32-gcc "${cflags[@]}" tests/c/controller_loop.c -L"$fmu_dir/c/win64" \
        -l:eigenmpc_fmu.dll -lm -o "$win/controller_loop.exe"
    wine "$win/controller_loop.exe"
    x86_64-w64-mingw32-gcc "${cflags[@]}" tests/c/fmu_master.c -o "$win/fmu_master.exe"
    PATH_PREFIX=Z: run_pairs "win64 FMI 2.0" "" "$win" wine "$win/fmu_master.exe" win64
    PATH_PREFIX=Z: run_pairs "win64 FMI 3.0" fmi3/ "$win/fmi3" \
        wine "$win/fmu_master.exe" x86_64-windows
}

aarch64_hosts() {
    if [ ! -d "$work/fmi3/DoublePendulum/binaries/aarch64-linux" ]; then
        echo "-- aarch64-linux: the FMUs carry no aarch64 binary" \
            "(FMU_PLATFORMS=${FMU_PLATFORMS:-}); skipped"
        return
    fi
    echo "-- aarch64-linux (aarch64-linux-gnu-gcc, under qemu-user)"
    local arm="$work/aarch64-linux" && mkdir -p "$arm"
    # qemu-user runs aarch64 programs with the cross toolchain's C library.
    local qemu=(qemu-aarch64 -L /usr/aarch64-linux-gnu)
    local c_lib="$fmu_dir/c/aarch64-linux"
    aarch64-linux-gnu-gcc "${cflags[@]}" tests/c/controller_loop.c -L"$c_lib" -leigenmpc_fmu \
        -Wl,-rpath,"$c_lib" -lm -o "$arm/controller_loop"
    "${qemu[@]}" "$arm/controller_loop"
    aarch64-linux-gnu-gcc "${cflags[@]}" tests/c/fmu_master.c -ldl -lm -o "$arm/fmu_master"
    run_pairs "aarch64-linux FMI 3.0" fmi3/ "$arm/fmi3" \
        "${qemu[@]}" "$arm/fmu_master" aarch64-linux
}

win64_hosts
aarch64_hosts
