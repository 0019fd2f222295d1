"""The Dask runner against the native `eigenmpc sweep`: the same runs from
the same spec (grid order, random sample), and the same metrics from a
16-run sweep on a 2-worker local cluster, to the agreement of the FMU loop
with the native loop (the plant FMU's integrator against the native one)."""

import csv
import math
import os
import pathlib
import subprocess

import pytest

from eigenmpc_sweep import Spec, expand, run_sweep, write_results

ROOT = pathlib.Path(__file__).resolve().parents[2]
TARGET = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
SPEC = """
duration = 25.0

[grid]
"controller.E_ref" = [10.0, 14.0]
"model.m[2]" = [0.9, 1.1]
"imperfections.delay" = [0, 2]
"imperfections.measurement_noise" = [0.0, 0.01]
"""


def native(spec_path, out):
    cli = TARGET / "release" / "eigenmpc"
    if not cli.exists():
        pytest.fail(f"{cli} missing: run `cargo build --release --bin eigenmpc` first")
    subprocess.run([str(cli), "sweep", "--spec", str(spec_path), "--out", str(out)], check=True, capture_output=True)
    with open(out / "sweep.csv") as f:
        return list(csv.DictReader(f))


def test_runs_expand_as_the_native_sweep(tmp_path):
    spec_path = tmp_path / "spec.toml"
    spec_path.write_text(
        'duration = 6.0\n[grid]\n"controller.E_ref" = { from = 10.0, to = 14.0, count = 2 }\n'
        '[random]\nsamples = 3\nseed = 11\n[random.ranges]\n"model.m[2]" = { from = 0.9, to = 1.1 }\n'
        '"plant.qd0[1]" = { from = -0.1, to = 0.1 }\n'
    )
    rows = native(spec_path, tmp_path / "native")
    spec = Spec.load(spec_path)
    runs = expand(spec)
    assert len(runs) == len(rows) == 6
    for run, row in zip(runs, rows):
        for name, value in run:
            assert float(row[name]) == value, (name, row[name], value)
    with pytest.raises(ValueError, match="give the scope"):
        expand(Spec(grid={"E_ref": [1.0]}))


def close(a, b, tol):
    if a == "" or b == "":
        return a == b
    return abs(float(a) - float(b)) <= tol


def test_a_16_run_sweep_on_2_dask_workers_equals_the_native_one(tmp_path):
    from dask.distributed import Client, LocalCluster

    spec_path = tmp_path / "spec16.toml"
    spec_path.write_text(SPEC)
    expected = native(spec_path, tmp_path / "native")
    spec = Spec.load(spec_path)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with Client(cluster) as client:
            rows = run_sweep(spec, TARGET / "fmu", client)
    write_results(spec, rows, tmp_path / "dask")
    with open(tmp_path / "dask" / "sweep.csv") as f:
        got = list(csv.DictReader(f))
    assert len(got) == len(expected) == 16
    assert [e for _, _, e in rows] == [None] * 16
    for g, e in zip(got, expected):
        for name in spec.swept():
            assert float(g[name]) == float(e[name])
        assert close(g["time_to_band"], e["time_to_band"], 0.051), (g, e)  # two samples
        assert g["success"] == e["success"]
        assert close(g["final_energy_error"], e["final_energy_error"], 1e-3)
        assert close(g["mean_energy_error"], e["mean_energy_error"], 1e-4)
        for j in ("1", "2"):
            assert close(g[f"rms_torque_{j}"], e[f"rms_torque_{j}"], 1e-4)
        assert g["failed_solves"] == e["failed_solves"]
        assert g["model_updates"] == e["model_updates"]
        assert g["distance_to_mode"] == "" and e["distance_to_mode"] != ""
    assert any(math.isfinite(float(g["time_to_band"])) for g in got if g["time_to_band"])
