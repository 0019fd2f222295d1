"""The FMI 3.0 Co-Simulation archives (target/fmu/fmi3/*.fmu): the same
models and the same binary as the FMI 2.0 archives, described with arrays
(q, qd, tau, chart.coef) and unique value references. Checked with fmpy:
validation, simulate_fmu, a closed loop of controller and plant through
FMU3Slave that reproduces the FMI 2.0 figures, and FMU state save, restore
and serialization that continue bit for bit."""

import math
import subprocess

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

from conftest import FIGURES, ROOT, fmu_dir

FMUS = ["EigenMPC", "DoublePendulum", "EigenMPC3", "TriplePendulum"]
STEP = 0.025
START_ANGLE = 0.05


def fmi3_path(identifier):
    path = fmu_dir() / "fmi3" / f"{identifier}.fmu"
    if not path.exists():
        pytest.fail(f"{path} missing: run `cargo run -p fmu-build` first")
    return str(path)


@pytest.mark.parametrize("identifier", FMUS)
def test_fmpy_validates_and_simulates_each_fmi3_fmu(identifier):
    path = fmi3_path(identifier)
    problems = validate_fmu(path)
    assert problems == [], problems
    md = read_model_description(path)
    assert md.fmiVersion == "3.0"
    names = {v.name: v for v in md.modelVariables}
    joints = 3 if "3" in identifier or identifier.startswith("Triple") else 2
    for array in ("q", "qd", "tau"):
        v = names[array]
        assert v.type == "Float64" and len(v.dimensions) == 1
        assert int(v.dimensions[0].start) == joints, array
    if identifier.startswith("EigenMPC"):
        coef = names["chart.coef"]
        assert [int(d.start) for d in coef.dimensions] == [joints, 10]
        assert names["variant"].type == "Enumeration"
    result = simulate_fmu(path, stop_time=1.0, output_interval=STEP)
    assert len(result) >= 40
    for field in result.dtype.names:
        assert np.all(np.isfinite(result[field])), field


class Slave:
    """One FMI 3.0 instance of an archive (a shipped FMU's identifier, or a
    path), with its variables by name."""

    def __init__(self, identifier, name):
        path = identifier if identifier.endswith(".fmu") else fmi3_path(identifier)
        self.md = read_model_description(path)
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.fmu = FMU3Slave(guid=self.md.guid, unzipDirectory=extract(path),
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.fmu.instantiate()

    def size(self, name):
        v = self.vars[name]
        n = 1
        for d in v.dimensions:
            n *= int(d.start)
        return n

    def get(self, name):
        return self.fmu.getFloat64([self.vars[name].valueReference], self.size(name))

    def set(self, name, values):
        self.fmu.setFloat64([self.vars[name].valueReference], list(values))


def closed_loop(controller_id, plant_id, stop, save_at=None):
    """The demo's loop (controller stepped first, 25 ms): the energy trace,
    and with save_at, the FMU states of both saved at that time."""
    plant, controller = Slave(plant_id, "plant"), Slave(controller_id, "controller")
    n = plant.size("q")
    for s in (plant, controller):
        s.fmu.enterInitializationMode(startTime=0.0)
    plant.set("q0", [START_ANGLE] * n)
    plant.fmu.exitInitializationMode()
    controller.set("q", plant.get("q"))
    controller.set("qd", plant.get("qd"))
    controller.fmu.exitInitializationMode()
    e_ref = controller.get("E_ref")[0]
    trace, saved = [], None
    steps = round(stop / STEP)
    for k in range(steps + 1):
        t = k * STEP
        if save_at is not None and abs(t - save_at) < 1e-9:
            saved = (plant.fmu.getFMUState(), controller.fmu.getFMUState(), k)
        trace.append(plant.get("energy")[0])
        if k > 0:
            controller.set("q", plant.get("q"))
            controller.set("qd", plant.get("qd"))
        controller.fmu.doStep(t, STEP)
        tau = controller.get("tau")
        if k == steps:
            break
        plant.set("tau", tau)
        plant.fmu.doStep(t, STEP)
    return plant, controller, e_ref, trace, saved


def band_time(trace, e_ref):
    outside = [k for k, e in enumerate(trace) if abs(e - e_ref) >= 0.05 * abs(e_ref) or not math.isfinite(e)]
    return (outside[-1] + 1) * STEP if outside else 0.0


@pytest.mark.parametrize("pair,stop,band,energy", [
    (("EigenMPC", "DoublePendulum"), 30.0, 19.675, 13.990879594),
    (("EigenMPC3", "TriplePendulum"), 60.0, 43.625, 13.940953522),
])
def test_fmi3_closed_loop_reproduces_the_fmi2_figures(pair, stop, band, energy):
    # The FMI 2.0 figures of the same pair (tests/c/hosts.sh's master and
    # the demo print them for the FMI 2.0 archives, on linux64 and win64).
    plant, controller, e_ref, trace, _ = closed_loop(*pair, stop)
    for s in (plant, controller):
        s.fmu.terminate()
        s.fmu.freeInstance()
    FIGURES.append(f"fmpy FMI 3.0, {pair[0]} + {pair[1]}, {stop:.0f} s: 5 % band for good at "
                   f"{band_time(trace, e_ref):.3f} s, E = {trace[-1]:.9f} J")
    assert band_time(trace, e_ref) == pytest.approx(band, abs=1e-9)
    assert trace[-1] == pytest.approx(energy, abs=1e-6)


def test_fmi3_state_restore_and_deserialization_continue_bit_for_bit():
    plant, controller, e_ref, trace, saved = closed_loop("EigenMPC", "DoublePendulum", 6.0, save_at=3.0)
    plant_state, controller_state, k0 = saved
    serialized = (plant.fmu.serializeFMUState(plant_state), controller.fmu.serializeFMUState(controller_state))

    def rerun(restore):
        restore()
        energies = []
        for k in range(k0, round(6.0 / STEP) + 1):
            t = k * STEP
            energies.append(plant.get("energy")[0])
            controller.set("q", plant.get("q"))
            controller.set("qd", plant.get("qd"))
            controller.fmu.doStep(t, STEP, noSetFMUStatePriorToCurrentPoint=False)
            tau = controller.get("tau")
            if k == round(6.0 / STEP):
                break
            plant.set("tau", tau)
            plant.fmu.doStep(t, STEP, noSetFMUStatePriorToCurrentPoint=False)
        return energies

    # The first run sets the inputs at k0 > 0 as rerun does: same sequence.
    first = trace[k0:]
    restored = rerun(lambda: (plant.fmu.setFMUState(plant_state), controller.fmu.setFMUState(controller_state)))
    assert restored == first, "restored run differs"

    def from_bytes():
        plant.fmu.setFMUState(plant.fmu.deserializeFMUState(serialized[0]))
        controller.fmu.setFMUState(controller.fmu.deserializeFMUState(serialized[1]))

    assert rerun(from_bytes) == first, "deserialized run differs"
    FIGURES.append(f"fmpy FMI 3.0 state: saved at 3 s, {len(first)} samples after restore and after "
                   f"deserialization ({len(serialized[1])} bytes) identical to the first run")


def test_an_exported_robot_as_fmi3_closes_the_loop(eigenmpc_cli, tmp_path):
    """`eigenmpc export --fmi 2,3` of the 4-link example: the FMI 3.0 pair
    validates and closes the loop under FMU3Slave with the FMI 2.0 pair's
    figures (band 3.950 s, tests/python/test_export.py and tests/c)."""
    run = subprocess.run([str(eigenmpc_cli), "export", "--model", str(ROOT / "robots/examples/four-link-rigid.yml"),
                          "--energy", "1", "--out", str(tmp_path), "--fmi", "2,3"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    controller, plant = (str(tmp_path / "fmi3" / f"FourLinkRigid{k}.fmu") for k in ("EigenMPC", "Plant"))
    for path in (controller, plant):
        assert validate_fmu(path) == [], path
    p, c, e_ref, trace, _ = closed_loop(controller, plant, 15.0)
    FIGURES.append(f"fmpy FMI 3.0, exported FourLinkRigid (4 joints), 15 s: 5 % band for good at "
                   f"{band_time(trace, e_ref):.3f} s, E = {trace[-1]:.6f} J")
    assert band_time(trace, e_ref) == pytest.approx(3.950, abs=1e-9)
    assert trace[-1] == pytest.approx(0.999478, abs=1e-6)
