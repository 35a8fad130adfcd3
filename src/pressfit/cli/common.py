"""What every ``pressfit`` command shares: the model option, the error handler, number parsing."""

from __future__ import annotations

import functools
import math
import sys
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import click
from tqdm import tqdm

from pressfit.description.cases import MAX_FORCE_N
from pressfit.description.machine import DEFAULT_MODEL
from pressfit.errors import PressfitError

MODEL_OPTION = click.option("--model", "model_path", type=click.Path(path_type=Path), default=DEFAULT_MODEL,
                            show_default=True, help="Machine description (TOML).")


def close_progress_bars() -> None:
    """Finish any open progress bar so that a message after it starts on its own line."""
    for bar in list(getattr(tqdm, "_instances", ())):
        bar.close()


def user_errors(func: Callable[..., Any]) -> Callable[..., Any]:
    """Turn a :class:`PressfitError` into a one-line message and exit code 2 (never a traceback)."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except PressfitError as exc:
            close_progress_bars()
            click.echo(f"error: {' '.join(str(exc).split())}", err=True)
            sys.exit(2)

    return wrapper


class FiniteFloat(click.ParamType):
    """A finite number (no NaN or inf) in [low, high] (``open_low``: > low); the error names the option."""

    name = "number"

    def __init__(self, low: float = -math.inf, high: float = math.inf, open_low: bool = False) -> None:
        self.low, self.high, self.open_low = low, high, open_low

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> float:
        if isinstance(value, float) and math.isfinite(value):
            x = value
        else:
            try:
                x = float(value)
            except (TypeError, ValueError):
                self.fail(f"{value!r} is not a number", param, ctx)
        if not math.isfinite(x):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        if x < self.low or x > self.high or (self.open_low and x == self.low):
            self.fail(f"{x:g} is outside {'(' if self.open_low else '['}{self.low:g}, {self.high:g}]", param, ctx)
        return x


class FloatList(click.ParamType):
    """Comma-separated finite numbers in [low, high], at least one, no empty item (``1e-5,2e-5``)."""

    name = "list"

    def __init__(self, low: float = -math.inf, high: float = math.inf) -> None:
        self.item = FiniteFloat(low, high)

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> list[float]:
        if isinstance(value, list):
            return value
        items = str(value).split(",")
        if any(not s.strip() for s in items):
            self.fail(f"{value!r}: give comma-separated numbers without empty items", param, ctx)
        return [self.item.convert(s.strip(), param, ctx) for s in items]


COORDINATE = FiniteFloat(-100.0, 100.0)  # m: a plate pose far outside any machine is a typo
FORCE = FiniteFloat(-MAX_FORCE_N, MAX_FORCE_N)  # N or N m, the case files' bound


def increasing_pair(ctx: click.Context, param: click.Parameter, value: Any) -> Any:
    """Callback of a ``nargs=2`` range option: the second value must be larger than the first."""
    if value is not None and len(value) == 2 and not value[0] < value[1]:
        raise click.BadParameter(f"{value[0]:g} {value[1]:g}: give LOW HIGH with LOW < HIGH", ctx, param)
    return value


def parse_numbers(values: tuple[str, ...], what: str) -> list[float]:
    """Positional numbers of a command (finite), or a usage error naming ``what``."""
    try:
        return [FORCE.convert(v, None, None) for v in values]
    except click.BadParameter as exc:
        raise click.UsageError(f"{what}: {exc.format_message()}") from None


PROGRESS_OPTION = click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
OVERWRITE_OPTION = click.option("--overwrite", is_flag=True, help="Replace existing output files.")


def cluster_options(func: Callable[..., Any]) -> Callable[..., Any]:
    """``--workers N`` (a local Dask cluster of N processes; default one per core) or ``--scheduler ADDRESS``,
    and ``--dashboard`` (the local cluster's dashboard, on 127.0.0.1 only)."""
    func = click.option("--dashboard", is_flag=True, help="Start the local cluster's Dask dashboard (on 127.0.0.1; "
                        "its address is printed).")(func)
    func = click.option("--scheduler", help="Address of a running Dask scheduler: tls://HOST:8786 (certificates "
                        "from the Dask configuration, distributed.comm.tls) or tcp://HOST:8786 (unencrypted; "
                        "instead of --workers).")(func)
    return click.option("--workers", type=click.IntRange(1),
                        help="Worker processes of the local cluster (default: one per core).")(func)


def echo_written(paths: Iterable[Path]) -> None:
    """One 'wrote PATH' line per output file."""
    for p in paths:
        click.echo(f"wrote {p}")
