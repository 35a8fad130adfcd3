"""numba's ``njit`` as pressfit compiles with it: the one place a kernel's cache lives.

Compiled with ``error_model="numpy"`` (a division by zero gives inf or nan, which the callers' finiteness checks
refuse, rather than an exception from inside a kernel) and ``cache=True``: the first call in a fresh install
compiles and numba keeps the result in the user's cache directory (:func:`cache_directory`, created on demand),
never in the installed package's directory (a leftover ``__pycache__`` there outlives ``pip uninstall`` and shadows
a later editable install as a namespace package); where that directory is not writable, each process compiles.
"""

from __future__ import annotations

import os
from pathlib import Path

import platformdirs
from numba import config, njit


def cache_directory() -> Path:
    """The compiled kernels' cache: numba's own ``NUMBA_CACHE_DIR`` when the user set it, else
    ``<user cache dir>/pressfit/numba`` (platformdirs: ``$XDG_CACHE_HOME/pressfit/numba`` on Linux)."""
    own = os.environ.get("NUMBA_CACHE_DIR")
    return Path(own) if own else platformdirs.user_cache_path("pressfit", appauthor=False) / "numba"


def compiled(function):
    """``njit`` with the cache in :func:`cache_directory` only (numba's user-provided locator, the other
    locators, which fall back to the package's ``__pycache__``, switched off while this kernel is declared);
    where that directory cannot be created or written, numba finds no locator and the kernel is compiled in each
    process instead."""
    saved = config.CACHE_DIR, config.CACHE_LOCATOR_CLASSES
    config.CACHE_DIR, config.CACHE_LOCATOR_CLASSES = str(cache_directory()), "UserProvidedCacheLocator"
    try:
        return njit(cache=True, error_model="numpy")(function)
    except RuntimeError:  # numba: "cannot cache function ...: no locator available"
        return njit(error_model="numpy")(function)
    finally:
        config.CACHE_DIR, config.CACHE_LOCATOR_CLASSES = saved
