"""The packaged FMUs as an importer receives them: small binaries (debug
information stripped, kept apart in target/fmu/*.so.debug) that export the 34
FMI 2.0 co-simulation functions and, for EigenMPC, the plain C API."""

import subprocess
import zipfile

import pytest

from conftest import FIGURES, fmu_dir, fmu_path

FMUS = ["EigenMPC", "DoublePendulum", "EigenMPC3", "TriplePendulum"]


@pytest.mark.parametrize("identifier", FMUS)
def test_binaries_are_stripped_and_export_only_the_fmi_and_c_api(identifier, tmp_path):
    with zipfile.ZipFile(fmu_path(identifier)) as z:
        name = f"binaries/linux64/{identifier}.so"
        size = z.getinfo(name).file_size
        z.extract(name, tmp_path)
    library = tmp_path / name
    FIGURES.append(f"{identifier}.fmu binary: {size / 1e6:.1f} MB unzipped")
    assert size < 8e6, f"{size} bytes: debug information not stripped?"
    assert (fmu_dir() / f"{identifier}.so.debug").stat().st_size > size
    out = subprocess.run(["nm", "-D", "--defined-only", str(library)], check=True, capture_output=True, text=True)
    exported = {line.split()[2] for line in out.stdout.splitlines() if len(line.split()) == 3 and line.split()[1] in "TDBRVW"}
    fmi = {s for s in exported if s.startswith("fmi2")}
    assert len(fmi) == 34, sorted(fmi)
    capi = {s for s in exported if s.startswith("eigenmpc_")}
    assert bool(capi) == (identifier == "EigenMPC"), sorted(capi)
    assert exported == fmi | capi, sorted(exported - fmi - capi)
