"""The packaged FMUs as an importer receives them: each the one FMU binary,
small (debug information stripped, kept apart in
target/fmu/eigenmpc_robot.so.debug), exporting the 34 FMI 2.0 co-simulation
functions and nothing else (the plain C API is libeigenmpc_fmu.so, tested by
the C host tests), and resources/ saying which model it is."""

import json

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
    fmi = {s for s in exported if s.startswith("fmi2")}
    assert len(fmi) == 34, sorted(fmi)
    assert exported == fmi, sorted(exported - fmi)


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
