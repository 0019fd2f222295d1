"""The DoublePendulum FMU under fmpy and libcosim."""

import math

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import fmi2FMUstate
from fmpy.validation import validate_fmu

from fmi_host import Slave, pendulum_energy

SWING = {"q0[1]": 1.2, "q0[2]": -0.7, "qd0[1]": 0.5, "qd0[2]": 1.5}
E0 = pendulum_energy(1.2, -0.7, 0.5, 1.5)
FMI2_ERROR = 3


def test_validates_without_problems(plant_fmu):
    assert validate_fmu(str(plant_fmu)) == []


def test_model_structure(plant_md):
    names = {v.name: v for v in plant_md.modelVariables}
    outputs = [u.variable.name for u in plant_md.outputs]
    assert outputs == ["q[1]", "q[2]", "qd[1]", "qd[2]", "energy"]
    # co-simulation: no direct feedthrough from the torques
    assert all(u.dependencies == [] for u in plant_md.outputs)
    initial = {u.variable.name: sorted(d.name for d in u.dependencies) for u in plant_md.initialUnknowns}
    assert initial["q[1]"] == ["q0[1]"]
    assert initial["qd[2]"] == ["qd0[2]"]
    assert "damping[1]" not in initial["energy"] and "b[1]" not in initial["energy"]
    assert "g" in initial["energy"] and "I[2]" in initial["energy"] and "Ir[1]" in initial["energy"]
    assert names["tau[1]"].causality == "input" and names["tau[1]"].unit == "N.m"
    assert names["m[1]"].variability == "fixed" and float(names["m[1]"].min) > 0


def test_simulate_fmu_free_run_conserves_energy(plant_fmu):
    result = simulate_fmu(
        str(plant_fmu),
        start_values=SWING,
        stop_time=60.0,
        output_interval=0.01,
        output=["energy", "q[2]"],
    )
    assert result["time"][-1] == pytest.approx(60.0)
    assert result["energy"][0] == pytest.approx(E0, rel=1e-14)
    drift = np.max(np.abs(result["energy"] - E0)) / E0
    print(f"simulate_fmu 60 s: max relative energy drift {drift:.2e}")
    assert drift < 1e-8
    assert np.ptp(result["q[2]"]) > 1.0  # it really swings


def test_step_by_step_energy_and_work(plant_md, plant_unzipped):
    s = Slave(plant_md, plant_unzipped)
    s.initialize(SWING)
    (e,) = s.get("energy")
    assert e == pytest.approx(E0, rel=1e-14)
    worst = 0.0
    for _ in range(6000):
        s.step(0.01)
        worst = max(worst, abs(s.get("energy")[0] - E0) / E0)
    assert worst < 1e-8
    # torques held over a step do work tau . dq, which is the energy gain
    e_start = s.get("energy")[0]
    work = 0.0
    for k in range(300):
        tau = [2.0 * math.sin(0.3 * k), -1.5 * math.cos(0.2 * k)]
        s.set_named({"tau[1]": tau[0], "tau[2]": tau[1]})
        before = s.get("q[1]", "q[2]")
        s.step(0.02)
        after = s.get("q[1]", "q[2]")
        work += tau[0] * (after[0] - before[0]) + tau[1] * (after[1] - before[1])
    gain = s.get("energy")[0] - e_start
    assert abs(gain) > 0.05
    assert gain == pytest.approx(work, abs=1e-8 * E0)
    s.fmu.terminate()
    s.free()


def expect_error(s, call, *needles):
    with pytest.raises(FMICallException) as info:
        call()
    assert info.value.status == FMI2_ERROR
    assert s.logged(*needles), s.messages


def test_bad_calls_are_errors_not_crashes(plant_md, plant_unzipped):
    s = Slave(plant_md, plant_unzipped)
    expect_error(s, lambda: s.step(0.01), "fmi2DoStep", "not allowed in state instantiated")
    s.fmu.reset()
    expect_error(s, lambda: s.fmu.setReal([999], [0.0]), "unknown Real value reference 999")
    s.fmu.reset()
    expect_error(s, lambda: s.set_named({"tau[1]": float("nan")}), "tau[1] = NaN is not a finite number")
    s.fmu.reset()
    expect_error(s, lambda: s.set_named({"m[1]": 0.0}), "m[1] = 0 is below its minimum")
    s.fmu.reset()
    expect_error(s, lambda: s.fmu.getReal([s.vr["q[1]"]]), "not allowed in state instantiated")
    s.fmu.reset()
    s.initialize(SWING)
    expect_error(s, lambda: s.set_named({"l[1]": 2.0}), "l[1]", "cannot be set in state stepComplete")
    s.fmu.reset()
    s.initialize(SWING)
    expect_error(s, lambda: s.fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=-0.1), "must be finite and > 0")
    s.fmu.reset()
    s.initialize(SWING)
    expect_error(
        s,
        lambda: s.fmu.getDirectionalDerivative([s.vr["q[1]"]], [s.vr["tau[1]"]], [1.0]),
        "fmi2GetDirectionalDerivative: not supported",
    )
    s.fmu.reset()
    s.initialize(SWING)
    # A pointer that is not one of this FMU's states is refused, not used.
    expect_error(s, lambda: s.fmu.setFMUstate(fmi2FMUstate(0x1234)), "fmi2SetFMUstate", "not a live state")
    # after all that, the instance still works
    s.fmu.reset()
    s.initialize(SWING)
    s.step(0.1)
    assert s.get("energy")[0] == pytest.approx(E0, rel=1e-9)
    s.free()


def test_instances_are_independent(plant_md, plant_unzipped):
    a = Slave(plant_md, plant_unzipped, "a")
    b = Slave(plant_md, plant_unzipped, "b")
    a.initialize(SWING)
    b.initialize({"q0[1]": 0.3})
    for _ in range(100):
        a.step(0.01)
        b.step(0.01)
    assert a.get("energy")[0] == pytest.approx(E0, rel=1e-9)
    assert b.get("energy")[0] == pytest.approx(pendulum_energy(0.3, 0, 0, 0), rel=1e-9)
    a.free()
    b.free()


def test_runs_under_libcosim(plant_fmu, plant_md):
    libcosimpy = pytest.importorskip("libcosimpy")
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    vr = {v.name: v.valueReference for v in plant_md.modelVariables}
    step_ns = 10_000_000  # 10 ms
    execution = CosimExecution.from_step_size(step_size=step_ns)
    slave = CosimLocalSlave(fmu_path=str(plant_fmu), instance_name="pendulum")
    index = execution.add_local_slave(local_slave=slave)
    for name, value in SWING.items():
        assert execution.real_initial_value(index, vr[name], value)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer=observer)
    assert execution.simulate_until(target_time=20 * 10**9)
    q1, q2, w1, w2, energy = observer.last_real_values(
        index, [vr["q[1]"], vr["q[2]"], vr["qd[1]"], vr["qd[2]"], vr["energy"]]
    )
    assert execution.status().current_time == 20 * 10**9
    assert energy == pytest.approx(E0, rel=1e-8)
    # the reported state is consistent with the reported energy
    assert pendulum_energy(q1, q2, w1, w2) == pytest.approx(energy, rel=1e-12)
    assert (q1, q2) != (SWING["q0[1]"], SWING["q0[2]"])
    del libcosimpy
