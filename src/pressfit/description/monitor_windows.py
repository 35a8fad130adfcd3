"""The process monitor's evaluation objects as data: ``windows.json`` (schema in docs/monitor.md).

A vendor-neutral description of what a press-fit process monitor (Kistler maXYmos, burster DIGIFORCE, Promess,
HBM) checks on a force-displacement curve, x = the press displacement (m), y = the press force (N), SI units in
the file. Four kinds of element, each named (the verdict names the element that failed):

* ``window``: a box ``x_min_m <= x <= x_max_m``, ``y_min_n <= y <= y_max_n`` the curve must pass, entering
  through its ``entry`` side and leaving through its ``exit`` side (``left``, ``right``, ``top``, ``bottom``);
  ``exit = "none"`` asks the curve to end inside the box (a block window at the end of the stroke);
* ``threshold``: a force level ``force_n`` over ``x_min_m <= x <= x_max_m`` the curve ``must_cross`` (reach)
  or ``must_not_cross`` (never exceed);
* ``envelope``: lower and upper force bounds (N) as functions of the displacement (m), piecewise linear between
  the points ``displacement_m`` (strictly increasing): the curve must stay between them over that span;
* ``max_force``: the force the curve must never exceed anywhere.

The file may carry the tolerance band it was derived from (``band``: its grid and quantile curves, for the
plot) and a free ``source`` table (what produced it: the study, its samples, the derivation's parameters).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import Field, ValidationError, model_validator

from pressfit.description.machine import Finite, StrictModel, validation_error
from pressfit.errors import ModelFileError

SCHEMA_VERSION = 1
MAX_WINDOWS_BYTES = 10_000_000  # a windows file is a few kB (an envelope of a few hundred points)
Side = Literal["left", "right", "top", "bottom"]


class Window(StrictModel):
    """A box (m, N) the curve passes through ``entry`` and leaves through ``exit`` (module doc)."""

    type: Literal["window"] = "window"
    name: str
    x_min_m: Finite
    x_max_m: Finite
    y_min_n: Finite
    y_max_n: Finite
    entry: Side
    exit: Side | Literal["none"]

    @model_validator(mode="after")
    def _box(self) -> Window:
        if not (self.x_min_m < self.x_max_m and self.y_min_n < self.y_max_n):
            raise ValueError("a window needs x_min_m < x_max_m and y_min_n < y_max_n")
        return self


class Threshold(StrictModel):
    """A force level (N) over a displacement range (m) the curve must reach (``must_cross``) or must never
    exceed (``must_not_cross``)."""

    type: Literal["threshold"] = "threshold"
    name: str
    force_n: Finite
    x_min_m: Finite
    x_max_m: Finite
    mode: Literal["must_cross", "must_not_cross"]

    @model_validator(mode="after")
    def _range(self) -> Threshold:
        if not self.x_min_m < self.x_max_m:
            raise ValueError("a threshold needs x_min_m < x_max_m")
        return self


class Envelope(StrictModel):
    """Lower and upper force bounds (N) at the displacements ``displacement_m`` (m, strictly increasing, at
    least 2), linear in between."""

    type: Literal["envelope"] = "envelope"
    name: str
    displacement_m: Annotated[list[Finite], Field(min_length=2)]
    lower_force_n: list[Finite]
    upper_force_n: list[Finite]

    @model_validator(mode="after")
    def _curves(self) -> Envelope:
        n = len(self.displacement_m)
        if len(self.lower_force_n) != n or len(self.upper_force_n) != n:
            raise ValueError(f"lower_force_n and upper_force_n need one value per displacement ({n})")
        if any(b <= a for a, b in zip(self.displacement_m, self.displacement_m[1:], strict=False)):
            raise ValueError("displacement_m must be strictly increasing")
        if any(lo > hi for lo, hi in zip(self.lower_force_n, self.upper_force_n, strict=True)):
            raise ValueError("lower_force_n must not exceed upper_force_n")
        return self


class MaxForce(StrictModel):
    """The force (N) the curve must never exceed."""

    type: Literal["max_force"] = "max_force"
    name: str
    force_n: Finite


Element = Annotated[Window | Threshold | Envelope | MaxForce, Field(discriminator="type")]


class Band(StrictModel):
    """A tolerance band for the plot: force quantiles (N) ``force_n[k]`` at ``quantiles[k]`` over ``grid_m``."""

    grid_m: Annotated[list[Finite], Field(min_length=2)]
    quantiles: Annotated[list[Finite], Field(min_length=1)]
    force_n: list[list[float]]  # NaN (JSON null) where too few curves reach the displacement
    samples: Annotated[int, Field(ge=1)]

    @model_validator(mode="after")
    def _shape(self) -> Band:
        if len(self.force_n) != len(self.quantiles) or any(len(r) != len(self.grid_m) for r in self.force_n):
            raise ValueError("force_n needs one row per quantile, one value per grid point")
        return self


class Windows(StrictModel):
    """A ``windows.json``: the evaluation objects, checked in file order."""

    schema_version: Literal[1]
    name: str = ""
    x_quantity: Literal["displacement_m"] = "displacement_m"
    y_quantity: Literal["force_n"] = "force_n"
    elements: Annotated[list[Element], Field(min_length=1)]
    band: Band | None = None
    source: dict[str, Any] = {}

    @model_validator(mode="after")
    def _names(self) -> Windows:
        names = [e.name for e in self.elements]
        dup = next((n for n in names if names.count(n) > 1), None)
        if dup is not None:
            raise ValueError(f"element name {dup!r} is used twice: each element needs its own name")
        return self


def _nulls_to_nan(data: Any) -> Any:
    """The band's JSON nulls (a quantile undefined where no curve reaches) back to NaN."""
    band = data.get("band") if isinstance(data, dict) else None
    if isinstance(band, dict) and isinstance(band.get("force_n"), list):
        band = {**band, "force_n": [[math.nan if v is None else v for v in row] if isinstance(row, list) else row
                                    for row in band["force_n"]]}
        return {**data, "band": band}
    return data


def load_windows(path: Path | str) -> Windows:
    """Read and validate a ``windows.json``; ModelFileError names the file and the key at fault."""
    path = Path(path)
    try:
        if not path.is_file():
            raise ModelFileError(path, "<file>", "file does not exist (or is not a regular file)")
        if path.stat().st_size >= MAX_WINDOWS_BYTES:
            raise ModelFileError(path, "<file>", f"a windows file of less than {MAX_WINDOWS_BYTES} bytes")
        data = json.loads(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError:
        raise ModelFileError(path, "<file>", "a UTF-8 JSON file") from None
    except json.JSONDecodeError as exc:
        raise ModelFileError(path, f"<line {exc.lineno}>", f"valid JSON ({exc.msg})") from None
    except OSError as exc:
        raise ModelFileError(path, "<file>", f"a readable file ({exc.strerror})") from None
    if not isinstance(data, dict):
        raise ModelFileError(path, "<top level>", "a JSON object with schema_version and elements")
    if data.get("schema_version") != SCHEMA_VERSION:
        raise ModelFileError(path, "schema_version", f"{SCHEMA_VERSION} (this pressfit reads windows files of "
                             f"schema version {SCHEMA_VERSION}; got {data.get('schema_version')!r})")
    try:
        return Windows.model_validate(_nulls_to_nan(data))
    except ValidationError as exc:
        raise validation_error(path, exc) from None
