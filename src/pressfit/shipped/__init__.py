"""The machine and case files shipped with pressfit.

In the repository they live at the top level (``models/``, ``cases/``); the build maps them into this
package (``pyproject.toml``: ``[tool.setuptools.package-dir]``), so a wheel, a plain ``pip install .``
and an editable install all find them here with :mod:`importlib.resources`.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path


def _directory(name: str) -> Path:
    # both data packages hold an __init__.py, so files() is a plain directory on every kind of install
    return Path(str(files(f"pressfit.shipped.{name}")))


def models_dir() -> Path:
    """The directory of the shipped machine files (``models/*.toml``)."""
    return _directory("models")


def cases_dir() -> Path:
    """The directory of the shipped case files (``cases/**/*.toml``)."""
    return _directory("cases")


def default_model() -> Path:
    """The reference machine of the paper (``models/pressfit_4upu.toml``)."""
    return models_dir() / "pressfit_4upu.toml"
