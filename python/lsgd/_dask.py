"""lsgd.sweep(client=...): a sweep's cells on a Dask cluster (issue 34).

The grid is expanded and every dataset, point and cell checked here, in the
client, exactly as lsgd.sweep checks them without a client; then each cell
(one configuration on one dataset: a run and its evaluation) is a Dask task.
A worker runs it with the same library call as a local sweep
(eval::run_sweep_cell), from the dataset's spec and the cell's whole options
as YAML, so a row is the local row (times aside). Workers read the datasets
at the paths the client names (a shared file system, or the same files on
every machine) and import the same lsgd (checked: a worker with another
build is an error naming it).
"""

import uuid

from . import _lsgd


def _run_cell(dataset_spec, options, label, strict, commit):
    """One cell, on a worker (pickled by reference: lsgd._dask._run_cell)."""
    if commit != _lsgd.__commit__:
        raise _lsgd.Error(f"{label}: this worker's lsgd is commit {_lsgd.__commit__}, the client's "
                          f"{commit}: run the same build everywhere (PYTHONPATH on the workers)")
    try:
        return _lsgd._sweep_cell(dataset_spec, options, label, strict)
    except _lsgd.Error as error:
        where = _worker_address()
        if where:
            raise type(error)(f"{error} (on worker {where})") from None
        raise


def _worker_address():
    try:
        from distributed import get_worker
        return get_worker().address
    except (ImportError, ValueError):
        return ""


# How long a sweep waits for its cluster's first worker before it says so.
WORKER_WAIT_S = 30


def sweep(client, datasets, sets, options, jobs, strict):
    """lsgd.sweep's rows, each cell run as a task of `client` (a distributed.Client)."""
    if not (callable(getattr(client, "submit", None)) and callable(getattr(client, "wait_for_workers", None))):
        raise _lsgd.InvalidArgument(
            f"lsgd.sweep: client is a {type(client).__name__}, not a distributed.Client "
            "(distributed.Client('tcp://HOST:8786') for a scheduler, or a LocalCluster's)")
    plan = _lsgd._sweep_plan(list(datasets), list(sets), options, jobs)
    # A cluster without a worker would run nothing and say nothing.
    try:
        client.wait_for_workers(1, timeout=WORKER_WAIT_S)
    except (TimeoutError, OSError) as error:
        address = getattr(getattr(client, "scheduler", None), "address", "") or "the scheduler"
        raise _lsgd.Error(f"lsgd.sweep: the Dask cluster at {address} has had no worker for "
                          f"{WORKER_WAIT_S} s (start one: dask worker {address})") from error
    try:
        from distributed import as_completed
    except ImportError as error:  # a client was given, so Dask is there; keep the message clear
        raise _lsgd.Error("lsgd.sweep(client=...) needs Dask distributed "
                          "(Debian: python3-distributed)") from error
    run = f"lsgd-sweep-{uuid.uuid4().hex}"
    futures = [client.submit(_run_cell, cell["dataset_spec"], cell["options"], cell["label"], strict,
                             _lsgd.__commit__, key=f"{run}-{i}", pure=False, priority=-i)
               for i, cell in enumerate(plan)]
    index = {f.key: i for i, f in enumerate(futures)}
    measured = [None] * len(plan)
    try:
        # As sweep without a client: after a failure no new cell starts (the
        # others are cancelled), and the first failure is raised, naming its cell.
        for future in as_completed(futures):
            measured[index[future.key]] = future.result()
    finally:
        client.cancel([f for f in futures if not f.done()])
    rows = []
    for cell, values in zip(plan, measured):
        row = {"dataset": cell["dataset"], "values": cell["values"]}
        row.update(values)
        rows.append(row)
    return rows
