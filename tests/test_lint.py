"""The linter is part of the test command: ruff, configured in pyproject.toml ([tool.ruff]: line length 120,
pyflakes, pycodestyle, isort, bugbear, pyupgrade, numpy, pytest style, no print or assert in the library)."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_ruff_finds_nothing():
    run = subprocess.run([sys.executable, "-m", "ruff", "check", "--no-cache", "src", "tests", "benchmarks"],
                         cwd=ROOT, capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "All checks passed" in run.stdout  # ruff ran on the tree (not an empty selection)
