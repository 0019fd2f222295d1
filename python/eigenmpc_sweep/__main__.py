"""`eigenmpc-sweep --spec FILE`: an `eigenmpc sweep` spec on a Dask cluster."""

import argparse
import sys
import time

from .dask_runner import run_sweep, write_results
from .spec import Spec, expand


def main(argv=None):
    parser = argparse.ArgumentParser(prog="eigenmpc-sweep", description=__doc__)
    parser.add_argument("--spec", required=True, help="sweep spec, TOML or JSON (as for `eigenmpc sweep`)")
    parser.add_argument("--fmu-dir", default="target/fmu", help="folder with EigenMPC.fmu and DoublePendulum.fmu")
    parser.add_argument("--scheduler", help="address of an existing Dask scheduler (default: a local cluster)")
    parser.add_argument("--workers", type=int, help="worker processes of the local cluster (default: the cores)")
    parser.add_argument("--out", default="target/dask-sweep", help="output folder: sweep.csv, sweep.json")
    args = parser.parse_args(argv)
    from dask.distributed import Client, LocalCluster

    try:
        spec = Spec.load(args.spec)
        runs = expand(spec)
    except (OSError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    if args.scheduler:
        client = Client(args.scheduler)
    else:
        client = Client(LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True))
    with client:
        start = time.perf_counter()
        rows = run_sweep(spec, args.fmu_dir, client)
        wall = time.perf_counter() - start
        threads = sum(client.nthreads().values())
    write_results(spec, rows, args.out)
    failed = sum(1 for _, m, _ in rows if m is None)
    print(
        f"{len(runs)} runs of {spec.duration} s in {wall:.2f} s on {threads} Dask worker thread(s): "
        f"{len(runs) / wall / threads:.2f} runs/s per thread" + (f"; {failed} failed" if failed else "")
    )
    print(f"wrote {args.out}/sweep.csv, sweep.json")
    return 0


if __name__ == "__main__":
    sys.exit(main())
