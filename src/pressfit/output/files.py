"""Atomic, non-clobbering output files (CSV, JSON, text, figures)."""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from pressfit.errors import OutputError, OutputExistsError


def _atomic(path: Path | str, write: Callable[[Path], None], overwrite: bool) -> Path:
    """Write through ``write(tmp)`` into a temporary file beside ``path``, then rename it in place."""
    path = Path(path)
    if path.exists() and not overwrite:
        raise OutputExistsError(f"{path} exists; pass --overwrite (overwrite=True) to replace it")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent)
    except OSError as exc:
        raise OutputError(f"cannot write {path}: {exc.strerror}") from None
    os.close(fd)
    try:
        write(Path(tmp))
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return path


def write_text(path: Path | str, text: str, overwrite: bool = False) -> Path:
    return _atomic(path, lambda p: p.write_text(text, encoding="utf-8"), overwrite)


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (np.floating, np.integer, np.bool_)):
        return obj.item()
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def to_json(data: Any) -> str:
    return json.dumps(data, indent=2, default=_jsonable, allow_nan=False)


def write_json(path: Path | str, data: Any, overwrite: bool = False) -> Path:
    return write_text(path, to_json(data) + "\n", overwrite)


def write_csv(path: Path | str, header: Sequence[str], rows: Iterable[Sequence[Any]],
              overwrite: bool = False) -> Path:
    lines = [",".join(header)] + [",".join(_fmt(v) for v in row) for row in rows]
    return write_text(path, "\n".join(lines) + "\n", overwrite)


def _fmt(v: Any) -> str:
    return repr(float(v)) if isinstance(v, (float, np.floating)) else str(v)


def save_figure(fig: Any, path: Path | str, overwrite: bool = False) -> Path:
    """Save a matplotlib figure atomically (format from the suffix: .png or .svg)."""
    fmt = Path(path).suffix.lstrip(".")
    return _atomic(path, lambda p: fig.savefig(p, format=fmt, dpi=120, bbox_inches="tight"), overwrite)


def write_parquet(path: Path | str, columns: dict[str, np.ndarray], overwrite: bool = False) -> Path:
    """Write named columns (equal-length arrays) as one Parquet file (pyarrow, zstd)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.table({k: np.asarray(v) for k, v in columns.items()})
    return _atomic(path, lambda p: pq.write_table(table, p, compression="zstd"), overwrite)
