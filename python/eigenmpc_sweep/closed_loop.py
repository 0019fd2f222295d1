"""One closed loop of the controller FMU and the plant FMU under fmpy, with
the imperfections of `eigenmpc::robustness::run_imperfect` (the native
sweep's loop): measurement delay and noise, motor responsiveness, torque
noise, in the same order and from the same random stream; and its metrics,
computed as `eigenmpc::mpc::closed_loop::summarise` does."""

import math
from collections import deque

import numpy as np
from fmpy import read_model_description
from fmpy.fmi2 import FMU2Slave

from .spec import WINDOW, XorShift, start_values

# The CSV's metric columns, in the native order.
METRICS = (
    "time_to_band",
    "success",
    "final_energy_error",
    "mean_energy_error",
    "rms_torque_1",
    "rms_torque_2",
    "distance_to_mode",
    "failed_solves",
    "model_updates",
    "solve_time_median",
    "solve_time_p99",
)
STATE = ("q[1]", "q[2]", "qd[1]", "qd[2]")
TORQUE = ("tau[1]", "tau[2]")
# The native loop integrates the plant with rtol = atol = 1e-10.
PLANT_TOLERANCES = {"rtol": 1e-10, "atol": 1e-10}


class Instance:
    """An FMU instance with name-based access."""

    def __init__(self, unzipdir, name):
        self.md = read_model_description(f"{unzipdir}/modelDescription.xml")
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.type = {v.name: v.type for v in self.md.modelVariables}
        self.fmu = FMU2Slave(
            guid=self.md.guid,
            unzipDirectory=str(unzipdir),
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self.fmu.instantiate()
        self.used = False

    def set(self, values):
        for name, value in values.items():
            if name not in self.vr:
                raise ValueError(f"{name} is not a variable of {self.md.modelName}")
            vr, kind = [self.vr[name]], self.type[name]
            if kind == "Real":
                self.fmu.setReal(vr, [float(value)])
            elif kind == "Boolean":
                self.fmu.setBoolean(vr, [bool(value)])
            else:
                if value != int(value):
                    raise ValueError(f"{name} = {value} must be an integer")
                self.fmu.setInteger(vr, [int(value)])

    def reals(self, names):
        return self.fmu.getReal([self.vr[n] for n in names])

    def integer(self, name):
        return self.fmu.getInteger([self.vr[name]])[0]

    def start(self):
        """Back to the start values (fmi2Reset) for a new run."""
        if self.used:
            self.fmu.reset()
        self.used = True

    def free(self):
        self.fmu.freeInstance()


def quantile(sorted_values, p):
    """Nearest rank, as the native `quantile`."""
    if not sorted_values:
        return math.nan
    idx = min(max(math.ceil(p * len(sorted_values)), 1), len(sorted_values)) - 1
    return sorted_values[idx]


def run_closed_loop(controller, plant, spec, run):
    """Runs `run` of `spec` on the two instances; returns the metrics (dict)."""
    ctrl_values, plant_values, imp = start_values(spec, run)
    plant.start()
    plant.set({**PLANT_TOLERANCES, **plant_values})
    plant.fmu.setupExperiment(startTime=0.0)
    plant.fmu.enterInitializationMode()
    plant.fmu.exitInitializationMode()
    noise = XorShift(int(spec.noise_seed))
    z0 = plant.reals(STATE)
    history = deque([list(z0)] * imp["delay"])
    sigma = imp["measurement_noise"]

    def measure(z):
        history.append(list(z))
        seen = history.popleft()
        if sigma > 0.0:
            return [v + sigma * noise.sample() for v in seen]
        return seen

    measured = measure(z0)
    controller.start()
    controller.set(ctrl_values)
    controller.fmu.setupExperiment(startTime=0.0)
    controller.fmu.enterInitializationMode()
    # The first solve (at initialization) takes the first measurement.
    controller.fmu.setReal([controller.vr[n] for n in STATE], measured)
    controller.fmu.exitInitializationMode()
    dt, e_ref = controller.reals(["sample_period", "E_ref"])
    steps = round(spec.duration / dt)
    a = imp["responsiveness"]
    applied = [0.0, 0.0]
    times, energies, torques, statuses, solve_times = [], [], [], [], []
    vr_in = [controller.vr[n] for n in STATE]
    vr_tau = [controller.vr[n] for n in TORQUE]
    vr_plant_tau = [plant.vr[n] for n in TORQUE]
    for i in range(steps + 1):
        t = i * dt
        if i > 0:
            measured = measure(plant.reals(STATE))
            controller.fmu.setReal(vr_in, measured)
        controller.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=dt)
        tau = controller.fmu.getReal(vr_tau)
        applied = [c * a + p * (1.0 - a) for c, p in zip(tau, applied)]
        torque = list(applied)
        if imp["torque_noise"] > 0.0:
            torque = [v + imp["torque_noise"] * noise.sample() for v in torque]
        times.append(t)
        energies.append(plant.reals(["energy"])[0])
        torques.append(torque)
        statuses.append(controller.integer("solver_status"))
        solve_times.append(controller.reals(["solve_time"])[0])
        if i == steps:
            break
        plant.fmu.setReal(vr_plant_tau, torque)
        plant.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=dt)
    return metrics(
        np.array(times), np.array(energies), np.array(torques), statuses, solve_times, e_ref, spec.duration,
        controller.integer("model_updates"),
    )


def metrics(times, energies, torques, statuses, solve_times, e_ref, duration, model_updates):
    band = 0.05 * abs(e_ref)
    outside = np.nonzero(~(np.abs(energies - e_ref) < band))[0]
    if len(outside) == 0:
        time_to_band = float(times[0])
    elif outside[-1] + 1 < len(times):
        time_to_band = float(times[outside[-1] + 1])
    else:
        time_to_band = None
    tail = times > times[-1] - WINDOW + 1e-9
    mean = float(np.mean(energies[tail]))
    rms = np.sqrt(np.mean(torques[tail] ** 2, axis=0))
    ordered = sorted(solve_times)
    return {
        "time_to_band": time_to_band,
        "success": time_to_band is not None and time_to_band <= duration - WINDOW + 1e-9,
        "final_energy_error": float(energies[-1] - e_ref),
        "mean_energy_error": (mean - e_ref) / e_ref,
        "rms_torque_1": float(rms[0]),
        "rms_torque_2": float(rms[1]),
        # Needs the eigenmode engine, which the FMUs do not expose.
        "distance_to_mode": None,
        "failed_solves": sum(1 for s in statuses if s >= 2),
        "model_updates": int(model_updates),
        "solve_time_median": quantile(ordered, 0.5),
        "solve_time_p99": quantile(ordered, 0.99),
    }
