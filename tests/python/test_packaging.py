"""The packaged FMUs as an importer receives them: each the one FMU binary
(per platform: linux64, win64, and aarch64-linux in the FMI 3.0 archives),
small (debug information stripped, kept apart in
target/fmu/eigenmpc_robot.so.debug), exporting the 34 FMI 2.0 co-simulation
functions and the 75 of FMI 3.0 (the same binary serves the FMI 3.0
archives) and nothing else (the plain C API is libeigenmpc_fmu.so, tested by
the C host tests), and resources/ saying which model it is."""

import json
import os

import subprocess
import zipfile

import pytest

from conftest import FIGURES, fmu_dir, fmu_path

FMUS = ["EigenMPC", "DoublePendulum", "EigenMPC3", "TriplePendulum"]


@pytest.mark.parametrize("identifier", FMUS)
def test_binaries_are_stripped_and_export_only_the_fmi_functions(identifier, tmp_path):
    with zipfile.ZipFile(fmu_path(identifier)) as z:
        name = f"binaries/linux64/{identifier}.so"
        size = z.getinfo(name).file_size
        z.extract(name, tmp_path)
    library = tmp_path / name
    FIGURES.append(f"{identifier}.fmu binary: {size / 1e6:.1f} MB unzipped")
    assert size < 8e6, f"{size} bytes: debug information not stripped?"
    assert (fmu_dir() / "eigenmpc_robot.so.debug").stat().st_size > size
    robot = fmu_dir() / "robot" / "linux64" / "libeigenmpc_robot.so"
    assert library.read_bytes() == robot.read_bytes(), "not the one FMU binary"
    out = subprocess.run(["nm", "-D", "--defined-only", str(library)], check=True, capture_output=True, text=True)
    exported = {line.split()[2] for line in out.stdout.splitlines() if len(line.split()) == 3 and line.split()[1] in "TDBRVW"}
    fmi2 = {s for s in exported if s.startswith("fmi2")}
    fmi3 = {s for s in exported if s.startswith("fmi3")}
    assert len(fmi2) == 34 and len(fmi3) == 75, (sorted(fmi2), sorted(fmi3))
    assert exported == fmi2 | fmi3, sorted(exported - fmi2 - fmi3)


@pytest.mark.parametrize("identifier", FMUS)
def test_resources_say_which_model_the_binary_is(identifier):
    with zipfile.ZipFile(fmu_path(identifier)) as z:
        spec = json.loads(z.read("resources/eigenmpc-export.json"))
        names = z.namelist()
    assert spec["model_name"] == identifier
    assert spec["kind"] == ("controller" if identifier.startswith("EigenMPC") else "plant")
    assert spec["joints"] == (3 if identifier.endswith("3") or identifier.startswith("Triple") else 2)
    # The controllers carry their mode family, computed at packaging.
    assert ("resources/eigenmpc-family.json" in names) == (spec["kind"] == "controller")


# The Windows system libraries a win64 FMU binary may import (Rust's
# standard library and the mingw C runtime): nothing a user has to install.
WINDOWS_SYSTEM_DLLS = {
    "kernel32.dll", "msvcrt.dll", "ntdll.dll", "userenv.dll", "ws2_32.dll",
    "api-ms-win-core-synch-l1-2-0.dll", "bcryptprimitives.dll", "advapi32.dll",
}


@pytest.mark.parametrize("identifier", FMUS)
def test_win64_binaries_export_the_fmi_functions_and_import_only_windows(identifier, tmp_path):
    if "win64" not in os.environ.get("FMU_PLATFORMS", "win64"):
        pytest.skip("FMU_PLATFORMS leaves win64 out")
    with zipfile.ZipFile(fmu_path(identifier)) as z:
        name = f"binaries/win64/{identifier}.dll"
        assert name in z.namelist(), "no win64 binary"
        size = z.getinfo(name).file_size
        z.extract(name, tmp_path)
    FIGURES.append(f"{identifier}.fmu win64 binary: {size / 1e6:.1f} MB unzipped")
    assert size < 12e6, f"{size} bytes: not stripped?"
    out = subprocess.run(["x86_64-w64-mingw32-objdump", "-p", str(tmp_path / name)],
                         check=True, capture_output=True, text=True).stdout
    table = out.split("[Ordinal/Name Pointer] Table", 1)[1]
    exported = set()
    for line in table.splitlines()[1:]:
        parts = line.strip().split()
        if len(parts) != 3 or not parts[0].startswith("["):
            break
        exported.add(parts[2])
    fmi2 = {s for s in exported if s.startswith("fmi2")}
    fmi3 = {s for s in exported if s.startswith("fmi3")}
    assert len(fmi2) == 34 and len(fmi3) == 75 and exported == fmi2 | fmi3, sorted(exported)
    imported = {line.split(":", 1)[1].strip().lower() for line in out.splitlines() if "DLL Name:" in line}
    assert imported <= WINDOWS_SYSTEM_DLLS, sorted(imported - WINDOWS_SYSTEM_DLLS)


# The shared libraries an aarch64-linux FMU binary may need: glibc's, and
# libgcc's unwinder; nothing a user has to install on a Debian or Ubuntu
# board.
AARCH64_SYSTEM_LIBRARIES = {"libc.so.6", "libm.so.6", "libgcc_s.so.1", "ld-linux-aarch64.so.1"}


@pytest.mark.parametrize("identifier", FMUS)
def test_aarch64_binaries_are_in_the_fmi3_archives_only(identifier, tmp_path):
    if "aarch64-linux" not in os.environ.get("FMU_PLATFORMS", "aarch64-linux"):
        pytest.skip("FMU_PLATFORMS leaves aarch64-linux out")
    name = f"binaries/aarch64-linux/{identifier}.so"
    with zipfile.ZipFile(fmu_path(identifier)) as z:
        # FMI 2.0 names no 64-bit ARM platform.
        assert not any("aarch64" in n for n in z.namelist()), z.namelist()
    with zipfile.ZipFile(fmu_dir() / "fmi3" / f"{identifier}.fmu") as z:
        folders = {n.split("/")[1] for n in z.namelist() if n.startswith("binaries/")}
        assert {"x86_64-linux", "aarch64-linux"} <= folders, folders
        size = z.getinfo(name).file_size
        z.extract(name, tmp_path)
    library = tmp_path / name
    FIGURES.append(f"{identifier}.fmu aarch64-linux binary: {size / 1e6:.1f} MB unzipped")
    assert size < 8e6, f"{size} bytes: not stripped?"
    header = library.read_bytes()[:20]
    # ELF, 64-bit, little-endian, shared object, machine EM_AARCH64 (183).
    assert header[:4] == b"\x7fELF" and header[4] == 2 and header[5] == 1
    assert int.from_bytes(header[16:18], "little") == 3
    assert int.from_bytes(header[18:20], "little") == 183
    out = subprocess.run(["aarch64-linux-gnu-nm", "-D", "--defined-only", str(library)],
                         check=True, capture_output=True, text=True).stdout
    exported = {line.split()[2] for line in out.splitlines() if len(line.split()) == 3 and line.split()[1] in "TDBRVW"}
    fmi2 = {s for s in exported if s.startswith("fmi2")}
    fmi3 = {s for s in exported if s.startswith("fmi3")}
    assert len(fmi2) == 34 and len(fmi3) == 75 and exported == fmi2 | fmi3, sorted(exported)
    out = subprocess.run(["aarch64-linux-gnu-readelf", "-d", str(library)],
                         check=True, capture_output=True, text=True).stdout
    needed = {line.split("[", 1)[1].rstrip("]") for line in out.splitlines() if "(NEEDED)" in line}
    assert needed <= AARCH64_SYSTEM_LIBRARIES, sorted(needed - AARCH64_SYSTEM_LIBRARIES)
