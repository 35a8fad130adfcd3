"""Shared fixtures: the shipped machine."""

import pytest

from pressfit.description.machine import load_machine


@pytest.fixture(scope="session")
def machine():
    return load_machine()
