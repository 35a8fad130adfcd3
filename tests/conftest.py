"""Shared fixtures: the shipped machine."""

import os

import pytest

from pressfit.description.machine import load_machine

if "MUTANT_UNDER_TEST" in os.environ and not hasattr(pytest.Item, "_nodeid"):
    # mutmut 3.7.0 (the newest that accepts the pinned click 8.4.0; docs/testing.md) reads Item._nodeid,
    # which pytest 9 no longer has: alias it, under a mutation run only
    pytest.Item._nodeid = property(lambda self: self.nodeid)


@pytest.fixture(scope="session")
def machine():
    return load_machine()
