"""A built wheel stands alone: it carries the shipped models/ and cases/ (mapped into pressfit.shipped) and its
commands work from an unrelated working directory, without the repository (issue: a non-editable install
failed on every command because the default model was found with parents[2])."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """The wheel, built from the repository and unpacked as site-packages of its own (dependencies from the
    test environment)."""
    tmp = tmp_path_factory.mktemp("wheel")
    source = tmp / "source"  # a copy: an in-tree build would leave build/ in the repository
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(".git", ".venv", "build", "*.egg-info", "__pycache__",
                                                                 ".pytest_cache", ".hypothesis", "report", "out"))
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(tmp), str(source)],
                   check=True, capture_output=True)
    (wheel,) = tmp.glob("pressfit-*.whl")
    site = tmp / "site"
    with zipfile.ZipFile(wheel) as z:
        names = z.namelist()
        z.extractall(site)
    return site, names


def _run(site: Path, cwd: Path, *args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(site)}
    return subprocess.run([sys.executable, "-m", "pressfit", *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=300)


def test_wheel_carries_the_shipped_data(installed):
    _, names = installed
    shipped = {n for n in names if n.startswith("pressfit/shipped/")}
    assert "pressfit/shipped/models/pressfit_4upu.toml" in shipped
    for case in ("paper/A.toml", "paper/B.toml", "paper/C.toml", "envelope/press_workspace.toml"):
        assert f"pressfit/shipped/cases/{case}" in shipped


def test_commands_run_from_an_unrelated_directory(installed, tmp_path):
    site, _ = installed
    where = subprocess.run([sys.executable, "-c", "import pressfit, pressfit.shipped as s; "
                            "print(pressfit.__file__); print(s.cases_dir())"], cwd=tmp_path, capture_output=True,
                           text=True, env={**os.environ, "PYTHONPATH": str(site)}, check=True).stdout.split()
    assert all(Path(p).is_relative_to(site) for p in where), where  # the wheel's code and data, not the repo's
    tables = _run(site, tmp_path, "tables", "--json")
    assert tables.returncode == 0, tables.stderr
    assert len(json.loads(tables.stdout)) == 3 * 7 * 4  # cases A-C x 7 components x 4 legs
    solve = _run(site, tmp_path, "solve", "0", "0.72", "0", "--load", "0", "700", "0", "--json")
    assert solve.returncode == 0, solve.stderr
    axial = [leg["sections"]["actuator"]["N"] for leg in json.loads(solve.stdout)["legs"]]
    assert axial == pytest.approx([700 / (4 * 2 / 5**0.5)] * 4, rel=1e-3)  # 700 / (4 sin alpha), tan alpha = 2
    case = Path(where[1]) / "envelope" / "press_workspace.toml"
    check = _run(site, tmp_path, "check", str(case), "--no-progress")
    assert check.returncode == 0, check.stdout + check.stderr
    assert "1 passed, 0 failed" in check.stdout


def test_every_source_package_is_listed_for_the_wheel():
    """pyproject.toml lists the packages explicitly (the shipped data is mapped beside them): a subpackage
    missing from the list would be absent from a wheel while the editable install still finds it."""
    import tomllib

    root = Path(__file__).resolve().parents[1]
    listed = set(tomllib.loads((root / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    src = root / "src"
    found = {".".join(p.parent.relative_to(src).parts) for p in src.rglob("__init__.py")}
    assert found <= listed, f"packages missing from pyproject.toml: {sorted(found - listed)}"
