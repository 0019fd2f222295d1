#!/usr/bin/env bash
# The C host tests, on every platform the FMUs carry a binary for: linux64
# natively (gcc), win64 under wine (mingw). On each:
# - plant_loop: the unpacked DoublePendulum.fmu's binary linked, through the
#   FMI functions of the generated header;
# - controller_loop: the C library's plain C API in a closed loop;
# - fmu_master: a generic FMI master that loads a controller FMU and a plant
#   FMU from their unpacked folders and runs the 14 J scenario; its figures
#   on win64 must be linux64's (same band time, final energy within 1e-6 J).
# Usage: bash tests/c/hosts.sh (from tests/run.sh, after fmu-build).
set -euo pipefail
cd "$(dirname "$0")/../.."
target_dir=$(cd "${CARGO_TARGET_DIR:-target}" && pwd)
fmu_dir="$target_dir/fmu"
work="$target_dir/c-host"
rm -rf "$work" && mkdir -p "$work"
cflags=(-std=c11 -O2 -Wall -Wextra -Werror -Iinclude)

unpack() { # FMU -> folder
    python3 -m zipfile -e "$fmu_dir/$1.fmu" "$work/$1"
}
for f in EigenMPC DoublePendulum EigenMPC3 TriplePendulum; do unpack "$f"; done
guid=$(grep -o 'guid="[^"]*"' "$work/DoublePendulum/modelDescription.xml" | cut -d'"' -f2)

# The pairs fmu_master runs: shipped 2 and 3 joints, and an exported 4-link robot.
"$target_dir/release/eigenmpc" export --model robots/examples/four-link-rigid.yml --energy 1 \
    --out "$work/export" >/dev/null
for f in FourLinkRigidEigenMPC FourLinkRigidPlant; do
    python3 -m zipfile -e "$work/export/$f.fmu" "$work/$f"
done
pairs=("EigenMPC DoublePendulum 30" "EigenMPC3 TriplePendulum 60" "FourLinkRigidEigenMPC FourLinkRigidPlant 15")

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
for pair in "${pairs[@]}"; do
    read -r c p t <<<"$pair"
    "$linux/fmu_master" linux64 "$work/$c" "$work/$p" "$t" | tee "$linux/$c.txt"
done

if [ ! -d "$work/DoublePendulum/binaries/win64" ]; then
    echo "-- win64: the FMUs carry no win64 binary (FMU_PLATFORMS=${FMU_PLATFORMS:-}); skipped"
    exit 0
fi
echo "-- win64 (mingw, under wine)"
win="$work/win64" && mkdir -p "$win"
export WINEPREFIX="$target_dir/wine" WINEDEBUG=-all
# Debian's wine 8.0 lacks bcryptprimitives.dll (ProcessPrng, imported by
# Rust's standard library): a test shim beside the test programs.
x86_64-w64-mingw32-gcc -shared -O2 -Wall -Wextra -Werror -o "$win/bcryptprimitives.dll" \
    tests/c/wine/process_prng.c -ladvapi32
# The FMU's DLL keeps the name it was built with (eigenmpc_robot.dll) in its
# export directory, which is the name a program linked to it imports.
cp "$work/DoublePendulum/binaries/win64/DoublePendulum.dll" "$win/eigenmpc_robot.dll"
x86_64-w64-mingw32-gcc "${cflags[@]}" tests/c/plant_loop.c -L"$work/DoublePendulum/binaries/win64" \
    -l:DoublePendulum.dll -lm -o "$win/plant_loop.exe"
wine "$win/plant_loop.exe" "$guid" "file:///Z:$work/DoublePendulum/resources"
cp "$fmu_dir/c/win64/eigenmpc_fmu.dll" "$win/"
x86_64-w64-mingw32-gcc "${cflags[@]}" tests/c/controller_loop.c -L"$fmu_dir/c/win64" \
    -l:eigenmpc_fmu.dll -lm -o "$win/controller_loop.exe"
wine "$win/controller_loop.exe"
x86_64-w64-mingw32-gcc "${cflags[@]}" tests/c/fmu_master.c -o "$win/fmu_master.exe"
for pair in "${pairs[@]}"; do
    read -r c p t <<<"$pair"
    wine "$win/fmu_master.exe" win64 "Z:$work/$c" "Z:$work/$p" "$t" | tr -d '\r' | tee "$win/$c.txt"
    python3 - "$linux/$c.txt" "$win/$c.txt" <<'PY'
import sys
linux, win = (dict(zip(*[iter(open(f).read().split())] * 2)) for f in sys.argv[1:])
assert linux["joints"] == win["joints"] and linux["band"] == win["band"], (linux, win)
de = abs(float(linux["final_energy"]) - float(win["final_energy"]))
assert de <= 1e-6, f"final energy differs by {de} J: {linux} {win}"
print(f"   win64 = linux64: band {win['band']} s, final energy within {de:.1e} J")
PY
done
