"""The Dask runner of chunked studies: a LocalCluster of processes by default, any cluster by address.

Work goes out as one task per chunk (``task(*args_k)``, a picklable top-level function), a bounded number
in flight at a time (:func:`in_flight_limit`), so a study of 1e9 samples starts at once; each result
is handed to ``sink(k, result)`` on the client as soon as its chunk finishes (the caller writes it,
atomically, one file per chunk), so an interrupted study keeps every finished chunk and a rerun
passes them in ``done`` to skip them. A worker that dies mid-chunk loses only that chunk's task, which
the scheduler runs again elsewhere (``allowed-failures``); the sink receives each chunk exactly once.
Nothing here keeps process-global state: workers get everything in the task's arguments.
"""

from __future__ import annotations

import ipaddress
import os
import sys
import uuid
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING

from tqdm import tqdm

from pressfit.errors import ClusterError

if TYPE_CHECKING:
    from distributed import Client


IN_FLIGHT_PER_THREAD = 4  # chunks queued per worker thread: keeps every worker busy, memory bounded
WORKERS_PER_CORE = 4  # a local cluster of more worker processes per core is refused before it starts


def default_workers() -> int:
    """One single-threaded worker process per core available to this process."""
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1)


def transport_warning(address: str) -> str | None:
    """The warning for a scheduler address whose traffic is unencrypted beyond this machine (``tcp://`` or
    no scheme, to a host that is not loopback), else None. ``tls://`` uses Dask's security settings
    (``distributed.comm.tls.*`` of the Dask configuration: CA file, client certificate and key)."""
    scheme, _, rest = address.rpartition("://")
    if scheme not in ("", "tcp"):
        return None
    host = rest.rsplit(":", 1)[0].strip("[]") if ":" in rest else rest
    try:
        loopback = ipaddress.ip_address(host).is_loopback
    except ValueError:
        loopback = host == "localhost"
    if loopback:
        return None
    return (f"warning: the Dask scheduler {address} is reached over plain TCP: the study's data (machine, case, "
            "samples) travel unencrypted; use tls:// with certificates in the Dask configuration")


def _client(workers: int | None, scheduler: str | None, dashboard: bool) -> Client:
    from distributed import Client, LocalCluster

    if scheduler is not None:
        if workers is not None:
            raise ClusterError("give either a number of workers or a scheduler address, not both",
                               scheduler=scheduler, workers=workers)
        if (warn := transport_warning(scheduler)) is not None:
            tqdm.write(warn, file=sys.stderr)
        try:
            return Client(scheduler, timeout="20s")
        except TypeError:  # distributed: "TLS expects a `ssl_context` argument ... Instead got None"
            cause = ("tls:// needs the client's certificates in the Dask configuration (distributed.comm.tls.ca-file, "
                     "distributed.comm.tls.client.cert, distributed.comm.tls.client.key)")
            raise ClusterError(f"cannot reach the Dask scheduler at {scheduler!r}: {cause}", scheduler=scheduler,
                               cause=cause) from None
        except (OSError, TimeoutError, ValueError) as exc:
            raise ClusterError(f"cannot reach the Dask scheduler at {scheduler!r}: {exc}", scheduler=scheduler,
                               cause=str(exc)) from None
    n, cores = workers or default_workers(), default_workers()
    if n < 1:
        raise ClusterError(f"the number of workers must be at least 1, got {n}", workers=n)
    if n > WORKERS_PER_CORE * cores:  # each worker is a process with its own model: beyond the cores they only queue
        raise ClusterError(f"--workers {n}: this machine gives the study {cores} core(s); a local cluster of more than "
                           f"{WORKERS_PER_CORE * cores} worker processes is refused (they would only share the cores); "
                           "use --scheduler for a bigger cluster", workers=n)
    # scheduler and (only when asked) dashboard on loopback: a local study opens nothing to the network. The
    # scheduler's HTTP server (health and metrics routes) starts whatever the dashboard: on a free loopback port (with
    # no address Dask takes 8787 and warns when another cluster holds it)
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                           dashboard_address="127.0.0.1:0", scheduler_kwargs={"dashboard": dashboard}, silence_logs=40,
                           env={"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"})
    client = Client(cluster)
    if dashboard:
        tqdm.write(f"Dask dashboard: {client.dashboard_link}", file=sys.stderr)
    return client


@contextmanager
def connect(workers: int | None = None, scheduler: str | None = None, dashboard: bool = False) -> Iterator[Client]:
    """A Dask client for a study: a LocalCluster of ``workers`` single-threaded processes (default: one per
    core) listening on 127.0.0.1, its dashboard started (on 127.0.0.1, its address printed) only with
    ``dashboard``; or the running cluster at ``scheduler`` (``tls://host:port`` with Dask's TLS settings, or
    ``tcp://host:port``, which warns beyond loopback); a local cluster is closed on exit."""
    client = _client(workers, scheduler, dashboard)
    try:
        yield client
    finally:
        client.close()
        if scheduler is None:
            client.cluster.close()


def in_flight_limit(client: Client) -> int:
    """Chunks submitted at a time: ``IN_FLIGHT_PER_THREAD`` per worker thread (at least 4), so a study of
    any size keeps a bounded number of futures (and results) in memory."""
    threads = sum(client.nthreads().values()) or 1
    return max(4, IN_FLIGHT_PER_THREAD * threads)


def run_chunks(task: Callable[..., object], chunk_args: Sequence[tuple], sizes: Sequence[int],
               sink: Callable[[int, object], None], *, done: frozenset[int] = frozenset(),
               workers: int | None = None, scheduler: str | None = None, progress: bool = True,
               name: str = "chunk", client: Client | None = None, shared: object = None,
               dashboard: bool = False, total: int | None = None) -> int:
    """Run ``task(*chunk_args[k])`` (``task(shared, *chunk_args[k])`` when ``shared`` is given: sent to the
    workers once, not with every chunk) for every chunk k not in ``done`` on Dask and hand each result to
    ``sink(k, result)`` as it completes; ``sizes[k]`` is chunk k's number of samples (for the progress bar
    over samples, shown from the start; ``total``: their sum, if known). ``chunk_args`` and ``sizes`` may be
    lazy sequences: chunks are
    submitted in waves, at most :func:`in_flight_limit` at a time. ``client``: an open :func:`connect` client
    (studies that run several rounds); else one is opened for ``workers`` (processes of a LocalCluster,
    default one per core) or ``scheduler`` (the address of a running cluster). Returns the number of chunks
    run."""
    n = len(chunk_args)
    todo = n - sum(1 for k in done if 0 <= k < n)
    if not todo:
        return 0
    total = int(sum(sizes)) if total is None else total
    initial = int(sum(sizes[k] for k in done if 0 <= k < n))
    with tqdm(total=total, initial=initial, unit="sample", disable=not progress, desc=name) as bar:
        if client is None:
            with connect(workers, scheduler, dashboard) as c:
                return _run(c, task, chunk_args, sizes, sink, done, bar, name, shared)
        return _run(client, task, chunk_args, sizes, sink, done, bar, name, shared)


def _run(client: Client, task: Callable[..., object], chunk_args: Sequence[tuple], sizes: Sequence[int],
         sink: Callable[[int, object], None], done: frozenset[int], bar: tqdm, name: str, shared: object) -> int:
    from distributed import as_completed

    token = uuid.uuid4().hex[:8]  # keys unique per run: a shared cluster never mixes two studies
    head = () if shared is None else (client.scatter(shared, broadcast=True, hash=False),)
    pending = (k for k in range(len(chunk_args)) if k not in done)
    futures: dict[object, int] = {}

    def submit() -> object | None:
        k = next(pending, None)
        if k is None:
            return None
        fut = client.submit(task, *head, *chunk_args[k], key=f"{name}-{token}-{k}", pure=False)
        futures[fut] = k
        return fut

    queue = as_completed([f for _ in range(in_flight_limit(client)) if (f := submit()) is not None],
                         with_results=True, raise_errors=False)
    run = 0
    try:
        # results fetched on the client's event loop (a fut.result() from this thread can race with the
        # rescheduling of a chunk whose worker died: "Event bound to a different event loop")
        for fut, result in queue:
            k = futures.pop(fut)
            if fut.status == "error":
                raise ClusterError(f"{name} {k} failed on the cluster: {result!r}", chunk=k, cause=repr(result))
            sink(k, result)
            run += 1
            bar.update(sizes[k])
            if (nxt := submit()) is not None:
                queue.add(nxt)
    finally:
        client.cancel(list(futures))
    return run
