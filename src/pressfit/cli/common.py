"""What every ``pressfit`` command shares: the model option, the error handler, number parsing."""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import click

from pressfit.description.machine import DEFAULT_MODEL
from pressfit.errors import PressfitError

MODEL_OPTION = click.option("--model", "model_path", type=click.Path(path_type=Path), default=DEFAULT_MODEL,
                            show_default=True, help="Machine description (TOML).")


def user_errors(func: Callable[..., Any]) -> Callable[..., Any]:
    """Turn a :class:`PressfitError` into a one-line message and exit code 2 (never a traceback)."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except PressfitError as exc:
            click.echo(f"error: {exc}", err=True)
            sys.exit(2)

    return wrapper


def floats_option(text: str | None, what: str) -> list[float]:
    try:
        return [float(v) for v in text.split(",") if v.strip()] if text else []
    except ValueError:
        raise PressfitError(f"{what} must be comma-separated numbers, got {text!r}") from None
