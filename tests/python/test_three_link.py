"""The 3-link pair EigenMPC3 / TriplePendulum under fmpy, and the plants'
start from rest at the limits of their tolerance ranges."""

import math

import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from conftest import FIGURES, fmu_path
from fmi_host import Slave

DT = 0.025
Q = ["q[1]", "q[2]", "q[3]"]
QD = ["qd[1]", "qd[2]", "qd[3]"]
TAU = ["tau[1]", "tau[2]", "tau[3]"]


@pytest.mark.parametrize("identifier", ["EigenMPC3", "TriplePendulum"])
def test_validates_without_problems(identifier):
    assert validate_fmu(str(fmu_path(identifier))) == []


def test_model_descriptions_follow_the_table(three_link_pair):
    (cmd, _), (pmd, _) = three_link_pair
    cv = {v.name: v for v in cmd.modelVariables}
    assert [v.name for v in cmd.modelVariables if v.causality == "input"] == Q + QD
    assert [u.variable.name for u in cmd.outputs][:3] == TAU
    assert cv["chart.coef[3,9]"].valueReference == 129 and cv["r[1]"].valueReference == 130
    assert float(cv["E_ref"].start) == 14.0 and cv["I[3]"].unit == "kg.m2"
    pv = {v.name: v for v in pmd.modelVariables}
    assert [v.name for v in pmd.modelVariables if v.causality == "input"] == TAU
    assert pv["damping[3]"].valueReference == 19 and float(pv["r[2]"].start) < 0


def test_curved_14_j_brings_the_chain_onto_its_mode_torque_free(three_link_pair):
    """Controller stepped before the plant, 25 ms steps, from q = 0.05 rad at rest, 60 s."""
    (cmd, cdir), (pmd, pdir) = three_link_pair
    ctrl, plant = Slave(cmd, cdir, "controller3"), Slave(pmd, pdir, "chain")
    q0 = {f"q0[{j}]": 0.05 for j in (1, 2, 3)}
    plant.initialize(q0)
    ctrl.fmu.setupExperiment(startTime=0.0)
    ctrl.fmu.enterInitializationMode()
    ctrl.set_named({f"q[{j}]": 0.05 for j in (1, 2, 3)})
    ctrl.fmu.exitInitializationMode()
    state = [plant.vr[n] for n in Q + QD]
    ctrl_state = [ctrl.vr[n] for n in Q + QD]
    tau_out, tau_in = [ctrl.vr[n] for n in TAU], [plant.vr[n] for n in TAU]
    energies, torques, statuses = [], [], []
    seconds = 60.0
    for _ in range(round(seconds / DT)):
        ctrl.fmu.setReal(ctrl_state, plant.fmu.getReal(state))
        ctrl.step(DT)
        tau = ctrl.fmu.getReal(tau_out)
        statuses.append(ctrl.fmu.getInteger([ctrl.vr["solver_status"]])[0])
        plant.fmu.setReal(tau_in, tau)
        plant.step(DT)
        energies.append(plant.get("energy")[0])
        torques.append(tau)
    band = next(
        (DT * (i + 1) for i in range(len(energies)) if all(abs(e - 14.0) < 0.7 for e in energies[i:])),
        None,
    )
    last = torques[-round(5.0 / DT):]
    rms = [math.sqrt(sum(t[j] ** 2 for t in last) / len(last)) for j in range(3)]
    FIGURES.append(
        f"fmpy, EigenMPC3 + TriplePendulum, curved 14 J from q = 0.05 rad, 60 s: 5 % band for good at "
        f"{band} s, final E = {energies[-1]:.4f} J, RMS torque last 5 s = "
        + " / ".join(f"{r:.4f}" for r in rms)
        + " N m"
    )
    assert all(s == 0 for s in statuses)
    assert band is not None and band < 50.0
    assert abs(energies[-1] - 14.0) < 0.2
    assert max(rms) < 0.03
    ctrl.free()
    plant.free()


@pytest.mark.parametrize("identifier,n", [("DoublePendulum", 2), ("TriplePendulum", 3)])
@pytest.mark.parametrize("rtol_end", ["min", "max"])
@pytest.mark.parametrize("atol_end", ["min", "max"])
def test_plant_starts_from_rest_at_the_tolerance_limits(identifier, n, rtol_end, atol_end):
    """q0 = qd0 = 0 with a saturated torque, rtol and atol at the ends of their
    ranges (from the model description): the run succeeds from its first step."""
    path = str(fmu_path(identifier))
    v = {x.name: x for x in read_model_description(path).modelVariables}
    rtol, atol = float(getattr(v["rtol"], rtol_end)), float(getattr(v["atol"], atol_end))
    assert {float(v["rtol"].min), float(v["rtol"].max)} == {1e-14, 1e-2}
    tau = {f"tau[{j}]": (1.0 if j % 2 else -1.0) for j in range(1, n + 1)}
    result = simulate_fmu(
        path,
        start_values={"rtol": rtol, "atol": atol, **tau},
        stop_time=0.1,
        output_interval=0.025,
        output=[f"qd[{j}]" for j in range(1, n + 1)] + ["energy"],
    )
    assert len(result) == 5
    # the torque did work from the first step on
    first = result[1]
    power = sum(tau[f"tau[{j}]"] * first[f"qd[{j}]"] for j in range(1, n + 1))
    assert power > 0 and first["energy"] > 0


def test_non_physical_link_is_refused_naming_the_parameter(three_link_pair):
    _, (pmd, pdir) = three_link_pair
    s = Slave(pmd, pdir, "bad")
    s.fmu.setupExperiment(startTime=0.0)
    s.set_named({"r[3]": 0.0})
    s.fmu.enterInitializationMode()
    with pytest.raises(FMICallException) as info:
        s.fmu.exitInitializationMode()
    assert info.value.status == 3
    assert s.logged("model parameter I[3] = 0 is invalid"), s.messages
    s.fmu.reset()
    with pytest.raises(FMICallException):
        s.set_named({"gr[1]": 0.0})
    assert s.logged("gr[1] = 0 is below its minimum"), s.messages
    s.free()
