"""The Dask runner of chunked studies: a LocalCluster of processes by default, any cluster by address.

Work goes out as one task per chunk (``task(*args_k)``, a picklable top-level function); each result
is handed to ``sink(k, result)`` on the client as soon as its chunk finishes (the caller writes it,
atomically, one file per chunk), so an interrupted study keeps every finished chunk and a rerun
passes them in ``done`` to skip them. A worker that dies mid-chunk loses only that chunk's task, which
the scheduler runs again elsewhere (``allowed-failures``); the sink receives each chunk exactly once.
Nothing here keeps process-global state: workers get everything in the task's arguments.
"""

from __future__ import annotations

import os
import uuid
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING

from tqdm import tqdm

from pressfit.errors import PressfitError

if TYPE_CHECKING:
    from distributed import Client


class ClusterError(PressfitError):
    """The Dask cluster cannot be started or reached, or a chunk failed on it."""


def default_workers() -> int:
    """One single-threaded worker process per core available to this process."""
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1)


def _client(workers: int | None, scheduler: str | None) -> Client:
    from distributed import Client, LocalCluster

    if scheduler is not None:
        if workers is not None:
            raise ClusterError("give either a number of workers or a scheduler address, not both")
        try:
            return Client(scheduler, timeout="20s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise ClusterError(f"cannot reach the Dask scheduler at {scheduler!r}: {exc}") from None
    n = workers or default_workers()
    if n < 1:
        raise ClusterError(f"the number of workers must be at least 1, got {n}")
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0",
                           silence_logs=40, env={"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"})
    return Client(cluster)


@contextmanager
def connect(workers: int | None = None, scheduler: str | None = None) -> Iterator[Client]:
    """A Dask client for a study: a LocalCluster of ``workers`` single-threaded processes (default: one per
    core), or the running cluster at ``scheduler`` (``tcp://host:port``); a local cluster is closed on exit."""
    client = _client(workers, scheduler)
    try:
        yield client
    finally:
        client.close()
        if scheduler is None:
            client.cluster.close()


def run_chunks(task: Callable[..., object], chunk_args: Sequence[tuple], sizes: Sequence[int],
               sink: Callable[[int, object], None], *, done: frozenset[int] = frozenset(),
               workers: int | None = None, scheduler: str | None = None, progress: bool = True,
               name: str = "chunk", client: Client | None = None) -> int:
    """Run ``task(*chunk_args[k])`` for every chunk k not in ``done`` on Dask and hand each result to
    ``sink(k, result)`` as it completes; ``sizes[k]`` is chunk k's number of samples (for the progress bar
    over samples). ``client``: an open :func:`connect` client (studies that run several rounds); else one is
    opened for ``workers`` (processes of a LocalCluster, default one per core) or ``scheduler``
    (``tcp://host:port`` of a running cluster). Returns the number of chunks run."""
    todo = [k for k in range(len(chunk_args)) if k not in done]
    if not todo:
        return 0
    if client is None:
        with connect(workers, scheduler) as c:
            return _run(c, task, chunk_args, sizes, sink, todo, progress, name)
    return _run(client, task, chunk_args, sizes, sink, todo, progress, name)


def _run(client: Client, task: Callable[..., object], chunk_args: Sequence[tuple], sizes: Sequence[int],
         sink: Callable[[int, object], None], todo: list[int], progress: bool, name: str) -> int:
    from distributed import as_completed

    token = uuid.uuid4().hex[:8]  # keys unique per run: a shared cluster never mixes two studies
    futures = {client.submit(task, *chunk_args[k], key=f"{name}-{token}-{k}", pure=False): k for k in todo}
    try:
        with tqdm(total=int(sum(sizes)), initial=int(sum(sizes)) - int(sum(sizes[k] for k in todo)), unit="sample",
                  disable=not progress, desc=name) as bar:
            # results fetched on the client's event loop (a fut.result() from this thread can race with the
            # rescheduling of a chunk whose worker died: "Event bound to a different event loop")
            for fut, result in as_completed(futures, with_results=True, raise_errors=False):
                k = futures[fut]
                if fut.status == "error":
                    raise ClusterError(f"{name} {k} failed on the cluster: {result!r}")
                sink(k, result)
                bar.update(sizes[k])
    finally:
        client.cancel(list(futures))
    return len(todo)
