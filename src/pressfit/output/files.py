"""Atomic, non-clobbering output files (CSV, JSON, text, figures)."""

from __future__ import annotations

import errno
import json
import os
import shutil
import tempfile
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pressfit.errors import OutputConflictError, OutputError, OutputExistsError

if TYPE_CHECKING:
    from matplotlib.figure import Figure

LOCK_NAME = ".pressfit-writing"  # made in an output directory while a run moves its files in (write_directory)


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def check_target(path: Path | str, overwrite: bool) -> Path:
    """Check before any computation that a single output file can be written (raises otherwise).

    Refused: an existing file without ``overwrite``, a directory or special file (FIFO, device) at the path,
    a parent that is a file or not writable. A symlink is followed (its target is replaced, not the link).
    """
    path = Path(path)
    real = Path(os.path.realpath(path))
    if real.exists() and not real.is_file():
        raise OutputError(f"cannot write {path}: it is a directory or special file, not a regular file", path=path)
    if real.exists() and not overwrite:
        raise OutputExistsError(f"{path} exists; pass --overwrite to replace it", path=path)
    _check_parent(path, real.parent)
    return real


def _check_parent(path: Path, parent: Path) -> None:
    """The nearest existing ancestor of ``parent`` must be a writable directory."""
    anc = parent
    while not anc.exists() and anc != anc.parent:
        anc = anc.parent
    if not anc.is_dir():
        raise OutputError(f"cannot write {path}: {anc} is not a directory", path=path)
    if not os.access(anc, os.W_OK | os.X_OK):
        raise OutputError(f"cannot write {path}: {anc} is not writable", path=path)


def _same_file(a: Path, b: Path) -> bool:
    """The same file: equal resolved paths (symlinks followed), or one file under two names (a hard link)."""
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def check_distinct(outputs: dict[str, Path | str | None], inputs: Iterable[Path | str]) -> None:
    """Refuse, before any computation, two output options (name -> path; None = not given) naming one file,
    and an output that is one of the input files (``inputs``: every file the command reads, files found in
    an input directory included); raises OutputConflictError naming both."""
    named = [(option, Path(p)) for option, p in outputs.items() if p is not None]
    files = [Path(f) for f in inputs]
    for k, (option, path) in enumerate(named):
        for other, other_path in named[k + 1:]:
            if _same_file(path, other_path):
                raise OutputConflictError(option, path, other, f"{option} {path} and {other} {other_path} name the "
                                          "same file: give each output its own file")
        for f in files:
            if _same_file(path, f):
                raise OutputConflictError(option, path, str(f), f"{option} {path} is the input file {f}: writing "
                                          "it would replace the input; give another output file")


def check_inputs_outside(out_dir: Path | str, inputs: Iterable[Path | str]) -> None:
    """Refuse, before any computation, an input file inside the output directory ``out_dir`` of a command whose
    output names are known only from its results (a design study's ``designs/design-NNNNNN.toml``): with
    ``--overwrite`` one of them could replace the input (OutputConflictError naming both)."""
    out = Path(os.path.realpath(out_dir))
    for f in inputs:
        real = Path(os.path.realpath(f))
        if out == real or out in real.parents:
            raise OutputConflictError("--out", out_dir, str(f), f"--out {out_dir} holds the input file {f}: the "
                                      "study's files are named by its results and could replace it; give another "
                                      "--out or move the input out of it")


def check_directory(out_dir: Path | str, overwrite: bool) -> Path:
    """Check before any computation that a multi-file output directory can be written: it must be new or
    empty unless ``overwrite`` (then files of the same names are replaced), and its parent writable."""
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise OutputError(f"cannot write {out}: it exists and is not a directory", path=out)
    if (out / LOCK_NAME).is_dir():
        raise OutputExistsError(f"{out} is being written by another pressfit run (or by one that was killed: "
                                f"then remove {out / LOCK_NAME})", path=out)
    if out.is_dir() and not overwrite and any(out.iterdir()):
        raise OutputExistsError(f"{out} exists and is not empty; pass --overwrite to replace its files", path=out)
    _check_parent(out, out if out.is_dir() else out.parent)
    return out


def write_directory(out_dir: Path | str, overwrite: bool, write: Callable[[Path], Iterable[Path]],
                    inputs: Iterable[Path | str] = ()) -> list[Path]:
    """Run ``write(tmp)`` into a temporary directory beside ``out_dir``, then move it in (so an error or a
    signal leaves no partial output); returns the final paths.

    The check of :func:`check_directory` is repeated at the move, so of two runs writing the same directory
    one wins and the other raises OutputExistsError (its files discarded): a directory this run creates is
    replaced by the temporary one in one rename, which fails once it holds anything; an existing one is
    claimed by creating ``LOCK_NAME`` in it (atomic; a second run finds it), re-checked to be empty unless
    ``overwrite`` (then files of the same names are replaced), filled file by file and released. An output
    that would replace one of ``inputs`` (the files the command read) raises OutputConflictError before any
    file is moved."""
    out = check_directory(out_dir, overwrite)
    inputs = [Path(f) for f in inputs]
    real = Path(os.path.realpath(out))
    try:
        real.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{real.name}.", dir=real.parent))
    except OSError as exc:
        raise OutputError(f"cannot write {out}: {exc.strerror}", path=out) from None
    try:
        written = [Path(p) for p in write(tmp)]
        files = sorted(q.relative_to(tmp) for q in tmp.rglob("*") if q.is_file())
        for f in (f for f in files if (real / f).exists()):  # only an existing file can be an input
            check_distinct({"--out": out / f}, inputs)
        _move_in(tmp, real, out, overwrite)
        return [out / p.relative_to(tmp) for p in written] if written else [out / p for p in files]
    except OSError as exc:
        raise OutputError(f"cannot write {out}: {exc.strerror}", path=out) from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _move_in(tmp: Path, real: Path, out: Path, overwrite: bool) -> None:
    """Move the files of ``tmp`` into the directory ``real`` (:func:`write_directory`)."""
    try:
        real.mkdir()
        created = True
    except FileExistsError:
        created = False
    if created:
        os.chmod(tmp, real.stat().st_mode & 0o7777)
        try:
            os.rename(tmp, real)  # onto the empty directory made just now; fails if another run is in it
            return
        except OSError as exc:
            if exc.errno not in (errno.ENOTEMPTY, errno.EEXIST):
                raise
    lock = real / LOCK_NAME
    try:
        lock.mkdir()
    except FileExistsError:
        raise OutputExistsError(f"{out} is being written by another pressfit run (or by one that was killed: "
                                f"then remove {lock})", path=out) from None
    except NotADirectoryError:
        raise OutputError(f"cannot write {out}: it is no longer a directory", path=out) from None
    try:
        if not overwrite and set(os.listdir(real)) - {LOCK_NAME}:
            raise OutputExistsError(f"{out} was filled by another run while this one computed; this run wrote "
                                    "nothing (pass --overwrite to replace its files)", path=out)
        for p in sorted(q for q in tmp.rglob("*") if q.is_file()):
            target = real / p.relative_to(tmp)
            target.parent.mkdir(parents=True, exist_ok=True)
            os.replace(p, target)
    finally:
        lock.rmdir()


def _atomic(path: Path | str, write: Callable[[Path], None], overwrite: bool) -> Path:
    """Write through ``write(tmp)`` into a temporary file beside ``path``, then rename it in place.

    A symlink is written through (its target replaced); the file gets the mode of the file it replaces,
    or 0666 less the umask. The temporary file is removed on any error or interruption."""
    path = Path(path)
    real = check_target(path, overwrite)
    try:
        real.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{real.name}.", suffix=real.suffix, dir=real.parent)
    except OSError as exc:
        raise OutputError(f"cannot write {path}: {exc.strerror}", path=path) from None
    os.close(fd)
    try:
        os.chmod(tmp, real.stat().st_mode & 0o7777 if real.exists() else 0o666 & ~_umask())
        write(Path(tmp))
        os.replace(tmp, real)
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


def _finite(obj: Any) -> Any:
    """``obj`` with every non-finite number as None (JSON null: an unbounded or undefined figure, e.g. the settling
    time of a force that never settled or the alignment of a pin never touched, whose verdict says why)."""
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _finite(obj.tolist())
    if isinstance(obj, (float, np.floating)) and not np.isfinite(obj):
        return None
    return obj


def to_json(data: Any) -> str:
    return json.dumps(_finite(data), indent=2, default=_jsonable, allow_nan=False)


def write_json(path: Path | str, data: Any, overwrite: bool = False) -> Path:
    return write_text(path, to_json(data) + "\n", overwrite)


def write_csv(path: Path | str, header: Sequence[str], rows: Iterable[Sequence[Any]],
              overwrite: bool = False) -> Path:
    lines = [",".join(header)] + [",".join(_fmt(v) for v in row) for row in rows]
    return write_text(path, "\n".join(lines) + "\n", overwrite)


def _fmt(v: Any) -> str:
    return repr(float(v)) if isinstance(v, (float, np.floating)) else str(v)


def save_figure(fig: Figure, path: Path | str, overwrite: bool = False) -> Path:
    """Save a matplotlib figure atomically (format from the suffix: .png or .svg)."""
    fmt = Path(path).suffix.lstrip(".")
    return _atomic(path, lambda p: fig.savefig(p, format=fmt, dpi=120, bbox_inches="tight"), overwrite)


def write_parquet(path: Path | str, columns: dict[str, np.ndarray], overwrite: bool = False,
                  metadata: dict[str, str] | None = None) -> Path:
    """Write named columns (equal-length arrays) as one Parquet file (pyarrow, zstd), with optional
    key-value ``metadata`` in its schema."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.table({k: np.asarray(v) for k, v in columns.items()})
    if metadata:
        table = table.replace_schema_metadata(metadata)
    return _atomic(path, lambda p: pq.write_table(table, p, compression="zstd"), overwrite)
