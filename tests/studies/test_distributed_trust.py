"""The Monte Carlo study directory and the Dask runner under hostile conditions (issue 18): chunks of another
study, damaged chunks and stray files on resume, a first run that failed, bounded waves of futures, the
local cluster on loopback only, TLS to a remote scheduler, and a warning for plain TCP."""

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from pressfit.description.cases import load_case
from pressfit.errors import ClusterError, OutputExistsError
from pressfit.output import montecarlo_files as mcf
from pressfit.studies import distributed, montecarlo
from pressfit.workflows.tolerance_study import run_montecarlo
from tests.studies.test_distributed import TILT
from tests.studies.test_montecarlo import synthetic_case

ENV = os.environ | {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    return load_case(synthetic_case(tmp_path_factory.mktemp("case"), samples=6, extra=TILT))


@pytest.fixture(scope="module")
def clean(case, cluster, tmp_path_factory):
    """A finished 6-sample study in 2 chunks of 3, and its columns."""
    out = tmp_path_factory.mktemp("clean") / "mc"
    run_montecarlo(case, out, chunk_size=3, scheduler=cluster.scheduler_address, progress=False)
    return out, mcf.read_samples(out)


def _run(case, cluster, out, **kw):
    return run_montecarlo(case, out, chunk_size=3, scheduler=cluster.scheduler_address, progress=False, **kw)


def _same(a, b):
    assert a.keys() == b.keys()
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)


def _copy(clean, tmp_path):
    out = tmp_path / "mc"
    shutil.copytree(clean[0], out)
    return out


@pytest.fixture(scope="module")
def other_seed(case, cluster, tmp_path_factory):
    out = tmp_path_factory.mktemp("other") / "mc"
    run_montecarlo(case, out, chunk_size=3, seed=99, scheduler=cluster.scheduler_address, progress=False)
    return out


@pytest.mark.parametrize("name", ["chunk-000002.parquet", "chunk-000001.parquet"])
def test_a_chunk_of_another_seed_is_refused_naming_the_file(case, cluster, clean, other_seed, tmp_path, name):
    """Another seed's chunk 1 copied in as an extra chunk 2 (old code: "9 samples" for a 6-sample study) or
    over this study's chunk 1 (old code: silently mixed): refused, one error naming the file (it is readable
    data of another study: never deleted)."""
    out = _copy(clean, tmp_path)
    shutil.copy(mcf.chunk_path(other_seed, 1), out / "samples" / name)
    with pytest.raises(OutputExistsError, match=f"{name} is not a chunk of this Monte Carlo study: it belongs "
                                                "to another study") as err:
        _run(case, cluster, out)
    assert "\n" not in str(err.value)
    assert (out / "samples" / name).exists()


def test_a_chunk_under_another_index_is_refused(case, cluster, clean, tmp_path):
    """This study's chunk 0 copied to chunk-000001: the same fingerprint, but its metadata index (and samples
    0..2) do not match the name: refused."""
    out = _copy(clean, tmp_path)
    shutil.copy(mcf.chunk_path(out, 0), mcf.chunk_path(out, 1))
    with pytest.raises(OutputExistsError, match="chunk-000001.parquet is not a chunk of this Monte Carlo study: "
                                                "its chunk index does not match its name"):
        _run(case, cluster, out)


@pytest.mark.parametrize("damage", ["truncated", "empty", "text"])
def test_a_damaged_chunk_is_run_again(case, cluster, clean, tmp_path, damage):
    """A truncated, empty or text file named chunk-000001.parquet (old code: a pyarrow traceback): that chunk
    is run again, the result is the clean study's bit for bit, and the run names the file it replaced."""
    out = _copy(clean, tmp_path)
    path = mcf.chunk_path(out, 1)
    data = path.read_bytes()
    path.write_bytes({"truncated": data[: len(data) // 2], "empty": b"", "text": b"sample,status\n0,ok\n"}[damage])
    run = _run(case, cluster, out)
    assert run.chunks_run == 1 and run.rerun == [path]
    _same(mcf.read_samples(out), clean[1])


def test_stray_files_are_ignored(case, cluster, clean, tmp_path):
    """Files that are not named chunk-NNNNNN.parquet (notes, an old export) are neither read nor removed."""
    out = _copy(clean, tmp_path)
    (out / "samples" / "notes.txt").write_text("not data")
    shutil.copy(mcf.chunk_path(out, 0), out / "samples" / "chunk-0.parquet")
    run = _run(case, cluster, out)
    assert run.chunks_run == 0
    assert run.summary.samples == 6
    _same(mcf.read_samples(out, montecarlo.plan_from_case(case, chunk_size=3)), clean[1])
    assert (out / "samples" / "notes.txt").exists()


def test_a_first_run_that_wrote_only_study_json_can_be_restarted(case, cluster, clean, tmp_path, monkeypatch):
    """A first run stopped before its first chunk (scheduler unreachable, SIGTERM) leaves study.json only:
    a new study (another seed) in that directory starts instead of being refused as "a different study"."""
    out = tmp_path / "mc"

    def unreachable(*a, **k):
        raise ClusterError("cannot reach the Dask scheduler at 'tcp://10.9.9.9:8786'", scheduler="tcp://10.9.9.9:8786")

    monkeypatch.setattr(distributed, "run_chunks", unreachable)
    with pytest.raises(ClusterError):
        run_montecarlo(case, out, chunk_size=3, progress=False)
    assert [p.name for p in out.iterdir()] == ["study.json"]
    monkeypatch.undo()
    run = _run(case, cluster, out, seed=99)
    assert run.chunks_run == 2
    assert json.loads((out / "study.json").read_text())["seed"] == 99
    with pytest.raises(OutputExistsError, match="different Monte Carlo study"):  # now it has started
        _run(case, cluster, out, seed=3)


def test_overwrite_starts_afresh_even_with_a_summary(case, cluster, clean, tmp_path):
    """--overwrite removes the study's own files (old code left summary.json and then refused)."""
    out = _copy(clean, tmp_path)
    run = _run(case, cluster, out, seed=99, overwrite=True)
    assert run.chunks_run == 2 and json.loads((out / "study.json").read_text())["seed"] == 99


# --- the runner ------------------------------------------------------------------------------------------
def _square(x):
    return x * x


def test_chunks_go_out_in_bounded_waves(cluster):
    """200 chunks on the shared cluster: never more than in_flight_limit futures submitted and not yet handed to the
    sink (old code: all 200 at once); every result exactly once, in any order."""
    from distributed import Client

    with Client(cluster) as client:
        limit = distributed.in_flight_limit(client)
        assert limit < 200
        submitted, got, worst = [0], {}, [0]
        real = client.submit

        def counting(*a, **k):
            submitted[0] += 1
            return real(*a, **k)

        client.submit = counting

        def sink(k, r):
            got[k] = r
            worst[0] = max(worst[0], submitted[0] - len(got) + 1)

        distributed.run_chunks(_square, [(k,) for k in range(200)], [1] * 200, sink, client=client,
                               progress=False)
    assert got == {k: k * k for k in range(200)}
    assert worst[0] <= limit


def test_progress_is_shown_before_the_cluster_starts(monkeypatch, capsys):
    """The progress bar (0 of N samples) is on screen before connecting (old code: only after every future
    was submitted, minutes for 1e9 samples)."""
    def slow_cluster(*a, **k):
        raise ClusterError("stop here")

    monkeypatch.setattr(distributed, "connect", slow_cluster)
    with pytest.raises(ClusterError):
        distributed.run_chunks(_square, [(1,)] * 10, [100] * 10, lambda k, r: None, progress=True, name="mc")
    assert "0/1000" in capsys.readouterr().err


def test_a_billion_samples_plan_without_a_list_of_seeds(case):
    """chunk_seed(plan, k) alone equals SeedSequence(seed).spawn(n)[k] (bit for bit), so the runner needs no
    list of 2e7 seeds for 1e9 samples."""
    plan = montecarlo.plan_from_case(case, samples=12, chunk_size=3)
    for k, s in enumerate(montecarlo.chunk_seeds(plan)):
        np.testing.assert_array_equal(montecarlo.draw_inputs(plan, k, s)["load_tilt_rad"],
                                      montecarlo.draw_inputs(plan, k, montecarlo.chunk_seed(plan, k))["load_tilt_rad"])
    big = montecarlo.plan_from_case(case, samples=10**9, chunk_size=50)
    assert big.n_chunks == 2 * 10**7 and big.chunk_range(big.n_chunks - 1) == (10**9 - 50, 10**9)


# --- security --------------------------------------------------------------------------------------------
def _listening(pids):
    import psutil

    return {(c.laddr.ip, c.laddr.port) for p in pids for c in psutil.Process(p).net_connections("inet")
            if c.status == psutil.CONN_LISTEN}


@pytest.mark.parametrize("dashboard", [False, True])
def test_the_local_cluster_listens_on_loopback_only(dashboard, capsys):
    """Scheduler, workers and (only with --dashboard) the dashboard listen on 127.0.0.1 (old code: the
    dashboard on 0.0.0.0); with the dashboard its address is printed. The scheduler's HTTP server (its health route)
    is on a free port, not Dask's default 8787 (taken by any other cluster: a warning), and serves the dashboard's
    page only when asked (old code: always)."""
    import urllib.error
    import urllib.request

    def status(url):
        try:
            return urllib.request.urlopen(url, timeout=10).status
        except urllib.error.HTTPError as exc:
            return exc.code

    with distributed.connect(workers=1, dashboard=dashboard) as client:
        sockets = _listening([os.getpid(), *client.run(os.getpid).values()])
        link = client.dashboard_link if dashboard else None
        port = client.scheduler_info()["services"]["dashboard"]
        pages = [status(f"http://127.0.0.1:{port}/{page}") for page in ("health", "status")]
    assert sockets and {ip for ip, _ in sockets} == {"127.0.0.1"}, sockets
    assert port != 8787 and pages == [200, 200 if dashboard else 404]
    err = capsys.readouterr().err
    assert (f"Dask dashboard: {link}" in err) if dashboard else ("dashboard" not in err)


@pytest.mark.parametrize(("address", "warns"), [("tcp://10.0.0.5:8786", True), ("10.0.0.5:8786", True),
                                                ("tcp://node7.cluster:8786", True), ("tcp://127.0.0.1:8786", False),
                                                ("tcp://localhost:8786", False), ("tcp://[::1]:8786", False),
                                                ("tls://10.0.0.5:8786", False)])
def test_plain_tcp_beyond_loopback_warns(address, warns):
    w = distributed.transport_warning(address)
    assert (w is not None) == warns
    if warns:
        assert address in w and "unencrypted" in w


def _self_signed(tmp_path: Path) -> tuple[Path, Path]:
    # not a skip: a TLS check that silently does not run is not a pass (openssl is part of Debian's base system)
    assert shutil.which("openssl") is not None, "openssl is needed to make the test certificate"
    cert, key = tmp_path / "cert.pem", tmp_path / "key.pem"
    subprocess.run(["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1", "-subj", "/CN=127.0.0.1",
                    "-addext", "subjectAltName=IP:127.0.0.1", "-keyout", str(key), "-out", str(cert)],
                   check=True, capture_output=True)
    return cert, key


@pytest.mark.slow
def test_a_tls_scheduler_with_certificates_from_the_dask_configuration(case, tmp_path):
    """A scheduler and a worker started as separate processes by Dask's own commands (a user's remote cluster; plain
    tcp:// by address is the shared LocalCluster's, tests/conftest.py), here on tls://127.0.0.1 with a self-signed
    certificate; the client takes its
    certificates from the Dask configuration (distributed.comm.tls.*, as documented): the study runs and
    equals the in-process computation bit for bit; without the configuration the client cannot connect."""
    import dask
    import distributed as _  # noqa: F401  (loads its configuration first: leaving config.set would drop it)

    cert, key = _self_signed(tmp_path)
    tls = ["--tls-ca-file", str(cert), "--tls-cert", str(cert), "--tls-key", str(key)]
    file = tmp_path / "scheduler.json"
    procs = [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--protocol", "tls", "--host",
                               "127.0.0.1", "--port", "0", "--no-dashboard", "--scheduler-file", str(file), *tls],
                              env=ENV, stderr=subprocess.DEVNULL)]
    try:
        deadline = time.monotonic() + 60
        while not file.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        address = json.loads(file.read_text())["address"]
        assert address.startswith("tls://127.0.0.1:")
        procs.append(subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1",
                                       "--no-dashboard", *tls], env=ENV, stderr=subprocess.DEVNULL))
        config = {"distributed.comm.tls.ca-file": str(cert), "distributed.comm.tls.client.cert": str(cert),
                  "distributed.comm.tls.client.key": str(key)}
        with dask.config.set(config):
            run = run_montecarlo(case, tmp_path / "tls", chunk_size=3, scheduler=address, progress=False)
        assert run.chunks_run == 2
        plan = montecarlo.plan_from_case(case, chunk_size=3)
        here = [montecarlo.evaluate_chunk(plan, k, montecarlo.chunk_seed(plan, k)) for k in range(2)]
        remote = mcf.read_samples(tmp_path / "tls")
        for key_ in remote:
            np.testing.assert_array_equal(remote[key_], np.concatenate([c[key_] for c in here]), err_msg=key_)
        with pytest.raises(ClusterError, match="tls:// needs the client's certificates") as refused:
            distributed._client(None, address, False)
        assert refused.value.scheduler == address and refused.value.cause.startswith("tls:// needs")
    finally:  # the worker first: signalled together, the worker waits out its reconnection to the scheduler (8 s)
        for p in reversed(procs):
            p.terminate()
            p.wait(timeout=30)


# --- tiny and failed studies -----------------------------------------------------------------------------
@pytest.mark.parametrize("samples", [1, 2, 3])
def test_one_or_two_samples_work_and_say_the_sensitivity_is_undefined(case, cluster, tmp_path, samples):
    """1 or 2 samples (old code: a traceback in the sensitivity plot after partial writes): the study is
    summarised, the notes say the rank correlation is undefined, and no sensitivity plot is written; from 3
    samples on it is computed and plotted."""
    run = run_montecarlo(case, tmp_path / "mc", samples=samples, chunk_size=3,
                             scheduler=cluster.scheduler_address, progress=False)
    assert run.summary.samples == samples
    undefined = any(n.startswith("sensitivity: undefined") for n in run.summary.notes)
    assert undefined == (samples < 3) and bool(run.summary.sensitivity) == (samples >= 3)
    assert (tmp_path / "mc" / "sensitivity.png").exists() == (samples >= 3)
    assert (tmp_path / "mc" / "histograms.png").exists()


@pytest.mark.slow
def test_a_study_where_every_sample_fails_exits_2_with_the_reasons_counted(tmp_path, cluster):
    """120 kN down at pose A buckles the machine (factor 0.83): every sample is unstable; the command exits 2
    with one line counting the reasons (old code: a traceback from the plots), the chunks kept."""
    from click.testing import CliRunner

    from pressfit.cli import main
    from tests.studies.test_montecarlo_trust import pose_a_case

    path = pose_a_case(tmp_path, -120e3, samples=4, limit=0.5)
    result = CliRunner().invoke(main, ["study", "montecarlo", str(path), "--scheduler", cluster.scheduler_address,
                                       "--no-progress", "--out", str(tmp_path / "mc")])
    assert result.exit_code == 2, result.output
    assert "every sample failed (4 x UnstableEquilibriumError)" in result.output
    assert result.output.strip().count("\n") == 0
    assert len(list((tmp_path / "mc" / "samples").glob("chunk-*.parquet"))) == 2


def test_a_local_cluster_beyond_four_workers_per_core_is_refused_before_it_starts(monkeypatch):
    """--workers beyond WORKERS_PER_CORE x the cores the study may use is a huge request (500 processes on two
    cores thrashed the machine): refused naming the number and the cores, before any process starts; at the cap the
    cluster is started (a recording stand-in here)."""
    import distributed as dd
    from click.testing import CliRunner

    from pressfit.cli import main
    from pressfit.shipped import cases_dir

    started = []

    class Cluster:
        def __init__(self, n_workers, **kwargs):
            started.append(n_workers)

    monkeypatch.setattr(dd, "LocalCluster", Cluster)
    monkeypatch.setattr(dd, "Client", lambda cluster: cluster)
    cap = distributed.WORKERS_PER_CORE * distributed.default_workers()
    assert isinstance(distributed._client(cap, None, False), Cluster) and started == [cap]
    with pytest.raises(ClusterError, match=rf"--workers {cap + 1}: this machine gives the study "
                                           rf"{distributed.default_workers()} core\(s\).*more than {cap} worker"):
        distributed._client(cap + 1, None, False)
    assert started == [cap]
    res = CliRunner().invoke(main, ["study", "curve", str(cases_dir() / "paper" / "insertion_compliant_pin.toml"),
                                    "--samples", "10", "--workers", "500", "--no-progress"])
    assert res.exit_code == 2 and res.output.startswith("error: --workers 500:") and started == [cap], res.output
