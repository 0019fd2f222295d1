"""The Dask runner is the native `eigenmpc sweep` split over workers: the
same CSV and JSON (every column but the machine's solve times) from a
16-run sweep on a 2-worker local cluster, a robot file of 4 joints, and the
native errors for a bad spec."""

import csv
import json
import os
import pathlib
import subprocess

import pytest

from eigenmpc_sweep import SweepError, parts, plan, run_sweep

ROOT = pathlib.Path(__file__).resolve().parents[2]
TARGET = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
CLI = TARGET / "release" / "eigenmpc"
SPEC = """
duration = 25.0

[grid]
"controller.E_ref" = [10.0, 14.0]
"model.m[2]" = [0.9, 1.1]
"imperfections.delay" = [0, 2]
"imperfections.measurement_noise" = [0.0, 0.01]
"""


@pytest.fixture(scope="module")
def cli():
    if not CLI.exists():
        pytest.fail(f"{CLI} missing: run `cargo build --release --bin eigenmpc` first")
    return str(CLI)


@pytest.fixture(scope="module")
def client():
    from dask.distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with Client(cluster) as c:
            yield c


def native(cli, spec_path, out):
    subprocess.run([cli, "sweep", "--spec", str(spec_path), "--out", str(out)], check=True, capture_output=True)


def without_solve_times(out):
    with open(out / "sweep.csv") as f:
        rows = [{k: v for k, v in r.items() if not k.startswith("solve_time")} for r in csv.DictReader(f)]
    runs = json.loads((out / "sweep.json").read_text())["runs"]
    for r in runs:
        r.get("metrics", {}).pop("solve_time", None)
    return rows, runs


def test_parts_cover_every_run_once():
    for runs, partitions in [(16, 2), (5, 3), (3, 8), (1, 1)]:
        ranges = parts(runs, partitions)
        assert [i for a, b in ranges for i in range(a, b)] == list(range(runs))
        assert len(ranges) == min(runs, partitions)


def test_a_16_run_sweep_on_2_dask_workers_equals_the_native_one(tmp_path, cli, client):
    spec_path = tmp_path / "spec16.toml"
    spec_path.write_text(SPEC)
    native(cli, spec_path, tmp_path / "native")
    summary = run_sweep(spec_path, client, tmp_path / "dask", binary=cli)
    assert "16 runs of 25 s merged from 2 record file(s)" in summary, summary
    got, expected = without_solve_times(tmp_path / "dask"), without_solve_times(tmp_path / "native")
    assert len(got[0]) == 16
    assert got == expected
    assert all(r["error"] == "" for r in got[0])
    assert any(r["time_to_band"] for r in got[0])
    for name in ("sweep.png", "sweep.svg"):
        assert (tmp_path / "dask" / name).stat().st_size > 300


def test_a_four_joint_robot_file_sweeps_through_dask(tmp_path, cli, client):
    robot = ROOT / "robots" / "examples" / "four-link-rigid.yml"
    spec_path = tmp_path / "four.toml"
    spec_path.write_text(f'duration = 10.0\nmodel = "{robot}"\n[grid]\n"controller.E_ref" = [0.8, 1.0]\n')
    assert plan(spec_path, cli) == {"runs": 2, "joints": 4, "swept": ["controller.E_ref"]}
    native(cli, spec_path, tmp_path / "native")
    run_sweep(spec_path, client, tmp_path / "dask", binary=cli)
    got = without_solve_times(tmp_path / "dask")
    assert got == without_solve_times(tmp_path / "native")
    assert [r["success"] for r in got[0]] == ["1", "1"]
    assert all(float(r["rms_torque_4"]) > 0 for r in got[0])


def test_a_bad_spec_fails_with_the_native_message(tmp_path, cli):
    spec_path = tmp_path / "bad.toml"
    spec_path.write_text('[grid]\n"E_ref" = [1.0]\n')
    with pytest.raises(SweepError, match="give the scope"):
        plan(spec_path, cli)
    from eigenmpc_sweep.__main__ import main

    assert main(["--spec", str(spec_path), "--eigenmpc", cli]) == 1
