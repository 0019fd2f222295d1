"""Shared fixtures: the packaged FMUs (built by `cargo run -p fmu-build`)."""

import os
import pathlib
import shutil

import pytest
from fmpy import extract, read_model_description

ROOT = pathlib.Path(__file__).resolve().parents[2]


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
