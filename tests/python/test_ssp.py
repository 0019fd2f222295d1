"""The shipped SSP archives (target/fmu/*.ssp, written by fmu-build): the
controller and plant FMUs with their connections and start state, run by
two SSP importers: fmpy's `simulate_ssp` and ecos (ecospy)."""

import numpy as np
import pytest
from fmpy.ssp.simulation import simulate_ssp
from fmpy.ssp.ssd import Parameter, ParameterSet, read_ssd

from conftest import FIGURES, fmu_dir

DT = 0.025
LOOPS = {"EigenMPC-DoublePendulum": (2, 30.0), "EigenMPC3-TriplePendulum": (3, 60.0)}


def ssp_path(name):
    path = fmu_dir() / f"{name}.ssp"
    if not path.exists():
        pytest.fail(f"{path} missing: run `cargo run -p fmu-build` first")
    return path


def start_parameters(ssd):
    """The components' inline start values, named as fmpy's master wants
    (`component.variable`)."""
    params = ParameterSet(name="initialValues")
    for component in ssd.system.elements:
        for binding in component.parameterBindings:
            for values in binding.parameterValues:
                for p in values.parameters:
                    params.parameters.append(Parameter(name=f"{component.name}.{p.name}", type=p.type, value=p.value))
    return params


@pytest.mark.parametrize("name", LOOPS)
def test_the_ssp_is_valid_and_complete(name):
    ssd = read_ssd(str(ssp_path(name)))  # validates against the SSP 1.0 schema
    joints, _ = LOOPS[name]
    assert [c.name for c in ssd.system.elements] == ["controller", "plant"]
    connections = {(c.startElement, c.startConnector, c.endElement, c.endConnector) for c in ssd.system.connections}
    state = [f"q[{j}]" for j in range(1, joints + 1)] + [f"qd[{j}]" for j in range(1, joints + 1)]
    torques = [f"tau[{j}]" for j in range(1, joints + 1)]
    assert connections == {("plant", n, "controller", n) for n in state} | {
        ("controller", n, "plant", n) for n in torques
    }
    starts = {p.name: float(p.value) for p in start_parameters(ssd).parameters}
    assert starts == {f"controller.q[{j}]": 0.05 for j in range(1, joints + 1)} | {
        f"plant.q0[{j}]": 0.05 for j in range(1, joints + 1)
    }


def check_loop(name, times, energy, tau, importer):
    """The paper's 14 J scenario: the plant ends on its mode, nearly torque-free."""
    tail = times > times[-1] - 5.0 + 1e-9
    rms = np.sqrt(np.mean(tau[tail] ** 2, axis=0))
    FIGURES.append(
        f"{importer} runs {name}.ssp, {times[-1]:.0f} s: E = {energy[-1]:.4f} J, "
        f"RMS torque last 5 s = {' / '.join(f'{r:.4f}' for r in rms)} N m"
    )
    assert abs(energy[-1] - 14.0) < 0.05 * 14.0
    assert np.all(np.abs(energy[tail] - 14.0) < 0.05 * 14.0)
    assert np.all(rms < 0.05)


@pytest.mark.parametrize("name", LOOPS)
def test_fmpy_runs_the_ssp(name):
    path = str(ssp_path(name))
    joints, seconds = LOOPS[name]
    result = simulate_ssp(path, stop_time=seconds, step_size=DT, parameter_set=start_parameters(read_ssd(path)))
    tau = np.column_stack([result[f"controller.tau[{j}]"] for j in range(1, joints + 1)])
    check_loop(name, result["time"], result["plant.energy"], tau, "fmpy simulate_ssp")


@pytest.mark.parametrize("name", LOOPS)
def test_ecos_runs_the_ssp(name):
    ecospy = pytest.importorskip("ecospy")
    joints, seconds = LOOPS[name]
    times, energy, tau = [], [], []
    with ecospy.EcosSimulation(ssp_path=str(ssp_path(name)), step_size=DT) as sim:
        sim.init(parameter_set="initialValues")
        # The start state reached the plant.
        assert sim.get_real("plant::q[1]") == 0.05
        for _ in range(round(seconds / DT)):
            sim.step(1)
            times.append(sim.get_time())
            energy.append(sim.get_real("plant::energy"))
            tau.append([sim.get_real(f"controller::tau[{j}]") for j in range(1, joints + 1)])
    check_loop(name, np.array(times), np.array(energy), np.array(tau), "ecos")
