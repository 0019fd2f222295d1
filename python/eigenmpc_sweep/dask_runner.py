"""The sweep on a Dask cluster: the runs split into contiguous partitions,
one pair of FMU instances per partition (fmi2Reset between runs), each FMU
unzipped once per worker machine; results in the order of the spec."""

import hashlib
import json
import os
import pathlib
import shutil
import tempfile

from fmpy import extract

from .closed_loop import METRICS, Instance, run_closed_loop
from .spec import Spec, expand


def unzipped(fmu_path):
    """The FMU's unzip directory, shared by the worker processes of a machine."""
    data = pathlib.Path(fmu_path).read_bytes()
    digest = hashlib.sha256(data).hexdigest()[:16]
    target = pathlib.Path(tempfile.gettempdir()) / f"eigenmpc-sweep-{digest}"
    if not (target / "modelDescription.xml").exists():
        scratch = pathlib.Path(tempfile.mkdtemp(prefix="eigenmpc-sweep-"))
        extract(str(fmu_path), unzipdir=str(scratch))
        try:
            os.rename(scratch, target)  # atomic: another process may have won
        except OSError:
            shutil.rmtree(scratch, ignore_errors=True)
    return target


def run_partition(fmu_paths, spec, indexed_runs):
    """Runs `(index, run)` pairs on one controller/plant pair."""
    controller = Instance(unzipped(fmu_paths[0]), "controller")
    plant = Instance(unzipped(fmu_paths[1]), "plant")
    out = []
    try:
        for index, run in indexed_runs:
            try:
                out.append((index, run, run_closed_loop(controller, plant, spec, run), None))
            except Exception as e:  # a failed run is a row with its error
                out.append((index, run, None, str(e)))
    finally:
        controller.free()
        plant.free()
    return out


def run_sweep(spec, fmu_dir, client, partitions=None):
    """The rows `(run, metrics or None, error or None)` of `spec`, computed
    on the Dask `client`'s cluster (one partition per worker thread by default)."""
    if not isinstance(spec, Spec):
        spec = Spec(**spec)
    runs = expand(spec)
    fmu_dir = pathlib.Path(fmu_dir)
    paths = [str((fmu_dir / f"{name}.fmu").resolve()) for name in ("EigenMPC", "DoublePendulum")]
    for p in paths:
        if not os.path.exists(p):
            raise FileNotFoundError(f"{p} missing: run `cargo run -p fmu-build` first")
    if partitions is None:
        partitions = max(1, sum(client.nthreads().values()))
    partitions = max(1, min(partitions, len(runs)))
    indexed = list(enumerate(runs))
    size = -(-len(indexed) // partitions)
    chunks = [indexed[k : k + size] for k in range(0, len(indexed), size)]
    futures = client.map(run_partition, [paths] * len(chunks), [spec] * len(chunks), chunks, pure=False)
    rows = sorted((row for part in client.gather(futures) for row in part), key=lambda r: r[0])
    return [(run, m, e) for _, run, m, e in rows]


def cell(v):
    """As the native CSV: whole numbers without a fraction, else the shortest round trip."""
    if v is None or (isinstance(v, float) and v != v):
        return ""
    if isinstance(v, bool):
        return "1" if v else "0"
    v = float(v)
    if v.is_integer() and abs(v) < 1e15:
        return str(int(v))
    return repr(v)


def write_results(spec, rows, out):
    """sweep.csv and sweep.json in `out`, with the native columns."""
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    swept = spec.swept()
    lines = [",".join(["run", *swept, *METRICS, "error"])]
    for i, (run, m, error) in enumerate(rows):
        cells = [str(i), *(cell(v) for _, v in run)]
        cells += [cell(m[k]) for k in METRICS] if m else [""] * len(METRICS)
        cells.append('"' + error.replace('"', '""') + '"' if error else "")
        lines.append(",".join(cells))
    (out / "sweep.csv").write_text("\n".join(lines) + "\n")
    runs = [
        {"run": i, "parameters": dict(run), **({"metrics": m} if m else {"error": error})}
        for i, (run, m, error) in enumerate(rows)
    ]
    (out / "sweep.json").write_text(json.dumps({"runs": runs}, indent=2) + "\n")
