"""Sweep specs and their expansion into runs, exactly as `eigenmpc sweep`
does it (cli/src/sweep/mod.rs): the grid in name order (the first name varies
slowest), then per grid point the random sample, drawn from the same
xorshift64* stream, so that both give the same runs with the same values."""

import json
import math
import pathlib
import sys
from dataclasses import dataclass, field

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

WINDOW = 5.0
# Values every run starts from (the paper's start state), as BASE in Rust.
BASE = {"plant.q0[1]": 0.05, "plant.q0[2]": 0.05}
IMPERFECTIONS = ("measurement_noise", "torque_noise", "responsiveness", "delay")
SCOPES = ("controller", "plant", "model", "imperfections")
MASK = (1 << 64) - 1


class XorShift:
    """eigenmpc::mpc::closed_loop::GaussianNoise: xorshift64* and Box-Muller."""

    def __init__(self, seed):
        self.state = seed if seed != 0 else 0x9E3779B97F4A7C15

    def uniform(self):
        x = self.state
        x ^= x >> 12
        x ^= (x << 25) & MASK
        x ^= x >> 27
        self.state = x
        y = (x * 0x2545F4914F6CDD1D) & MASK
        return ((y >> 11) + 0.5) / float(1 << 53)

    def sample(self):
        u, v = self.uniform(), self.uniform()
        return math.sqrt(-2.0 * math.log(u)) * math.cos(2.0 * math.pi * v)


def check_name(name):
    scope, dot, rest = name.partition(".")
    if not dot:
        raise ValueError(f"{name}: give the scope: controller.{name}, plant.{name}, model.{name} or imperfections.{name}")
    if scope not in SCOPES:
        raise ValueError(f"{name}: unknown scope `{scope}` (controller, plant, model, imperfections)")
    if scope == "imperfections" and rest not in IMPERFECTIONS:
        raise ValueError(f"{name}: unknown imperfection (known: {', '.join(IMPERFECTIONS)})")
    return scope, rest


def axis_values(axis):
    if isinstance(axis, list):
        return [float(v) for v in axis]
    start, stop, count = float(axis["from"]), float(axis["to"]), int(axis["count"])
    if count == 0:
        return []
    if count == 1:
        return [start]
    return [start + (stop - start) * i / (count - 1) for i in range(count)]


@dataclass
class Spec:
    duration: float = 30.0
    model: str = None
    fixed: dict = field(default_factory=dict)
    grid: dict = field(default_factory=dict)
    random: dict = None
    noise_seed: int = 1
    metric: str = None

    @classmethod
    def load(cls, path):
        path = pathlib.Path(path)
        text = path.read_text()
        data = tomllib.loads(text) if path.suffix.lower() == ".toml" else json.loads(text)
        known = {"duration", "model", "fixed", "grid", "random", "noise_seed", "metric"}
        unknown = set(data) - known
        if unknown:
            raise ValueError(f"{path}: unknown field(s) {sorted(unknown)}")
        return cls(**data)

    def swept(self):
        names = sorted(self.grid)
        if self.random:
            names += [n for n in sorted(self.random["ranges"]) if n not in self.grid]
        return names


def expand(spec):
    """The runs: per run a list of (name, value) in `spec.swept()` order."""
    if not (math.isfinite(spec.duration) and spec.duration > WINDOW):
        raise ValueError(f"duration = {spec.duration} s must be more than the {WINDOW} s scored at the end")
    if spec.model is not None:
        raise ValueError(
            "model files are not read by the Dask runner: give the robot's parameters as fixed "
            "model.<name> values (eigenmpc modes --model FILE --fmu-start-values lists them)"
        )
    for name in list(spec.fixed) + list(spec.grid):
        check_name(name)
    runs = [[]]
    for name in sorted(spec.grid):
        values = axis_values(spec.grid[name])
        if not values or not all(math.isfinite(v) for v in values):
            raise ValueError(f"grid {name}: needs at least one finite value")
        runs = [run + [(name, v)] for run in runs for v in values]
    if spec.random:
        samples = int(spec.random["samples"])
        if samples == 0:
            raise ValueError("random.samples must be at least 1")
        ranges = spec.random["ranges"]
        for name in ranges:
            check_name(name)
        rng = XorShift(int(spec.random.get("seed", 1)))
        sampled = []
        for run in runs:
            for _ in range(samples):
                r = list(run)
                for name in sorted(ranges):
                    lo, hi = float(ranges[name]["from"]), float(ranges[name]["to"])
                    r.append((name, lo + (hi - lo) * rng.uniform()))
                sampled.append(r)
        runs = sampled
    return runs


def start_values(spec, run):
    """The controller's and the plant's FMU start values and the imperfections of a run."""
    controller, plant = {}, {}
    imperfections = {"measurement_noise": 0.0, "torque_noise": 0.0, "responsiveness": 1.0, "delay": 0}
    for name, value in list(BASE.items()) + list(spec.fixed.items()) + list(run):
        scope, rest = check_name(name)
        if scope == "controller":
            controller[rest] = value
        elif scope == "plant":
            plant[rest] = value
        elif scope == "model":
            controller[rest] = value
            plant[rest] = value
        elif rest == "delay":
            if value < 0 or value != int(value):
                raise ValueError(f"{name} = {value}: a delay is a whole number of samples")
            imperfections["delay"] = int(value)
        else:
            imperfections[rest] = float(value)
    if not 0.0 < imperfections["responsiveness"] <= 1.0:
        raise ValueError(f"responsiveness = {imperfections['responsiveness']} must be in (0, 1]")
    return controller, plant, imperfections
