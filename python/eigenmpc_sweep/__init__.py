"""EigenMPC parameter sweeps on Dask: the `eigenmpc sweep` specs run with the
FMUs under fmpy (see README.md)."""

from .spec import Spec, expand
from .closed_loop import METRICS, run_closed_loop
from .dask_runner import run_sweep, write_results

__all__ = ["Spec", "expand", "METRICS", "run_closed_loop", "run_sweep", "write_results"]
