"""A small fmpy-based host used by the tests: instance with a log capture."""

import math
from ctypes import byref

from fmpy.fmi2 import (
    FMU2Slave,
    calloc,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    free,
)
from fmpy.logging import addLoggerProxy


class Slave:
    """An FMU2Slave whose log messages are recorded in `messages`."""

    def __init__(self, md, unzipdir, name="instance", logging_on=False):
        self.md = md
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.type = {v.name: v.type for v in md.modelVariables}
        self.messages = []

        def logger(_env, _name, status, category, message):
            self.messages.append((status, category.decode(), message.decode()))

        # Keep the ctypes callbacks alive as long as the instance.
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(logger)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        addLoggerProxy(byref(self.callbacks))
        self.fmu = FMU2Slave(
            guid=md.guid,
            unzipDirectory=str(unzipdir),
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self.fmu.instantiate(callbacks=self.callbacks, loggingOn=logging_on)
        self.time = 0.0

    def set_named(self, values: dict):
        """Sets Real, Integer / Enumeration (start-value files hold both) and Boolean values."""
        reals = {n: v for n, v in values.items() if self.type[n] == "Real"}
        booleans = {n: bool(v) for n, v in values.items() if self.type[n] == "Boolean"}
        integers = {n: int(v) for n, v in values.items() if self.type[n] in ("Integer", "Enumeration")}
        if reals:
            self.fmu.setReal([self.vr[n] for n in reals], list(reals.values()))
        if integers:
            self.fmu.setInteger([self.vr[n] for n in integers], list(integers.values()))
        if booleans:
            self.fmu.setBoolean([self.vr[n] for n in booleans], list(booleans.values()))

    def get(self, *names):
        return self.fmu.getReal([self.vr[n] for n in names])

    def initialize(self, start_values=None):
        self.fmu.setupExperiment(startTime=0.0)
        if start_values:
            self.set_named(start_values)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        self.time = 0.0

    def step(self, h):
        self.fmu.doStep(currentCommunicationPoint=self.time, communicationStepSize=h)
        self.time += h

    def logged(self, *needles):
        return any(all(n in m for n in needles) for _, _, m in self.messages)

    def free(self):
        self.fmu.freeInstance()


def pendulum_energy(q1, q2, w1, w2, m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=9.81):
    """Energy of the double pendulum (paper, section V), zero hanging at rest."""
    v = g * (m1 + m2) * l1 * (1 - math.cos(q1)) + g * m2 * l2 * (1 - math.cos(q1 + q2))
    c = math.cos(q2)
    m11 = (m1 + m2) * l1**2 + m2 * l2**2 + 2 * m2 * l1 * l2 * c
    m12 = m2 * l2**2 + m2 * l1 * l2 * c
    m22 = m2 * l2**2
    return v + 0.5 * (m11 * w1 * w1 + 2 * m12 * w1 * w2 + m22 * w2 * w2)
