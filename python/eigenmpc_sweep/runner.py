"""The sweep on a Dask cluster, computed by the Rust sweep itself.

`eigenmpc sweep --plan` says how many runs the spec has; each Dask task runs
a contiguous part of them with `eigenmpc sweep --only FROM..TO` (the spec's
expansion, its random sample, the closed loop and the metrics are the Rust
sweep's, for any robot file it takes) and returns its records; `eigenmpc
sweep --from-rows` merges them into the outputs a local sweep writes
(sweep.csv, sweep.json, the plots). Nothing of the sweep is computed here.
"""

import json
import os
import pathlib
import shutil
import subprocess


class SweepError(RuntimeError):
    """`eigenmpc` refused the spec or a part failed: its message."""


def eigenmpc_binary(path=None):
    """The `eigenmpc` executable: `path`, else `$EIGENMPC`, else `eigenmpc` on PATH."""
    candidate = path or os.environ.get("EIGENMPC") or shutil.which("eigenmpc")
    if not candidate or not os.path.exists(candidate):
        raise FileNotFoundError(
            f"eigenmpc not found ({candidate or 'not on PATH'}): build it with "
            "`cargo build --release --bin eigenmpc`, pass --eigenmpc or set EIGENMPC"
        )
    return str(pathlib.Path(candidate).resolve())


def _eigenmpc(binary, *args):
    out = subprocess.run([binary, *args], capture_output=True, text=True)
    if out.returncode != 0:
        raise SweepError(out.stderr.strip() or f"eigenmpc exited with {out.returncode}")
    return out.stdout


def plan(spec, binary):
    """`{"runs": count, "joints": n, "swept": [names]}` of the spec file."""
    return json.loads(_eigenmpc(binary, "sweep", "--spec", str(spec), "--plan"))


def run_part(binary, spec, start, stop):
    """The records (JSON text) of runs `start` to `stop - 1`, on one thread."""
    return _eigenmpc(
        binary, "sweep", "--spec", str(spec), "--only", f"{start}..{stop}", "--rows-out", "-", "--threads", "1"
    )


def parts(runs, partitions):
    """`partitions` contiguous `(start, stop)` ranges covering `runs` runs."""
    partitions = max(1, min(partitions, runs))
    size = -(-runs // partitions)
    return [(k, min(k + size, runs)) for k in range(0, runs, size)]


def run_sweep(spec, client, out, binary=None, partitions=None):
    """Runs the spec file on the Dask `client`'s cluster and writes the sweep's
    outputs to `out`; returns `eigenmpc`'s summary line. The workers need the
    `eigenmpc` binary and the spec (and its robot file) at the same paths."""
    binary = eigenmpc_binary(binary)
    spec = pathlib.Path(spec).resolve()
    runs = plan(spec, binary)["runs"]
    if partitions is None:
        partitions = max(1, sum(client.nthreads().values()))
    ranges = parts(runs, partitions)
    futures = client.map(
        run_part,
        [binary] * len(ranges),
        [str(spec)] * len(ranges),
        [a for a, _ in ranges],
        [b for _, b in ranges],
        pure=False,
    )
    texts = client.gather(futures)
    out = pathlib.Path(out)
    records = out / "records"
    records.mkdir(parents=True, exist_ok=True)
    args = []
    for (a, b), text in zip(ranges, texts):
        path = records / f"runs-{a}-{b}.json"
        path.write_text(text)
        args += ["--from-rows", str(path)]
    return _eigenmpc(binary, "sweep", "--spec", str(spec), *args, "--out", str(out)).strip()
