"""The compiled kernels' cache (pressfit.dynamics.kernels.cache_directory) lives in the user's cache directory,
never in the installed package: a ``__pycache__`` numba leaves there outlives ``pip uninstall`` and shadows a
later editable install as a namespace package (issue: the README's two commands run in order). Each case runs a
fresh interpreter, because numba picks a kernel's cache locator when the module is imported."""

import os
import subprocess
import sys
import time
from pathlib import Path

import pressfit

PACKAGE = Path(pressfit.__file__).resolve().parent
CALL = (
    "import numpy as np; from pressfit.dynamics import kernels; print(kernels.moved(np.zeros(3), np.ones(3), 0.5));"
    "print(getattr(kernels.moved._cache, '_cache_path', 'no cache'))"
)


def _run(env_cache: str) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"} | {"XDG_CACHE_HOME": env_cache}
    return subprocess.run([sys.executable, "-c", CALL], env=env, capture_output=True, text=True, timeout=120)


def _numba_files_since(start: float) -> list[Path]:
    return [p for p in PACKAGE.rglob("*.nb[ic]") if p.stat().st_mtime >= start]


def test_the_kernel_cache_is_written_to_the_user_cache_directory_only(tmp_path):
    start = time.time() - 1.0
    result = _run(str(tmp_path))
    assert result.returncode == 0 and result.stdout.split()[0] == "True", result
    assert Path(result.stdout.split()[1]).parent == tmp_path / "pressfit" / "numba"
    assert list((tmp_path / "pressfit" / "numba").rglob("*moved*.nbi")), "the kernel was not cached"
    assert _numba_files_since(start) == []


def test_an_unwritable_cache_directory_compiles_in_process_and_writes_nothing(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")  # mkdir under a file fails even for root (chmod would not)
    start = time.time() - 1.0
    result = _run(str(blocker / "cache"))
    assert result.returncode == 0 and result.stdout.splitlines() == ["True", "no cache"], result
    assert _numba_files_since(start) == []
