"""`eigenmpc export` of robot files of 1, 2, 4, 5 and 6 joints: the pair
validates in fmpy and closes the loop under fmpy into the 5 % band; the SSP
runs in fmpy's SSP master."""

import math
import shutil
import subprocess

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.ssp.simulation import simulate_ssp
from fmpy.ssp.ssd import read_ssd
from fmpy.validation import validate_fmu

from conftest import FIGURES, ROOT
from fmi_host import Slave
from test_ssp import start_parameters

DT = 0.025
# file, name, E_ref (J), seconds, torque bound the export must take from the file
ROBOTS = {
    "single": ("robots/examples/single-pendulum.yml", "Single", 2.0, 15.0, 1.0),
    "lab-A0": ("robots/lab-double-pendulum-A0.yml", "LabA0", 2.0, 30.0, 0.5),
    "four": ("robots/examples/four-link-rigid.yml", "FourLink", 1.0, 15.0, 2.0),
    "five": ("robots/examples/five-link-point-masses.yml", "FiveLink", 2.0, 30.0, 1.0),
    "six": ("robots/examples/six-link-rigid.yml", "SixLink", 1.0, 15.0, 2.0),
}


@pytest.fixture(scope="module")
def exported(eigenmpc_cli, tmp_path_factory):
    """{key: (out dir, name, joints)} of every robot, exported once."""
    out = {}
    for key, (file, name, energy, _, _) in ROBOTS.items():
        directory = tmp_path_factory.mktemp(f"export-{key}")
        args = [str(eigenmpc_cli), "export", "--model", str(ROOT / file), "--out", str(directory)]
        args += ["--energy", str(energy), "--name", name]
        if key == "lab-A0":
            args += ["--tau-max", "0.5"]
        run = subprocess.run(args, capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        for suffix in ("EigenMPC.fmu", "Plant.fmu", ".ssp"):
            assert f"wrote {directory / (name + suffix)}" in run.stdout
        joints = int(run.stdout.split(" joints)")[0].rsplit("(", 1)[1])
        out[key] = (directory, name, joints)
    yield out
    for directory, _, _ in out.values():
        shutil.rmtree(directory, ignore_errors=True)


@pytest.mark.parametrize("key", ROBOTS)
def test_the_exported_pair_validates(exported, key):
    directory, name, joints = exported[key]
    for suffix in ("EigenMPC", "Plant"):
        path = str(directory / f"{name}{suffix}.fmu")
        assert validate_fmu(path) == [], path
        md = read_model_description(path)
        assert md.coSimulation.modelIdentifier == f"{name}{suffix}"
        names = [v.name for v in md.modelVariables]
        assert f"q[{joints}]" in names and f"q[{joints + 1}]" not in names
    md = read_model_description(str(directory / f"{name}EigenMPC.fmu"))
    start = {v.name: v.start for v in md.modelVariables}
    # the robot's parameters and the torque bound from its file are the start values
    file = (ROOT / ROBOTS[key][0]).read_text()
    m1 = next(float(line.split(":")[1]) for line in file.splitlines() if line.startswith("m1:"))
    assert float(start["m[1]"]) == m1
    assert float(start["tau_max"]) == ROBOTS[key][4]
    assert float(start["E_ref"]) == ROBOTS[key][2]


@pytest.mark.parametrize("key", ROBOTS)
def test_the_exported_pair_closes_the_loop_under_fmpy(exported, key, tmp_path):
    """Controller stepped before the plant, 25 ms, from 0.05 rad at rest."""
    directory, name, joints = exported[key]
    _, _, energy_ref, seconds, _ = ROBOTS[key]
    slaves = []
    for suffix, instance in (("EigenMPC", "controller"), ("Plant", "plant")):
        path = str(directory / f"{name}{suffix}.fmu")
        unzipped = tmp_path / suffix
        extract(path, unzipdir=str(unzipped))
        slaves.append(Slave(read_model_description(path), unzipped, instance))
    ctrl, plant = slaves
    js = range(1, joints + 1)
    q, qd, tau = [f"q[{j}]" for j in js], [f"qd[{j}]" for j in js], [f"tau[{j}]" for j in js]
    plant.initialize({f"q0[{j}]": 0.05 for j in js})
    ctrl.fmu.setupExperiment(startTime=0.0)
    ctrl.fmu.enterInitializationMode()
    ctrl.set_named({f"q[{j}]": 0.05 for j in js})
    ctrl.fmu.exitInitializationMode()
    state, ctrl_state = [plant.vr[n] for n in q + qd], [ctrl.vr[n] for n in q + qd]
    tau_out, tau_in = [ctrl.vr[n] for n in tau], [plant.vr[n] for n in tau]
    energies, torques = [], []
    for _ in range(round(seconds / DT)):
        ctrl.fmu.setReal(ctrl_state, plant.fmu.getReal(state))
        ctrl.step(DT)
        torque = ctrl.fmu.getReal(tau_out)
        plant.fmu.setReal(tau_in, torque)
        plant.step(DT)
        energies.append(plant.get("energy")[0])
        torques.append(torque)
    band = next(
        (DT * (i + 1) for i in range(len(energies)) if all(abs(e - energy_ref) < 0.05 * energy_ref for e in energies[i:])),
        None,
    )
    last = torques[-round(5.0 / DT):]
    rms = [math.sqrt(sum(t[j] ** 2 for t in last) / len(last)) for j in range(joints)]
    FIGURES.append(
        f"fmpy, exported {name} ({joints} joints), E_ref {energy_ref} J, {seconds:.0f} s: 5 % band for good at "
        f"{band:.3f} s, final E = {energies[-1]:.4f} J, RMS torque last 5 s = " + " / ".join(f"{r:.4f}" for r in rms) + " N m"
    )
    assert band is not None and band < seconds - 5.0
    assert abs(energies[-1] - energy_ref) < 0.02 * energy_ref
    ctrl.free()
    plant.free()


def test_the_exported_ssp_runs_in_fmpy(exported):
    directory, name, joints = exported["four"]
    path = str(directory / f"{name}.ssp")
    ssd = read_ssd(path)
    assert [c.name for c in ssd.system.elements] == ["controller", "plant"]
    result = simulate_ssp(path, stop_time=15.0, step_size=DT, parameter_set=start_parameters(ssd))
    energy = result["plant.energy"]
    tail = result["time"] > 10.0
    assert np.all(np.abs(energy[tail] - 1.0) < 0.05)


def test_a_bad_export_is_a_clear_error(eigenmpc_cli, tmp_path):
    def run(*args):
        return subprocess.run([str(eigenmpc_cli), "export", *args], capture_output=True, text=True)

    four = str(ROOT / ROBOTS["four"][0])
    bad = run("--model", four, "--out", str(tmp_path), "--name", "4links")
    assert bad.returncode == 1 and "--name '4links'" in bad.stderr
    bad = run("--model", four, "--out", str(tmp_path), "--tau-max", "5")
    assert bad.returncode == 1 and "exceeds the motor torque limit 2" in bad.stderr
    bad = run("--model", four, "--out", str(tmp_path), "--binary", str(tmp_path / "none.so"))
    assert bad.returncode == 1 and "no such file" in bad.stderr
    assert not list(tmp_path.iterdir())


def test_the_exported_controller_takes_its_precomputed_mode_family(exported, tmp_path):
    """The family shipped in resources/ is taken as it is (no continuation at
    fmi2ExitInitializationMode), E_ref then moves along it; a changed model
    computes its own family and says why."""
    directory, name, joints = exported["six"]
    path = str(directory / f"{name}EigenMPC.fmu")
    md = read_model_description(path)
    assert float({v.name: v.start for v in md.modelVariables}["chart_source"]) == 1  # computed
    unzipped = tmp_path / "ctrl"
    extract(path, unzipdir=str(unzipped))
    assert (unzipped / "resources" / "eigenmpc-family.json").exists()
    ctrl = Slave(md, unzipped, "controller", logging_on=True)
    ctrl.initialize({f"q[{j}]": 0.05 for j in range(1, joints + 1)})
    assert ctrl.logged("the one computed at export"), ctrl.messages
    assert not ctrl.logged("computed now")
    lo, hi = ctrl.get("chart_energy_min", "chart_energy_max")
    assert lo < 0.5 and hi > 2.0, (lo, hi)
    ctrl.set_named({"E_ref": 1.5})
    ctrl.step(DT)
    assert ctrl.get("chart_energy")[0] == pytest.approx(1.5)
    ctrl.free()
    other = Slave(md, unzipped, "lighter", logging_on=True)
    other.initialize({"m[1]": 0.5})
    assert other.logged("computed now, not the exported one", "parameters differ"), other.messages
    other.free()
