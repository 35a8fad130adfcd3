"""Shared fixtures: the shipped machine, Tsai's 3-UPU, a 5-leg machine, and the suite's expensive artefacts, each
built once per test run (``--dist loadfile``: a module's tests run on one xdist worker, so a module fixture is
built once; the session's report is used by one module only).
Tests that use an expensive artefact are marked ``slow`` here; the edit-test loop is
``pytest -m "not slow and not browser"`` (docs/testing.md)."""

import json
import os
from pathlib import Path

import pytest
from click.testing import CliRunner
from n_legs import ring
from study_front import STUDY_FRONT
from threadpoolctl import threadpool_limits

from pressfit.cli import main
from pressfit.description.machine import load_machine

if "MUTANT_UNDER_TEST" in os.environ and not hasattr(pytest.Item, "_nodeid"):
    # mutmut 3.7.0 (the newest that accepts the pinned click 8.4.0; docs/testing.md) reads Item._nodeid,
    # which pytest 9 no longer has: alias it, under a mutation run only
    pytest.Item._nodeid = property(lambda self: self.nodeid)


def pytest_configure(config):
    """Under xdist, one BLAS thread per worker: two workers on two cores, each with a BLAS pool the size of the
    machine, oversubscribe the cores (an eigen-solve then waits on its own threads)."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        config._blas_limit = threadpool_limits(limits=1)


@pytest.fixture(scope="session")
def machine():
    return load_machine()


@pytest.fixture(scope="session")
def tsai():
    """Tsai's 3-UPU (models/tsai_3upu.toml): three legs at 120 degrees about y, leg 1 at -z."""
    return load_machine(Path(__file__).resolve().parents[1] / "models" / "tsai_3upu.toml")


@pytest.fixture(scope="session")
def five(machine):
    """The shipped machine with five legs at 72 degrees about y, leg 1 at -z (same p, r, sections, masses)."""
    return machine.with_overrides({"legs": ring(5)})


#: expensive fixtures (module- or session-scoped simulations, studies, clusters, installs): their tests are slow
EXPENSIVE = {"quick_report", "pairs", "both_models", "runs", "slow_and_fast", "measured", "short_runs", "sized",
             "free_run", "simulated", "rigid_runs", "study", "small_study", "every_pair", "loose_result", "cluster",
             "installed", "paper_fit", "report_dir", "calibrated", "compliant_pin_simulation",
             "shipped_play_runs", "board_run"}


@pytest.fixture(scope="module")
def cluster():
    """A LocalCluster of 2 single-threaded worker processes on loopback, shared by a module's Dask tests that run a
    study by its address (starting one, with pressfit imported on its workers, costs seconds); tests of the local
    cluster a command starts itself (``--workers``) start their own. Per module, not per session: an idle cluster
    costs about 8% of a core (its event loops and heartbeats), more than a start when modules lie minutes apart."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address="127.0.0.1:0", scheduler_kwargs={"dashboard": False}, silence_logs=50) as c:
        yield c


@pytest.fixture(scope="session")
def quick_report(tmp_path_factory):
    """``pressfit report --quick`` as a user runs it, with a cycle study's front (tests/output/test_html_report.py
    reads its report.md and report.html): built once per test run."""
    out, study = tmp_path_factory.mktemp("report"), tmp_path_factory.mktemp("study")
    (study / "summary.json").write_text(json.dumps({"samples": 4, "front": STUDY_FRONT}))
    result = CliRunner().invoke(main, ["report", "--out", str(out), "--quick", "--cycle-study", str(study)])
    assert result.exit_code == 0, result.output
    return out


def pytest_collection_modifyitems(config, items):
    """A test driving chromium is ``browser``; a test using an expensive fixture is ``slow``."""
    for item in items:
        if {"browser", "page"} & set(item.fixturenames):
            item.add_marker(pytest.mark.browser)
        if EXPENSIVE & set(item.fixturenames):
            item.add_marker(pytest.mark.slow)
