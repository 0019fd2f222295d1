"""EigenMPC parameter sweeps on Dask: the `eigenmpc sweep` specs, split into
parts that Dask workers run with the `eigenmpc` binary (see README.md)."""

from .runner import SweepError, eigenmpc_binary, parts, plan, run_part, run_sweep

__all__ = ["SweepError", "eigenmpc_binary", "parts", "plan", "run_part", "run_sweep"]
