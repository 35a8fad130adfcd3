"""The Dask runner: identical results with 1 and 2 workers and after an interrupted run is resumed, a killed
worker (small clusters, 1 thread per worker); a scheduler and a worker started as separate processes, by the
``dask scheduler`` and ``dask worker`` commands: tests/studies/test_distributed_trust.py, over TLS."""

import os
import signal
from pathlib import Path

import numpy as np
import pytest

from pressfit.description.cases import load_case
from pressfit.errors import ClusterError
from pressfit.output import montecarlo_files as mcf
from pressfit.studies import distributed, montecarlo
from pressfit.workflows.tolerance_study import run_montecarlo
from tests.studies.test_montecarlo import synthetic_case

TILT = """[montecarlo.inputs.load_tilt_rad]
distribution = "uniform"
low = 0.0
high = 0.05
"""


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    return load_case(synthetic_case(tmp_path_factory.mktemp("case"), samples=24, extra=TILT))


def _columns(out: Path) -> dict[str, np.ndarray]:
    return mcf.read_samples(out)


def _same(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> None:
    assert a.keys() == b.keys()
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)  # bit for bit


def test_one_and_two_workers_and_a_resumed_run_agree(case, cluster, tmp_path, monkeypatch):
    two_workers = {"scheduler": cluster.scheduler_address}
    one = run_montecarlo(case, tmp_path / "one", chunk_size=4, workers=1, progress=False)
    two = run_montecarlo(case, tmp_path / "two", chunk_size=4, **two_workers, progress=False)
    assert one.chunks_run == two.chunks_run == 6
    _same(_columns(tmp_path / "one"), _columns(tmp_path / "two"))
    np.testing.assert_array_equal(_columns(tmp_path / "one")["sample"], np.arange(24))

    real, written = mcf.io.write_parquet, []

    def interrupt_after_two(path, cols, overwrite=False, **kw):  # the user presses Ctrl-C after two chunks
        if len(written) == 2:
            raise KeyboardInterrupt
        written.append(path)
        return real(path, cols, overwrite, **kw)

    monkeypatch.setattr(mcf.io, "write_parquet", interrupt_after_two)
    with pytest.raises(KeyboardInterrupt):
        run_montecarlo(case, tmp_path / "resumed", chunk_size=4, **two_workers, progress=False)
    monkeypatch.setattr(mcf.io, "write_parquet", real)
    done, damaged = mcf.finished_chunks(tmp_path / "resumed", montecarlo.plan_from_case(case, chunk_size=4))
    assert done == {int(p.stem.split("-")[1]) for p in written} and not damaged
    resumed = run_montecarlo(case, tmp_path / "resumed", chunk_size=4, **two_workers, progress=False)
    assert resumed.chunks_run == 4
    _same(_columns(tmp_path / "one"), _columns(tmp_path / "resumed"))
    with pytest.raises(mcf.OutputExistsError, match="different Monte Carlo study"):
        run_montecarlo(case, tmp_path / "resumed", chunk_size=4, seed=99, workers=1, progress=False)


def test_a_killed_worker_leaves_every_sample_exactly_once(case, cluster):
    from distributed import Client

    plan = montecarlo.plan_from_case(case, samples=32, chunk_size=2)
    seeds = montecarlo.chunk_seeds(plan)
    got: dict[int, dict] = {}
    with Client(cluster) as client:
        pids = list(client.run(os.getpid).values())

        def sink(k, cols):
            assert k not in got  # exactly once
            got[k] = cols
            if len(got) == 1:
                os.kill(pids[0], signal.SIGKILL)  # one worker dies mid-study; its nanny restarts it

        distributed.run_chunks(montecarlo.evaluate_chunk, [(plan, k, seeds[k]) for k in range(plan.n_chunks)],
                               [2] * plan.n_chunks, sink, scheduler=cluster.scheduler_address, progress=False)
        assert pids[0] not in client.run(os.getpid).values()  # the kill really happened
        client.wait_for_workers(2, timeout=60)  # the shared cluster whole again for the next test
    samples = np.sort(np.concatenate([c["sample"] for c in got.values()]))
    np.testing.assert_array_equal(samples, np.arange(32))
    single = montecarlo.evaluate_chunk(plan, 5, seeds[5])
    for key in single:
        np.testing.assert_array_equal(got[5][key], single[key])


def test_a_cluster_error_carries_what_was_asked_for():
    """Workers and a scheduler address together are refused before any connection, the request as data
    (ClusterError.workers, .scheduler), so a caller needs no message parsing."""
    with pytest.raises(ClusterError, match="not both") as refused:
        distributed._client(2, "tcp://127.0.0.1:1", False)
    assert (refused.value.workers, refused.value.scheduler, refused.value.chunk) == (2, "tcp://127.0.0.1:1", None)
