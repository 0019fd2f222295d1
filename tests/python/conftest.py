"""Shared fixtures: the packaged FMUs (built by `cargo run -p fmu-build`)."""

import os
import pathlib
import shutil

import pytest
from fmpy import extract, read_model_description

ROOT = pathlib.Path(__file__).resolve().parents[2]

# Measured figures the tests report (shown in the summary without -s).
FIGURES: list[str] = []


def pytest_terminal_summary(terminalreporter):
    if FIGURES:
        terminalreporter.section("measured figures")
        for line in FIGURES:
            terminalreporter.write_line(line)


def fmu_dir() -> pathlib.Path:
    target = os.environ.get("CARGO_TARGET_DIR")
    return (pathlib.Path(target) if target else ROOT / "target") / "fmu"


def fmu_path(model_identifier: str) -> pathlib.Path:
    path = fmu_dir() / f"{model_identifier}.fmu"
    if not path.exists():
        pytest.fail(f"{path} missing: run `cargo run -p fmu-build` first")
    return path


@pytest.fixture(scope="session")
def plant_fmu() -> pathlib.Path:
    return fmu_path("DoublePendulum")


@pytest.fixture(scope="session")
def plant_md(plant_fmu):
    return read_model_description(str(plant_fmu))


@pytest.fixture(scope="session")
def plant_unzipped(plant_fmu, tmp_path_factory):
    directory = tmp_path_factory.mktemp("DoublePendulum")
    extract(str(plant_fmu), unzipdir=str(directory))
    yield directory
    shutil.rmtree(directory, ignore_errors=True)


@pytest.fixture(scope="session")
def controller_fmu() -> pathlib.Path:
    return fmu_path("EigenMPC")


@pytest.fixture(scope="session")
def controller_md(controller_fmu):
    return read_model_description(str(controller_fmu))


@pytest.fixture(scope="session")
def controller_unzipped(controller_fmu, tmp_path_factory):
    directory = tmp_path_factory.mktemp("EigenMPC")
    extract(str(controller_fmu), unzipdir=str(directory))
    yield directory
    shutil.rmtree(directory, ignore_errors=True)


@pytest.fixture(scope="session")
def eigenmpc_cli() -> pathlib.Path:
    """The release CLI (tests/run.sh builds it before pytest)."""
    target = os.environ.get("CARGO_TARGET_DIR")
    path = (pathlib.Path(target) if target else ROOT / "target") / "release" / "eigenmpc"
    if not path.exists():
        pytest.fail(f"{path} missing: run `cargo build --release --bin eigenmpc` first")
    return path


def _unzipped(identifier, tmp_path_factory):
    directory = tmp_path_factory.mktemp(identifier)
    extract(str(fmu_path(identifier)), unzipdir=str(directory))
    return directory


@pytest.fixture(scope="session")
def three_link_pair(tmp_path_factory):
    """(md, unzipped dir) of EigenMPC3 and of TriplePendulum."""
    dirs = [_unzipped(i, tmp_path_factory) for i in ("EigenMPC3", "TriplePendulum")]
    mds = [read_model_description(str(fmu_path(i))) for i in ("EigenMPC3", "TriplePendulum")]
    yield list(zip(mds, dirs))
    for d in dirs:
        shutil.rmtree(d, ignore_errors=True)
