"""Shared fixtures: the shipped machine, Tsai's 3-UPU and a 5-leg machine."""

import os
from pathlib import Path

import pytest
from n_legs import ring

from pressfit.description.machine import load_machine

if "MUTANT_UNDER_TEST" in os.environ and not hasattr(pytest.Item, "_nodeid"):
    # mutmut 3.7.0 (the newest that accepts the pinned click 8.4.0; docs/testing.md) reads Item._nodeid,
    # which pytest 9 no longer has: alias it, under a mutation run only
    pytest.Item._nodeid = property(lambda self: self.nodeid)


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
