"""`eigenmpc-sweep --spec FILE`: an `eigenmpc sweep` spec on a Dask cluster."""

import argparse
import sys
import time

from .runner import SweepError, eigenmpc_binary, plan, run_sweep


def main(argv=None):
    parser = argparse.ArgumentParser(prog="eigenmpc-sweep", description=__doc__)
    parser.add_argument("--spec", required=True, help="sweep spec, TOML or JSON (as for `eigenmpc sweep`)")
    parser.add_argument("--eigenmpc", help="the eigenmpc binary (default: $EIGENMPC, else eigenmpc on PATH)")
    parser.add_argument("--scheduler", help="address of an existing Dask scheduler (default: a local cluster)")
    parser.add_argument("--workers", type=int, help="worker processes of the local cluster (default: the cores)")
    parser.add_argument("--out", default="target/dask-sweep", help="output folder: sweep.csv, sweep.json, plots")
    args = parser.parse_args(argv)
    try:
        binary = eigenmpc_binary(args.eigenmpc)
        runs = plan(args.spec, binary)["runs"]  # a bad spec fails here, before a cluster starts
    except (OSError, SweepError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    from dask.distributed import Client, LocalCluster

    if args.scheduler:
        client = Client(args.scheduler)
    else:
        client = Client(LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True))
    with client:
        start = time.perf_counter()
        try:
            summary = run_sweep(args.spec, client, args.out, binary)
        except SweepError as e:
            print(f"error: {e}", file=sys.stderr)
            return 1
        wall = time.perf_counter() - start
        threads = sum(client.nthreads().values())
    print(summary)
    print(f"Dask: {runs} runs in {wall:.2f} s on {threads} worker thread(s), the cluster's start excluded")
    return 0


if __name__ == "__main__":
    sys.exit(main())
